//! Fuzz target: the gate file of `pgt compare --gate` (TOML and validation) must give a gate
//! or an error, never panic, loop or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::metrics::gate::Gate;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = Gate::parse(text, std::path::Path::new("fuzz-gate.toml"));
});
