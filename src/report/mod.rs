//! Reports of a comparison (docs/design.md §5): colour maps and heatmaps with colour bars, the
//! self-contained HTML page with its interactive viewer (`viewer.rs`, `viewer.js`), SVG colour
//! bars and plots of swept parameters, and the page of a sweep.

pub mod attribution;
pub mod colorbar;
pub mod colormap;
mod colormap_data;
pub mod compared;
pub mod heatmap;

pub use colormap::{ColorMap, Scale};
pub use compared::Compared;
pub use heatmap::{heatmap, Srgb8Image};
pub mod html;
pub mod summary;

pub use html::{write_report, ReportInputs, ReportOptions};
pub use summary::Summary;
pub mod plot;
pub mod sequence_compare;
pub mod sequence_page;
pub mod sequence_probe;
pub mod sweep_page;
pub mod text;
pub mod viewer;
