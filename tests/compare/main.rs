//! The comparison (docs/design.md §5, §10): SSIM and FLIP against published vectors, properties of
//! the metrics, `pgt compare` and `pgt sweep` end to end, and sequences of frames.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod cli;
mod flip;
mod properties;
mod sequence_frames;
mod ssim;
mod sweep;
