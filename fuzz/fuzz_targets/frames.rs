//! Fuzz target: the frame sources of the particle formats with frames (PDB models, XYZ frames,
//! MMPLD frames, mmCIF models) must return Ok or Err on any bytes, never panic, loop or
//! allocate without bound. The first byte picks the format; every frame found (at most 64) is
//! read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::frames::ByteSource;
use pgt::formats::{Format, IncludeSpec};

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else {
        return;
    };
    let name = ["pdb", "xyz", "mmpld", "mmcif"][usize::from(pick) % 4];
    let format = Format::named(name).expect("a format of the table");
    let path = std::path::PathBuf::from(format!("fuzz.{name}"));
    let spec = IncludeSpec::bare(&path);
    let Some(open) = format.frames else {
        return;
    };
    if let Ok(frames) = open(&spec, ByteSource::from_bytes(&path, bytes.to_vec())) {
        for k in 0..frames.info().count.min(64) {
            let _ = frames.read_frame(k);
        }
    }
});
