//! Fuzz target: the GRO reader (a particle file and a topology) must return Ok or Err on any
//! bytes, never panic, loop or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::formats::{load_bytes, Format, IncludeSpec};

fuzz_target!(|data: &[u8]| {
    let format = Format::named("gro").expect("a format of the table");
    let spec = IncludeSpec::bare(std::path::Path::new("fuzz.gro"));
    let _ = load_bytes(&spec, format, data);
});
