//! Fuzz target: the COLMAP model readers (text and binary) must return Ok or Err on any bytes,
//! never panic, loop or allocate without bound. The input is split in two at its first byte's
//! share: cameras, then images; each half is read as binary and, when it is UTF-8, as text.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::cameras::colmap;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&split, rest)) = data.split_first() else {
        return;
    };
    let at = (split as usize * rest.len() / 255).min(rest.len());
    let (cameras, images) = rest.split_at(at);
    let (c, i) = (Path::new("cameras.bin"), Path::new("images.bin"));
    let _ = colmap::parse_binary(cameras, c, images, i);
    if let (Ok(ct), Ok(it)) = (std::str::from_utf8(cameras), std::str::from_utf8(images)) {
        let _ = colmap::parse_text(ct, Path::new("cameras.txt"), it, Path::new("images.txt"));
    }
});
