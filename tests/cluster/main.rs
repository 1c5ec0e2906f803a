//! Renders in parts and their merge (docs/design.md §7): bit-identical merges, interrupted runs
//! that leave nothing behind, and a real single-node Slurm.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod merge;
mod signals;
mod slurm;
