//! Fuzz target: the 3DGS `cameras.json` reader must return Ok or Err on any text, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::cameras::cameras_json;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = cameras_json::parse(text, Path::new("cameras.json"));
    }
});
