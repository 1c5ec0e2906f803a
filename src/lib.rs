//! pgt — particle ground truth.
//!
//! Data flows one way (docs/design.md, STYLE.md): scene → geometry → optics → reference | approx →
//! metrics → report, with the command line on top. This file holds only module lines and
//! re-exports.

pub mod approx;
pub mod cli;
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

pub use error::{PgtError, Result};
pub use scene::{Scene, SceneLoadOptions};
