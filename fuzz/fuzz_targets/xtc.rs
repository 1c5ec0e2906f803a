//! Fuzz target: the xtc trajectory reader must return Ok or Err on any bytes, never panic, loop or
//! allocate without bound; every frame it announces is read (at most 64).
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::frames::ByteSource;

fuzz_target!(|data: &[u8]| {
    let source = ByteSource::from_bytes(std::path::Path::new("fuzz.xtc"), data.to_vec());
    if let Ok(t) = pgt::formats::xtc::open(source) {
        let mut positions = Vec::new();
        for k in 0..t.frames().min(64) {
            let _ = t.read_positions(k, &mut positions);
        }
    }
});
