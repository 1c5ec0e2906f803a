//! Fuzz target: nerfstudio's `dataparser_transforms.json` reader must return Ok or Err on any
//! text, never panic, and a transform it accepts must map a camera without panicking.
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use pgt::formats::cameras::transforms::Dataparser;
use pgt::geometry::Camera;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(d) = Dataparser::parse(text, Path::new("dataparser_transforms.json")) {
            let camera = Camera::new(DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO, DVec3::Y, 40.0, 8, 6);
            let _ = d.apply(&camera);
        }
    }
});
