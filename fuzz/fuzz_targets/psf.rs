//! Fuzz target: the PSF topology reader must return Ok or Err on any bytes, never panic, loop or
//! allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = pgt::formats::psf::read_atoms(std::path::Path::new("fuzz.psf"), data);
});
