//! The GPU approximations (docs/design.md §4) on whatever adapter wgpu finds (lavapipe in CI): the
//! CPU–GPU contract and layouts, the methods against exact answers, bands, buffer limits,
//! `pgt approx`, and the rasterising example.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod bands;
mod cli;
mod contract;
mod ellipsoids;
mod gaussians;
mod intrinsics;
mod layout;
mod limits;
mod methods;
mod raster;
mod reference;
mod reference_frames;
mod reference_gaussian;
mod sorted_blend;
mod view_color;
