//! The `pgt` command line end to end: `render`, `bench`, the first hour of a new user (outputs
//! checked before the work, closed pipes, help texts), and bad gate, experiment and shader files.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod bad_input_files;
mod bench;
mod first_hour;
mod render;
