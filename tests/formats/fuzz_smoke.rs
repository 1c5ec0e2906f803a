//! An in-process random-mutation smoke test of every parser (the quick stand-in for the
//! `fuzz/` targets): real files (or small hand-made ones) with bytes flipped, inserted, deleted,
//! duplicated and truncated, deterministically (SplitMix64). Every result must be Ok or an error
//! that names the file; a panic fails the test with the seed and iteration.

use crate::support::*;
use pgt::formats::random::SplitMix64;
use pgt::formats::{load_bytes, Format, IncludeSpec};
use std::path::Path;

/// Mutations per input (kept moderate: the machine is shared).
const ROUNDS: usize = 1000;

const TOKENS: &[&[u8]] = &[
    b"{",
    b"}",
    b"[",
    b"]",
    b"DEF A ",
    b"USE A ",
    b"PROTO P [ field SFFloat r 1 ] { Shape { geometry Sphere { radius IS r } } }",
    b"P { r 2 }",
    b"IS r",
    b"NULL",
    b"nan",
    b"-1e400",
    b"\"",
    b"#",
    b"\n",
    b"loop_\n",
    b";",
    b"'",
    b"MODEL 2\n",
    b"ATOM  ",
    b"\0\0\0\0\xff\xff\xff\xff",
    b"0x",
    b"Transform { scale 0 0 0 children [",
    b"1,2,3,4,5,6,7\n",
];

fn mutate(rng: &mut SplitMix64, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    let n = 1 + (rng.next_u64() % 8) as usize;
    for _ in 0..n {
        let len = b.len().max(1);
        let at = (rng.next_u64() as usize) % len;
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

fn smoke(name: &str, format: &str, input: &[u8], seed: u64) {
    let format = Format::named(format).expect("a format of the table");
    let spec = IncludeSpec::bare(Path::new(name));
    let mut rng = SplitMix64::new(seed);
    let mut errors = 0;
    for i in 0..ROUNDS {
        let m = mutate(&mut rng, input);
        // SMOKE_TRACE=1: print each iteration and keep its input, to find a hang or an abort.
        if std::env::var("SMOKE_TRACE").is_ok() {
            eprintln!("{name} {i}");
            std::fs::write(std::env::temp_dir().join("pgt_smoke_last"), &m).ok();
        }
        let r = std::panic::catch_unwind(|| load_bytes(&spec, format, &m));
        match r {
            Err(_) => panic!("{name}: panic at iteration {i} (seed {seed})"),
            Ok(Err(e)) => {
                errors += 1;
                assert!(e.to_string().contains(name), "{e}");
            }
            Ok(Ok(_)) => {}
        }
    }
    println!("{name}: {ROUNDS} mutations, {errors} rejected with an error, no panic");
}

fn bytes_or(rel: &str, fallback: &[u8]) -> Vec<u8> {
    shared(rel)
        .and_then(|p| std::fs::read(p).ok())
        .unwrap_or_else(|| fallback.to_vec())
}

#[test]
fn pdb_and_mmcif_survive_mutation() {
    let pdb = bytes_or(
        "pdb/1rx1.pdb",
        b"ATOM      1  N   ALA A   2      63.130 -67.331 -18.137  1.00 21.97           N  \n",
    );
    // The first 700 lines keep each mutation cheap.
    let head: Vec<u8> = pdb
        .split(|&b| b == b'\n')
        .take(700)
        .collect::<Vec<_>>()
        .join(&b'\n');
    smoke("m.pdb", "pdb", &head, 1);
    let cif = bytes_or(
        "pdb/3SN6.cif",
        b"data_x\nloop_\n_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n1 2 3\n",
    );
    let head: Vec<u8> = cif
        .split(|&b| b == b'\n')
        .take(2700)
        .collect::<Vec<_>>()
        .join(&b'\n');
    smoke("m.cif", "mmcif", &head, 2);
}

#[test]
fn vrml_survives_mutation() {
    for (k, rel) in [
        "vrml/castle_proto_nodes.wrl",
        "vrml/castle_proto_ultra_simple.wrl",
        "vrml/drawxtl_be4oteo6.wrl",
    ]
    .iter()
    .enumerate()
    {
        let b = bytes_or(
            rel,
            b"#VRML V2.0 utf8\nTransform { children Shape { geometry Sphere { } } }\n",
        );
        smoke("m.wrl", "vrml", &b, 10 + k as u64);
    }
}

#[test]
fn mmpld_survives_mutation() {
    for (k, rel) in [
        "mmpld/test_xyzr_float_rgba_byte.mmpld",
        "mmpld/test_xyz_double_int_double.mmpld",
        "mmpld/test_xyz_double_rgba_short.mmpld",
        "mmpld/testspheres_old_v100.mmpld",
        "mmpld/part_rnk000000_v103.mmpld",
    ]
    .iter()
    .enumerate()
    {
        let Some(p) = shared(rel) else { continue };
        let b = std::fs::read(p).expect("read");
        smoke("m.mmpld", "mmpld", &b, 20 + k as u64);
    }
}

#[test]
fn xyz_and_csv_survive_mutation() {
    smoke(
        "m.xyz",
        "xyz",
        b"3\nwater\nO 0 0 0\nH 1 0 0\nH 0 1 0\n2\nf2\nC 1 1 1\nN 2 2 2\n",
        30,
    );
    smoke(
        "m.csv",
        "csv",
        b"x,y,z,r,r,g,b,opacity\n1,2,3,0.5,1,0,0,0.5\n4,5,6,1,0,1,0,1\n",
        31,
    );
}

#[test]
fn local_copies_load() {
    // Files copied into tests/data (licences in tests/data/README.md), so CI without
    // ../shared still reads real files. Counts as in formats_pdb.rs / SOURCES.md.
    assert_eq!(load(&local("1rx1.pdb")).records.len(), 1435);
    assert_eq!(load(&local("3al1.pdb")).records.len(), 491);
    assert_eq!(
        load(&local("test_xyzr_float_rgba_byte.mmpld"))
            .records
            .len(),
        4
    );
}
