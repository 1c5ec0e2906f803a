//! The `pgt` command line end to end: `render`, `bench`, `camera`, `export`, and bad input files of
//! every kind (exit 2, the file named, no output).
//!
//! One module per topic; `support` is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod bad_input_files;
mod bench;
mod camera_projection;
mod export_roundtrip;
mod render;
