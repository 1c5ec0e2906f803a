//! pgt — particle ground truth.
//!
//! Data flows one way (docs/design.md, tests/architecture.rs): scene → geometry → optics →
//! reference | approx → metrics → report. The command line (`src/cli/`, a module of the `pgt`
//! binary) and the Python package (`python/`) sit on top and only translate. This file holds
//! only module lines and re-exports.

pub mod approx;
pub mod bench;
pub mod color;
pub mod error;
pub mod formats;
pub mod geometry;
pub mod image_io;
pub mod metrics;
pub mod optics;
pub mod parts;
pub mod reference;
pub mod report;
pub mod scene;
pub mod sequence;
pub mod signals;
pub mod sweep;

pub use error::{error_message, PgtError, Result};
pub use scene::{Scene, SceneLoadOptions};
