//! End to end through the built binary: `pgt info`, `pgt gen random`, bare-file rendering, and
//! bad input of every format (exit code 2, the file named, no output written).

use crate::support::*;
use std::path::Path;
use std::process::{Command, Output};

fn pgt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .output()
        .expect("run pgt")
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

#[test]
fn info_json_of_a_pdb_file() {
    let p = shared_or_skip!("pdb/1uun_opm_oriented.pdb");
    let v = json(&pgt(&["info", p.to_str().expect("utf8"), "--json"]));
    assert_eq!(v["particles"], 11032);
    assert_eq!(v["format"], "pdb");
    // 1UUN has C, N, O, S only (`cut -c77-78 | sort -u`): radii 1.52 (O) .. 1.80 (S).
    assert_eq!(v["radius"]["min"], 1.52);
    assert_eq!(v["radius"]["max"], 1.80);
    // Bounds: the extreme x of the atoms ± their radii, from the text.
    let xs: Vec<(f64, f64)> = lines_where(&p, |l| l.starts_with("ATOM  "))
        .iter()
        .map(|(_, t)| {
            let r = match t[76..78].trim() {
                "C" => 1.70,
                "N" => 1.55,
                "O" => 1.52,
                _ => 1.80,
            };
            (t[30..38].trim().parse::<f64>().expect("x"), r)
        })
        .collect();
    let min_x = xs.iter().map(|(x, r)| x - r).fold(f64::INFINITY, f64::min);
    let got = v["bounds"]["min"][0].as_f64().expect("number");
    assert!((got - min_x).abs() < 1e-9, "{got} vs {min_x}");
    assert_eq!(v["colors"]["distinct"], 4);
    // SOURCES.md: chains A–H × 1379 atoms, no MODEL records.
    let chains = v["details"]["chains"].as_object().expect("chains");
    assert_eq!(chains.len(), 8);
    assert!(chains.values().all(|n| n == 1379));
    assert_eq!(v["details"]["models"], serde_json::json!([1]));
}

#[test]
fn info_json_of_an_mmpld_file() {
    let p = shared_or_skip!("mmpld/testspheres_old_v100.mmpld");
    let v = json(&pgt(&["info", p.to_str().expect("utf8"), "--json"]));
    assert_eq!(v["particles"], 15);
    assert_eq!(v["details"]["version"], "1.0");
    assert_eq!(v["details"]["frames"], 100);
}

#[test]
fn info_of_a_scene_with_an_include() {
    let p = shared_or_skip!("pdb/1uun_opm_oriented.pdb");
    let dir = tempfile::tempdir().expect("tmp");
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "[[include]]\npath = {:?}\nchains = [\"A\", \"B\"]\ncolor_by = \"chain\"\nradius_scale = 0.5\n\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
            p.to_str().expect("utf8")
        ),
    )
    .expect("write");
    let v = json(&pgt(&["info", scene.to_str().expect("utf8"), "--json"]));
    assert_eq!(v["format"], "scene");
    assert_eq!(v["particles"], 2758 + 1);
    assert_eq!(v["radius"]["min"], 0.76);
    assert_eq!(v["radius"]["max"], 1.0);
    // Two chain colours plus the inline particle's default white.
    assert_eq!(v["colors"]["distinct"], 3);
}

#[test]
fn gen_random_is_deterministic_and_readable() {
    let dir = tempfile::tempdir().expect("tmp");
    let a = dir.path().join("a.csv");
    let b = dir.path().join("b.csv");
    let c = dir.path().join("c.csv");
    for (f, seed) in [(&a, "5"), (&b, "5"), (&c, "6")] {
        let out = pgt(&[
            "gen",
            "random",
            "--count",
            "1000",
            "--seed",
            seed,
            "--box",
            "0,0,0,10,20,30",
            "--radius",
            "0.1..0.2",
            "-o",
            f.to_str().expect("utf8"),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let (ta, tb, tc) = (
        std::fs::read(&a).expect("a"),
        std::fs::read(&b).expect("b"),
        std::fs::read(&c).expect("c"),
    );
    assert_eq!(ta, tb);
    assert_ne!(ta, tc);
    let v = json(&pgt(&["info", a.to_str().expect("utf8"), "--json"]));
    assert_eq!(v["particles"], 1000);
    let (lo, hi) = (&v["bounds"]["min"], &v["bounds"]["max"]);
    assert!(lo[0].as_f64().expect("n") >= -0.2 && hi[2].as_f64().expect("n") <= 30.2);
    assert!(
        v["radius"]["min"].as_f64().expect("n") >= 0.1
            && v["radius"]["max"].as_f64().expect("n") <= 0.2
    );
    // The default is the thesis's count.
    let d = dir.path().join("d.csv");
    assert!(pgt(&["gen", "random", "-o", d.to_str().expect("utf8")])
        .status
        .success());
    assert_eq!(
        json(&pgt(&["info", d.to_str().expect("utf8"), "--json"]))["particles"],
        73642
    );
    // Bad options: exit 2, nothing written.
    let e = dir.path().join("e.csv");
    for bad in [
        ["--radius", "2..1"],
        ["--count", "1000000000000"],
        ["--box", "1,2,3"],
    ] {
        let out = pgt(&[
            "gen",
            "random",
            bad[0],
            bad[1],
            "-o",
            e.to_str().expect("utf8"),
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
        assert!(!e.exists(), "{bad:?}");
    }
}

#[test]
fn bare_files_render() {
    let dir = tempfile::tempdir().expect("tmp");
    for rel in [
        "pdb/1rx1.pdb",
        "vrml/castle_proto_ultra_simple.wrl",
        "mmpld/test_xyzr_float_rgba_byte.mmpld",
    ] {
        let Some(p) = shared(rel) else { continue };
        let out_png = dir.path().join("o.png");
        let out = pgt(&[
            "render",
            p.to_str().expect("utf8"),
            "-o",
            out_png.to_str().expect("utf8"),
            "--mode",
            "opaque",
            "--size",
            "48x32",
        ]);
        assert!(
            out.status.success(),
            "{rel}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out_png.exists(), "{rel}");
        std::fs::remove_file(&out_png).expect("rm");
    }
}

/// Writes `bytes` as `name` and checks that `render` and `info` fail with exit code 2, name the
/// file and `want`, and write nothing.
fn rejects(dir: &Path, name: &str, bytes: &[u8], want: &str) {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write");
    let png = dir.join(format!("{name}.png"));
    let ps = p.to_str().expect("utf8");
    for args in [
        vec![
            "render",
            ps,
            "-o",
            png.to_str().expect("utf8"),
            "--mode",
            "opaque",
        ],
        vec!["info", ps],
    ] {
        let out = pgt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(name) && err.contains(want), "{name}: {err}");
        assert!(!png.exists(), "{name}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}

#[test]
fn bad_input_exits_2_names_the_file_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let atom = "ATOM      1  N   ALA A   2      63.130 -67.331 -18.137  1.00 21.97           N  \n";
    rejects(
        d,
        "trunc.pdb",
        format!("{atom}{}", &atom[..35]).as_bytes(),
        "trunc.pdb:2",
    );
    rejects(
        d,
        "nan.pdb",
        atom.replace("63.130", "   nan").as_bytes(),
        "not finite",
    );
    rejects(
        d,
        "bad.cif",
        b"data_x\nloop_\n_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n1 2 x\n",
        "bad.cif:6",
    );
    rejects(d, "magic.mmpld", b"MMPLX\0\x66\0\x01\0\0\0", "magic");
    let mut big = b"MMPLD\0".to_vec();
    big.extend_from_slice(&102u16.to_le_bytes());
    big.extend_from_slice(&u32::MAX.to_le_bytes());
    big.extend_from_slice(&[0u8; 64]);
    rejects(d, "count.mmpld", &big, "frames");
    rejects(
        d,
        "brace.wrl",
        b"#VRML V2.0 utf8\nGroup { children [ Shape { geometry Sphere { } } ]\n",
        "expected '}'",
    );
    rejects(
        d,
        "proto.wrl",
        b"#VRML V2.0 utf8\nNoSuchProto { }\n",
        "unknown node type",
    );
    rejects(
        d,
        "self.wrl",
        b"#VRML V2.0 utf8\nPROTO A [] { A { } }\n",
        "instantiates itself",
    );
    rejects(d, "use.wrl", b"#VRML V2.0 utf8\nUSE X\n", "use.wrl:2");
    rejects(d, "short.xyz", b"4\ncomment\nC 0 0 0\n", "short.xyz:1");
    rejects(d, "hdr.csv", b"1,2,3\n", "header");
    rejects(d, "radius.csv", b"x,y,z,radius\n0,0,0,-1\n", "radius.csv:2");
    rejects(d, "thing.dat", b"hello", "unsupported particle file type");
    rejects(
        d,
        "opacity.csv",
        b"x,y,z,opacity\n0,0,0,1.5\n",
        "opacity.csv:2",
    );
    rejects(d, "transp.wrl", b"#VRML V2.0 utf8\nShape { appearance Appearance { material Material { transparency -1 } } geometry Sphere { } }\n", "transp.wrl:2");
}

#[test]
fn scene_include_can_force_the_format() {
    let dir = tempfile::tempdir().expect("tmp");
    std::fs::write(
        dir.path().join("atoms.txt"),
        "ATOM      1  N   ALA A   2      63.130 -67.331 -18.137  1.00 21.97           N  \n",
    )
    .expect("write");
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "[[include]]\npath = \"atoms.txt\"\nformat = \"pdb\"\n",
    )
    .expect("write");
    let v = json(&pgt(&["info", scene.to_str().expect("utf8"), "--json"]));
    assert_eq!(v["particles"], 1);
    assert_eq!(v["radius"]["min"], 1.55);
    // A misspelt format is an error naming the scene file.
    std::fs::write(
        &scene,
        "[[include]]\npath = \"atoms.txt\"\nformat = \"pbd\"\n",
    )
    .expect("write");
    let out = pgt(&["info", scene.to_str().expect("utf8")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("s.toml"));
}

/// Runs `render`, `approx` and `info` on `input` and checks that each exits 2, that stderr
/// contains every one of `want` (the file and the reason), and that no output was written.
fn every_command_refuses(input: &Path, want: &[&str]) {
    let out_png = input.with_extension("out.png");
    let (ps, os) = (
        input.to_str().expect("utf8"),
        out_png.to_str().expect("utf8"),
    );
    for args in [
        vec!["render", ps, "-o", os, "--mode", "opaque", "--size", "8x8"],
        vec!["approx", ps, "-o", os, "--size", "8x8"],
        vec!["info", ps],
        vec!["info", ps, "--json"],
    ] {
        let out = pgt(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for w in want {
            assert!(err.contains(w), "{args:?}: wanted '{w}' in: {err}");
        }
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}: printed {:?}", out.stdout);
        assert!(!out_png.exists(), "{args:?}");
    }
}

/// Issue 13 item 1: a particle file that holds no particles (a truncated download, a wrong
/// path) is an error naming the file in every command, for every format.
#[test]
fn a_particle_file_without_particles_is_an_error() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    // Bytes ≥ 0x80 and newlines: no ATOM/HETATM record can start a line.
    let binary: Vec<u8> = (0..4096u32)
        .map(|i| {
            if i % 97 == 0 {
                b'\n'
            } else {
                0x80 | (i * 37 % 128) as u8
            }
        })
        .collect();
    let mut no_frames = b"MMPLD\0".to_vec();
    no_frames.extend_from_slice(&102u16.to_le_bytes());
    no_frames.extend_from_slice(&0u32.to_le_bytes());
    no_frames.extend_from_slice(&[0u8; 48]);
    no_frames.extend_from_slice(&68u64.to_le_bytes());
    let cases: [(&str, &[u8], &str); 8] = [
        ("zero.pdb", b"", "empty (0 bytes)"),
        ("binary.pdb", &binary, "no ATOM or HETATM records"),
        ("header.csv", b"x,y,z,radius\n", "no data rows"),
        ("comments.csv", b"# nothing\n\n", "no data rows"),
        ("nothing.wrl", b"#VRML V2.0 utf8\nGroup { }\n", "no Sphere"),
        ("zero.xyz", b"0\nno atoms\n", "no atoms"),
        (
            "noatoms.cif",
            b"data_x\n_cell.length_a 1.0\n",
            "no _atom_site rows",
        ),
        ("noframes.mmpld", &no_frames, "no frames"),
    ];
    for (name, bytes, reason) in cases {
        let p = d.join(name);
        std::fs::write(&p, bytes).expect("write");
        every_command_refuses(&p, &[name, "holds no particles", reason]);
    }
}

/// Issue 13 item 1: an include whose filters remove every atom names the file and the filter;
/// a scene without any particles stays valid (background and a warning: cli_render).
#[test]
fn an_include_emptied_by_its_filters_names_the_filter() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let water = "HETATM    1  O   HOH A   1      10.000  10.000  10.000  1.00  0.00           O  \n\
                 HETATM    2  H1  HOH A   1      10.500  10.000  10.000  1.00  0.00           H  \n\
                 HETATM    3  O   HOH B   2      12.000  10.000  10.000  1.00  0.00           O  \n";
    std::fs::write(d.join("water.pdb"), water).expect("write");
    let hydrogens =
        "ATOM      1  H   ALA A   1       1.000   2.000   3.000  1.00  0.00           H  \n";
    std::fs::write(d.join("hydrogens.pdb"), hydrogens).expect("write");
    for (scene, include, filter) in [
        (
            "water.toml",
            "path = \"water.pdb\"\nskip_water = true",
            "`skip_water = true`",
        ),
        (
            "chains_then_water.toml",
            "path = \"water.pdb\"\nchains = [\"B\"]\nskip_water = true",
            "`chains = [\"B\"]` keeps 1, and `skip_water = true` removes all",
        ),
        (
            "nochains.toml",
            "path = \"water.pdb\"\nchains = []",
            "`chains = []`",
        ),
        (
            "hydrogen.toml",
            "path = \"hydrogens.pdb\"\nskip_hydrogen = true",
            "`skip_hydrogen = true`",
        ),
    ] {
        let p = d.join(scene);
        std::fs::write(&p, format!("[[include]]\n{include}\n")).expect("write");
        let data = if scene == "hydrogen.toml" {
            "hydrogens.pdb"
        } else {
            "water.pdb"
        };
        every_command_refuses(&p, &[data, "holds no particles", filter]);
    }
    std::fs::write(
        d.join("frames.xyz"),
        "1\nfirst\nC 0 0 0\n0\nsecond, empty\n",
    )
    .expect("write");
    let p = d.join("frame.toml");
    std::fs::write(&p, "[[include]]\npath = \"frames.xyz\"\nframe = 1\n").expect("write");
    every_command_refuses(&p, &["frames.xyz", "`frame = 1` holds no particles"]);
    // Without the filter the same include loads.
    let p = d.join("ok.toml");
    std::fs::write(&p, "[[include]]\npath = \"water.pdb\"\n").expect("write");
    assert_eq!(
        json(&pgt(&["info", p.to_str().expect("utf8"), "--json"]))["particles"],
        3
    );
}

#[test]
fn info_says_what_it_reports_of_trajectories_in_help_and_text() {
    let help = pgt(&["info", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    for word in [
        "dcd",
        ".xtc",
        "GRO",
        "PSF",
        "frame count",
        "atoms per frame",
        "time step",
    ] {
        assert!(
            help.contains(word),
            "`pgt info --help` lacks {word}: {help}"
        );
    }
    // The text of a bare DCD ends with its frames line (stdout, after the other lines).
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let out = pgt(&["info", dcd.to_str().expect("utf8")]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let last = text.lines().last().unwrap_or_default();
    assert!(
        text.starts_with(&format!("{} (dcd)", dcd.display()))
            && last.starts_with("frames:    256 (42 atoms per frame, time step "),
        "{text}"
    );
}
