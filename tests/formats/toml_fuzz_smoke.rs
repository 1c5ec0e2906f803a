//! An in-process random-mutation smoke test of the TOML inputs (the quick stand-in for the
//! `fuzz/` targets `scene`, `gate` and `experiment`, as `fuzz_smoke.rs` is for the
//! particle files): the seeds of `fuzz/seeds/` and the examples with bytes flipped, inserted,
//! deleted, duplicated and truncated, deterministically (SplitMix64). Every result must be Ok or
//! an error that names the file; a panic fails the test with the seed and iteration.

use pgt::formats::random::SplitMix64;
use pgt::metrics::gate::Gate;
use pgt::sweep::Experiment;
use pgt::{Scene, SceneLoadOptions};
use std::path::Path;

/// Mutations per input (kept moderate: the machine is shared).
const ROUNDS: usize = 2000;

const TOKENS: &[&[u8]] = &[
    b"[",
    b"]",
    b"[[",
    b"]]",
    b"{",
    b"}",
    b"=",
    b",",
    b"\"",
    b"'",
    b"\n",
    b"#",
    b"nan",
    b"inf",
    b"-inf",
    b"-1",
    b"0",
    b"1e308",
    b"-1e400",
    b"4294967296",
    b"\"all\"",
    b"true",
    b"[]",
    b"[include]\n",
    b"[[particles]]\n",
    b"[[lights]]\n",
    b"[[percentiles]]\n",
    b"[[approximations]]\n",
    b"baseline = { n_exact = \"all\" }\n",
    b"method = \"thesis\"\n",
    b"samples = [1, 2, 3, 4, 5, 6, 7, 8]\n",
    b"width = 0\n",
    b"radius = 0\n",
    b"opacity = 1\n",
    b"kappa = 1e300\n",
    b"fov_y = 180\n",
    b"direction = [0, 0, 0]\n",
    b"\xff",
];

fn mutate(rng: &mut SplitMix64, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    let n = 1 + (rng.next_u64() % 8) as usize;
    for _ in 0..n {
        let at = (rng.next_u64() as usize) % b.len().max(1);
        match rng.next_u64() % 6 {
            0 => {
                if let Some(x) = b.get_mut(at) {
                    *x ^= 1 << (rng.next_u64() % 8);
                }
            }
            1 => {
                if at < b.len() {
                    b.remove(at);
                }
            }
            2 => {
                let t = TOKENS[(rng.next_u64() as usize) % TOKENS.len()];
                let at = at.min(b.len());
                b.splice(at..at, t.iter().copied());
            }
            3 => b.truncate(at),
            4 => {
                let end = (at + (rng.next_u64() % 64) as usize).min(b.len());
                let chunk = b[at.min(end)..end].to_vec();
                b.splice(at.min(b.len())..at.min(b.len()), chunk);
            }
            _ => {
                if let Some(x) = b.get_mut(at) {
                    *x = rng.next_u64() as u8;
                }
            }
        }
    }
    b
}

/// Mutates `seed_file` ROUNDS times and parses each with `parse`, which must not panic and
/// whose errors must name `name`.
fn smoke(name: &str, seed_file: &str, seed: u64, parse: impl Fn(&str) -> Result<(), String>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let input = std::fs::read(root.join(seed_file)).expect("a seed file of the repository");
    let mut rng = SplitMix64::new(seed);
    let mut errors = 0;
    for i in 0..ROUNDS {
        let m = mutate(&mut rng, &input);
        let Ok(text) = std::str::from_utf8(&m) else {
            continue; // the loaders read text; bytes that are not are refused by the reader
        };
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parse(text))) {
            Err(_) => panic!("{seed_file}: panic at iteration {i} (seed {seed}):\n{text}"),
            Ok(Err(e)) => {
                errors += 1;
                assert!(e.contains(name), "{e}");
            }
            Ok(Ok(())) => {}
        }
    }
    println!("{seed_file}: {ROUNDS} mutations, {errors} rejected with an error, no panic");
}

#[test]
fn scenes_survive_mutation() {
    // Includes resolve next to a scene file that does not exist, in the examples folder; an
    // error in an included file names that file instead of the scene, so the check on the
    // name is the folder's (mutated include paths that leave it are not followed).
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let path = folder.join("fuzz-scene.toml");
    let name = folder.to_string_lossy().into_owned();
    let parse = |t: &str| {
        if t.contains("include") && (t.contains("..") || t.contains("\"/")) {
            return Ok(());
        }
        Scene::from_toml_str(t, &path, &SceneLoadOptions::default())
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    for (k, seed) in [
        "examples/shadows.toml",
        "examples/inside.toml",
        "fuzz/seeds/scene/includes.toml",
    ]
    .iter()
    .enumerate()
    {
        smoke(&name, seed, 10 + k as u64, parse);
    }
}

#[test]
fn gate_and_experiment_files_survive_mutation() {
    let gate = |t: &str| {
        Gate::parse(t, Path::new("g.toml"))
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    smoke("g.toml", "fuzz/seeds/gate/full.toml", 20, gate);
    smoke("g.toml", "reports/examples/gate.toml", 21, gate);
    let experiment = |t: &str| {
        Experiment::parse(t, Path::new("e.toml"))
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    smoke("e.toml", "fuzz/seeds/experiment/full.toml", 30, experiment);
    smoke(
        "e.toml",
        "reports/examples/thesis_sweep/experiment.toml",
        31,
        experiment,
    );
}
