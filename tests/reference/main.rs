//! The exact CPU reference (docs/design.md §1–§3, §9, §10): closed forms and limits, the honesty
//! of its error estimate, huge σ, an independent Monte Carlo estimator, ellipsoids, and the
//! camera (its projection as `pgt camera` gives it, orbits and keyframes).
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod camera_projection;
mod dataset_cameras;
mod ellipsoids;
mod error;
mod exact;
mod gaussians;
mod limits;
mod mc;
mod scene_camera_paths;
mod view_color;
