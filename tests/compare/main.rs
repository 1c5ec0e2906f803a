//! The comparison (docs/design.md §5): SSIM and FLIP against published vectors, properties of the
//! metrics, `pgt compare` and `pgt sweep` end to end.
//!
//! One module per topic; `support` is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod cli;
mod flip;
mod former_ssim;
mod properties;
mod ssim;
mod sweep;
