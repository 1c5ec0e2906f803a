//! Fuzz target: a scene TOML goes through the whole load and validation (TOML, defaults, every
//! field check, includes) and must give a scene or an error, never panic, loop or allocate
//! without bound. Includes may only name the small particle files this target writes into its
//! own temporary folder (any other path is skipped), so that a mutated path never reaches
//! `/dev/zero` or a large file of the machine.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pgt::{Scene, SceneLoadOptions};
use std::path::PathBuf;
use std::sync::OnceLock;

/// The particle files includes may name, one per format.
const FILES: &[(&str, &str)] = &[
    (
        "a.pdb",
        "ATOM      1  N   ALA A   1      11.104   6.134  -6.504  1.00  0.00           N\n\
         ATOM      2  CA  ALA B   1      11.639   6.071  -5.147  1.00  0.00           C\n\
         HETATM    3  O   HOH W   2      12.000   7.000  -4.000  1.00  0.00           O\nEND\n",
    ),
    (
        "a.cif",
        "data_x\nloop_\n_atom_site.group_PDB\n_atom_site.type_symbol\n_atom_site.label_asym_id\n\
         _atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n\
         ATOM C A 1.0 2.0 3.0\nATOM O B 2.0 2.0 3.0\n",
    ),
    ("a.csv", "x,y,z,radius,red,green,blue,opacity\n0,0,0,1,1,0,0,0.5\n1,0,0,0.5,0,1,0,0.9\n"),
    (
        "b.csv",
        "x,y,z,sx,sy,sz,qw,qx,qy,qz,opacity\n0,0,0,1,0.1,0.5,1,0,0,0,0.5\n1,0,0,0.5,0.5,0.5,0.3,0.2,0.1,0.9,0.9\n",
    ),
    ("a.xyz", "2\nframe 0\nC 0 0 0\nO 1 0 0\n1\nframe 1\nH 0 1 0\n"),
    (
        "a.wrl",
        "#VRML V2.0 utf8\nTransform { translation 1 0 0 children [ Shape { geometry Sphere { radius 0.5 } } ] }\n",
    ),
];

/// The temporary folder holding [`FILES`]; the fuzzed scene "lives" there.
fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("pgt-fuzz-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        for (name, text) in FILES {
            std::fs::write(dir.join(name), text).expect("a particle file");
        }
        dir
    })
}

/// Whether every `[[include]]` path (as far as TOML can tell) is one of [`FILES`].
fn includes_are_safe(text: &str) -> bool {
    let Ok(table) = text.parse::<toml::Table>() else {
        return true; // the scene loader refuses it before reading any include
    };
    let Some(includes) = table.get("include") else {
        return true;
    };
    let Some(includes) = includes.as_array() else {
        return true; // a type error, refused before any include is read
    };
    includes.iter().all(|inc| match inc.get("path") {
        Some(toml::Value::String(p)) => FILES.iter().any(|(name, _)| name == p),
        Some(_) | None => true,
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if !includes_are_safe(text) {
        return;
    }
    let path = folder().join("fuzz.toml");
    let _ = Scene::from_toml_str(text, &path, &SceneLoadOptions::default());
});
