//! Fuzz target: the experiment file of `pgt sweep` (TOML, every entry against its method's
//! parameters, the expansion into runs, baselines) must give an experiment or an error, never
//! panic, loop or allocate without bound. The scene it names is not read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::sweep::Experiment;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = Experiment::parse(text, std::path::Path::new("fuzz-experiment.toml"));
});
