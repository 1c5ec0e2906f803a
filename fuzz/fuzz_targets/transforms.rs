//! Fuzz target: the NeRF `transforms.json` reader must return Ok or Err on any text, never
//! panic (frames without a size ask for an image size, which here is known for one name only).
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::cameras::transforms;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let size = |p: &Path| p.ends_with("r_0.png").then_some((50, 50));
        let _ = transforms::parse(text, Path::new("transforms.json"), &size);
    }
});
