//! Fuzz target: the 3D Gaussian splatting PLY reader must return Ok or Err on any bytes, never
//! panic, loop or allocate without bound; with the DC colour and with the view-dependent one in
//! the coefficient-major order (the two paths through the SH coefficients), and `pgt info`'s
//! details.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::{load_bytes, Format, IncludeSpec, ShColor, ShOrder};

fuzz_target!(|data: &[u8]| {
    let format = Format::named("ply").expect("a format of the table");
    let path = std::path::Path::new("fuzz.ply");
    let spec = IncludeSpec::bare(path);
    let _ = load_bytes(&spec, format, data);
    let view = IncludeSpec {
        sh: Some(ShColor::View),
        sh_order: Some(ShOrder::CoefficientMajor),
        view_from: Some(glam::DVec3::new(0.5, -1.0, 2.0)),
        extent: Some(2.0),
        ..IncludeSpec::bare(path)
    };
    let _ = load_bytes(&view, format, data);
    if let Some(details) = format.details {
        let _ = details(path, data);
    }
});
