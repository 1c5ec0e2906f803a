//! The `pgt` command line end to end: `render`, `bench`, the first hour of a new user (outputs
//! checked before the work, closed pipes, help texts), bad gate, experiment and shader files, and
//! what a scene that cannot be drawn, or draws black, is told.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod bad_input_files;
mod bench;
mod first_hour;
mod render;
mod scene_messages;
