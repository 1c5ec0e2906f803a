//! Frames in (docs/design.md §10, issue 32): every frame source against independent values.
//!
//! The expected frame counts, atoms per frame, time steps and positions come from
//! `tests/data/trajectory_vectors.json`, made by `scripts/trajectory_vectors.py` with MDAnalysis
//! (DCD, XTC, PSF, GRO, multi-model PDB, multi-frame XYZ) and a plain struct reading (MMPLD).
//! XTC is also checked frame by frame and atom by atom against the `molly` crate's decoder.
//! Positions agree to 1e-4 Å (MDAnalysis holds float32).

use crate::support::shared_or_skip;
use glam::DVec3;
use pgt::formats::frames::{open_frames, FrameSource};
use pgt::formats::topology::open_trajectory_file;
use pgt::formats::IncludeSpec;
use pgt::scene::{Scene, SceneFrames, SceneLoadOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Tolerance on positions, Å.
const TOL: f64 = 1e-4;

fn vectors() -> Value {
    let text =
        std::fs::read_to_string(crate::support::local("trajectory_vectors.json")).expect("vectors");
    serde_json::from_str(&text).expect("json")
}

fn trajectory_spec(topology: &Path, trajectory: &Path) -> IncludeSpec {
    let mut spec = IncludeSpec::bare(topology);
    spec.trajectory = Some(trajectory.to_path_buf());
    spec
}

fn position(v: &Value) -> DVec3 {
    let a: Vec<f64> = v
        .as_array()
        .expect("xyz")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect();
    DVec3::new(a[0], a[1], a[2])
}

/// The frame count, atoms per frame, time step and sampled positions of `source` against the
/// vectors of `key`.
fn check_against(source: &dyn FrameSource, key: &str, check_time: bool) {
    let all = vectors();
    let v = &all[key];
    let info = source.info();
    assert_eq!(
        info.count as u64,
        v["frames"].as_u64().expect("frames"),
        "{key}"
    );
    if let Some(n) = info.atoms_per_frame {
        assert_eq!(n as u64, v["atoms"].as_u64().expect("atoms"), "{key}");
    }
    if check_time {
        let dt = v["time_step_ps"].as_f64().expect("dt");
        let ours = info.time_step_ps.expect("a time step");
        assert!(
            (ours - dt).abs() <= 1e-6 * dt.abs().max(1.0),
            "{key}: dt {ours} vs {dt}"
        );
    }
    for f in v["frame_indices"].as_array().expect("frames") {
        let f = f.as_u64().expect("frame") as usize;
        let frame = source
            .read_frame(f)
            .unwrap_or_else(|e| panic!("{key} frame {f}: {e}"));
        let got: Vec<DVec3> = frame.particles.records.iter().map(|r| r.center).collect();
        assert_sampled_positions(&got, v, f, &format!("{key} frame {f}"));
    }
}

/// `got` (every atom of frame `f`) has the vectors' atom count and, at the sampled atoms, their
/// positions within `TOL`.
fn assert_sampled_positions(got: &[DVec3], v: &Value, f: usize, what: &str) {
    assert_eq!(
        got.len() as u64,
        v["atoms"].as_u64().expect("atoms"),
        "{what}"
    );
    for (k, a) in v["atom_indices"]
        .as_array()
        .expect("atoms")
        .iter()
        .enumerate()
    {
        let a = a.as_u64().expect("index") as usize;
        let expected = position(&v["positions"][f.to_string()][k]);
        assert!(
            (got[a] - expected).abs().max_element() <= TOL,
            "{what} atom {a}: {} vs {expected}",
            got[a]
        );
    }
}

#[test]
fn dcd_with_psf_matches_mdanalysis() {
    let psf = shared_or_skip!("trajectories/ala3.psf");
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let source = open_frames(&trajectory_spec(&psf, &dcd)).expect("opens");
    check_against(source.as_ref(), "ala3_dcd", true);
    let psf = shared_or_skip!("trajectories/tip125_tric_C36.psf");
    let dcd = shared_or_skip!("trajectories/tip125_tric_C36.dcd");
    let source = open_frames(&trajectory_spec(&psf, &dcd)).expect("opens");
    check_against(source.as_ref(), "tip125_dcd", true);
    // The PSF's elements give the radii: TIP3P oxygen 1.52 Å, hydrogens 1.20 Å.
    let f = source.read_frame(0).expect("frame 0");
    let radii: Vec<f64> = f
        .particles
        .records
        .iter()
        .take(3)
        .map(|r| r.radius)
        .collect();
    assert_eq!(radii, [1.52, 1.2, 1.2]);
}

#[test]
fn dcd_with_a_pdb_topology_reads_the_same_frames() {
    let pdb = shared_or_skip!("trajectories/ala3.pdb");
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let source = open_frames(&trajectory_spec(&pdb, &dcd)).expect("opens");
    check_against(source.as_ref(), "ala3_dcd", true);
}

#[test]
fn xtc_with_gro_matches_mdanalysis_in_angstrom() {
    let gro = shared_or_skip!("trajectories/ngl_md.gro");
    let xtc = shared_or_skip!("trajectories/ngl_md.xtc");
    let source = open_frames(&trajectory_spec(&gro, &xtc)).expect("opens");
    check_against(source.as_ref(), "ngl_md_xtc", true);
    // Units: GRO positions are the file's nm columns times 10 (read here from the text), and
    // the GRO and the XTC's frame 0 (a later snapshot of the same system) then lie within a few
    // Å of each other, not a factor of 10 apart.
    let text = std::fs::read_to_string(&gro).expect("gro");
    let (topology, _) = pgt::formats::gro::read_atoms(&gro, text.as_bytes()).expect("gro atoms");
    let frame = source.read_frame(0).expect("frame 0");
    for k in [0usize, 5000, 17410] {
        let line = text.lines().nth(2 + k).expect("atom line");
        let nm: Vec<f64> = (0..3)
            .map(|c| line[20 + 8 * c..28 + 8 * c].trim().parse().expect("number"))
            .collect();
        let expected = DVec3::new(nm[0], nm[1], nm[2]) * 10.0;
        assert!(
            (topology[k].position - expected).abs().max_element() < 1e-12,
            "atom {k}"
        );
    }
    // Atom 0 is a protein atom (waters diffuse and wrap around the box).
    let d = (topology[0].position - frame.particles.records[0].center).length();
    assert!(
        d < 5.0,
        "GRO {} vs XTC {}",
        topology[0].position,
        frame.particles.records[0].center
    );
}

#[test]
fn xtc_decoder_agrees_with_molly_on_every_frame_and_atom() {
    let xtc = shared_or_skip!("trajectories/ngl_md.xtc");
    let ours = open_trajectory_file(&xtc).expect("opens");
    let mut reader = molly::XTCReader::open(&xtc).expect("molly opens");
    let mut frame = molly::Frame::default();
    let mut positions = Vec::new();
    for k in 0..ours.frames() {
        reader.read_frame(&mut frame).expect("molly reads");
        let time = ours.read_positions(k, &mut positions).expect("reads");
        assert_eq!(time, Some(f64::from(frame.time)), "frame {k}");
        assert_eq!(positions.len(), frame.natoms(), "frame {k}");
        for (a, (p, m)) in positions.iter().zip(frame.coords()).enumerate() {
            let expected = DVec3::new(f64::from(m[0]), f64::from(m[1]), f64::from(m[2])) * 10.0;
            assert_eq!(*p, expected, "frame {k} atom {a}");
        }
    }
    assert!(
        reader.read_frame(&mut frame).is_err(),
        "molly has more frames than pgt"
    );
}

#[test]
fn multi_model_pdb_and_mmcif_and_multi_frame_xyz() {
    let pdb = shared_or_skip!("trajectories/md_ascii_trj.pdb");
    check_against(
        open_frames(&IncludeSpec::bare(&pdb))
            .expect("opens")
            .as_ref(),
        "md_ascii_trj_pdb",
        false,
    );
    let nmr = shared_or_skip!("trajectories/1LVZ.pdb");
    check_against(
        open_frames(&IncludeSpec::bare(&nmr))
            .expect("opens")
            .as_ref(),
        "1lvz_pdb",
        false,
    );
    // The mmCIF of the same entry holds the same models; MDAnalysis's own mmCIF reader (gemmi)
    // reads its first model, which pgt's frame 0 matches.
    let cif = shared_or_skip!("trajectories/1LVZ.cif");
    let cif_frames = open_frames(&IncludeSpec::bare(&cif)).expect("opens");
    check_against(cif_frames.as_ref(), "1lvz_pdb", false);
    check_first_frame(cif_frames.as_ref(), "1lvz_cif");
    let xyz = shared_or_skip!("trajectories/2r9r-1b.xyz");
    check_against(
        open_frames(&IncludeSpec::bare(&xyz))
            .expect("opens")
            .as_ref(),
        "2r9r_xyz",
        false,
    );
}

#[test]
fn every_mmpld_frame_matches_a_struct_reading() {
    let path = shared_or_skip!("mmpld/testspheres_old_v100.mmpld");
    let all = vectors();
    let v = &all["testspheres_mmpld"];
    let source = open_frames(&IncludeSpec::bare(&path)).expect("opens");
    assert_eq!(source.info().count, 100);
    let counts = v["particles_per_frame"].as_array().expect("counts");
    for (k, n) in counts.iter().enumerate() {
        let f = source.read_frame(k).expect("frame");
        assert_eq!(
            f.particles.records.len() as u64,
            n.as_u64().expect("n"),
            "frame {k}"
        );
        let pick = |which: &str| -> Vec<DVec3> {
            v[which]
                .as_array()
                .expect("c")
                .iter()
                .map(position)
                .collect()
        };
        let expected = match k {
            0 => pick("first_frame"),
            99 => pick("last_frame"),
            _ => continue,
        };
        let r = &f.particles.records;
        let got = [r[0].center, r[r.len() / 2].center, r[r.len() - 1].center];
        for (g, e) in got.iter().zip(&expected) {
            assert!(
                (*g - *e).abs().max_element() < 1e-6,
                "frame {k}: {g} vs {e}"
            );
        }
    }
    // The frame source and the one-file reader agree on a frame.
    let mut spec = IncludeSpec::bare(&path);
    spec.frame = Some(37);
    let whole = pgt::formats::load_particles(&spec).expect("frame 37");
    let one = source.read_frame(37).expect("frame 37");
    assert_eq!(whole.records, one.particles.records);
}

/// Frame 0 of `source` against the vectors of `key`, a reader that sees one frame.
fn check_first_frame(source: &dyn FrameSource, key: &str) {
    let all = vectors();
    let v = &all[key];
    assert_eq!(v["frames"].as_u64(), Some(1), "{key}: one frame");
    let frame = source.read_frame(0).expect("frame 0");
    let got: Vec<DVec3> = frame.particles.records.iter().map(|r| r.center).collect();
    assert_sampled_positions(&got, v, 0, key);
}

#[test]
fn single_frame_topologies_match_mdanalysis() {
    let pdb = shared_or_skip!("trajectories/ala3.pdb");
    let source = open_frames(&IncludeSpec::bare(&pdb)).expect("opens");
    check_against(source.as_ref(), "ala3_pdb", false);
    let gro = shared_or_skip!("trajectories/ngl_md.gro");
    let source = open_frames(&IncludeSpec::bare(&gro)).expect("opens");
    check_against(source.as_ref(), "ngl_md_gro", false);
}

/// tests/data/xtc/ (scripts/xtc_cases.py): small XTC files at the decoder's edges.
fn xtc_case(name: &str) -> PathBuf {
    crate::support::local(&format!("xtc/{name}.xtc"))
}

#[test]
fn xtc_with_the_small_integer_index_zero_reads_as_mdanalysis_reads_it() {
    let t = open_trajectory_file(&xtc_case("smallidx0")).expect("opens");
    let all = vectors();
    let v = &all["xtc_smallidx0"];
    assert_eq!(t.frames() as u64, v["frames"].as_u64().expect("frames"));
    assert_eq!(t.atoms() as u64, v["atoms"].as_u64().expect("atoms"));
    assert_eq!(t.time_step_ps(), v["time_step_ps"].as_f64());
    let mut p = Vec::new();
    for f in [0usize, 1] {
        t.read_positions(f, &mut p).expect("decodes");
        assert_sampled_positions(&p, v, f, &format!("frame {f}"));
    }
}

#[test]
fn xtc_frames_the_reference_decoder_cannot_decode_are_refused_by_file_frame_and_byte() {
    let mut p = Vec::new();
    // A run of small atoms at index 0: libxdrfile divides by the radix 0 there.
    let t = open_trajectory_file(&xtc_case("run_at_smallidx0")).expect("opens");
    let e = err_of(t.read_positions(0, &mut p));
    assert!(
        e.contains("run_at_smallidx0.xtc") && e.contains("frame 0") && e.contains("index 0"),
        "{e}"
    );
    // 13 atoms said, 12 in the block: the 13th is not decoded from the padding.
    let t = open_trajectory_file(&xtc_case("over_block")).expect("opens");
    assert_eq!(t.atoms(), 13);
    let e = err_of(t.read_positions(0, &mut p));
    assert!(
        e.contains("over_block.xtc")
            && e.contains("frame 0")
            && e.contains("byte ")
            && e.contains("ends before every atom"),
        "{e}"
    );
    // 2^31 - 1 atoms said over 8 bytes: an error, not a 25 GB reservation and an abort.
    let t = open_trajectory_file(&xtc_case("lying_count")).expect("opens");
    assert_eq!(t.atoms(), i32::MAX as usize);
    let e = err_of(t.read_positions(0, &mut p));
    assert!(
        e.contains("lying_count.xtc") && e.contains("frame 0"),
        "{e}"
    );
}

/// A temporary folder for a scene and its files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pgt-frames-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("mkdir");
    dir
}

fn err_of<T: std::fmt::Debug>(r: pgt::Result<T>) -> String {
    r.expect_err("an error").to_string()
}

#[test]
fn scene_includes_play_a_trajectory_and_frame_zero_is_the_static_scene() {
    let psf = shared_or_skip!("trajectories/ala3.psf");
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let dir = scratch("scene");
    let scene_path = dir.join("s.toml");
    let text = format!(
        "[camera]\nwidth = 16\nheight = 16\n\n[[include]]\npath = \"{}\"\ntrajectory = \"{}\"\nframes = \"10..250\"\nframe_step = 20\n",
        psf.display(),
        dcd.display()
    );
    std::fs::write(&scene_path, &text).expect("write");
    let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
    // 10, 30, …, 230: 12 frames.
    assert_eq!(frames.frame_count(), Some(12));
    let info = frames.frame_info().expect("frames");
    assert_eq!(info.atoms_per_frame, Some(42));
    let stat = Scene::load(&scene_path, &SceneLoadOptions::default()).expect("static");
    let f0 = frames.frame(0).expect("frame 0");
    assert_eq!(stat.particles, f0.particles);
    let source = open_frames(&trajectory_spec(&psf, &dcd)).expect("opens");
    let direct = source.read_frame(10 + 3 * 20).expect("source frame 70");
    let f3 = frames.frame(3).expect("frame 3");
    let centres: Vec<DVec3> = f3.particles.iter().map(|p| p.center).collect();
    let expected: Vec<DVec3> = direct.particles.records.iter().map(|r| r.center).collect();
    assert_eq!(centres, expected);
    let e = err_of(frames.frame(12));
    assert!(e.contains("frame 12") && e.contains("12 frame"), "{e}");
    // A range outside the file names the include's line, the file and the key.
    std::fs::write(&scene_path, text.replace("10..250", "0..300")).expect("write");
    let e = err_of(Scene::load(&scene_path, &SceneLoadOptions::default()));
    assert!(
        e.contains("s.toml:5")
            && e.contains("ala3.dcd")
            && e.contains("frames = \"0..300\"")
            && e.contains("256 frame"),
        "{e}"
    );
}

#[test]
fn bare_multi_model_files_play_and_agree_with_the_whole_file_reader() {
    let pdb = shared_or_skip!("trajectories/md_ascii_trj.pdb");
    let frames = SceneFrames::load(
        &pdb,
        &SceneLoadOptions {
            size: Some((8, 8)),
            ..Default::default()
        },
    )
    .expect("loads");
    assert_eq!(frames.frame_count(), Some(51));
    let stat = Scene::load(
        &pdb,
        &SceneLoadOptions {
            size: Some((8, 8)),
            ..Default::default()
        },
    )
    .expect("static");
    assert_eq!(frames.frame(0).expect("0").particles, stat.particles);
    for model in [2usize, 51] {
        let mut spec = IncludeSpec::bare(&pdb);
        spec.model = Some(model);
        let whole = pgt::formats::load_particles(&spec).expect("model");
        let frame = frames.frame(model - 1).expect("frame");
        let centres: Vec<DVec3> = frame.particles.iter().map(|p| p.center).collect();
        let expected: Vec<DVec3> = whole.records.iter().map(|r| r.center).collect();
        assert_eq!(centres, expected, "model {model}");
    }
}

#[test]
fn numbered_sequences_in_printf_and_glob_form() {
    let dir = scratch("seq");
    std::fs::create_dir_all(dir.join("seq")).expect("mkdir");
    for k in 0..3 {
        std::fs::write(
            dir.join(format!("seq/frame_{k:04}.csv")),
            format!("x,y,z,radius\n{k},0,0,0.5\n{k},1,0,0.5\n"),
        )
        .expect("write");
    }
    for pattern in ["seq/frame_%04d.csv", "seq/frame_*.csv"] {
        let scene_path = dir.join("s.toml");
        std::fs::write(
            &scene_path,
            format!("[camera]\nwidth = 8\nheight = 8\n[[include]]\nsequence = \"{pattern}\"\n"),
        )
        .expect("write");
        let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
        assert_eq!(frames.frame_count(), Some(3), "{pattern}");
        let f2 = frames.frame(2).expect("frame 2");
        assert_eq!(f2.particles[1].center, DVec3::new(2.0, 1.0, 0.0));
    }
    // A gap is a missing frame, named.
    std::fs::write(dir.join("seq/frame_0004.csv"), "x,y,z\n0,0,0\n").expect("write");
    let e = err_of(Scene::load(
        &dir.join("s.toml"),
        &SceneLoadOptions::default(),
    ));
    assert!(
        e.contains("frame_0002.csv")
            && e.contains("frame_0004.csv")
            && e.contains("expected number 3"),
        "{e}"
    );
    let e = err_of(Scene::from_toml_str(
        "[[include]]\nsequence = \"nothing/frame_*.csv\"\npath = \"x.csv\"\n",
        &dir.join("t.toml"),
        &SceneLoadOptions::default(),
    ));
    assert!(e.contains("t.toml:1") && e.contains("not both"), "{e}");
}

#[test]
fn moving_includes_must_play_the_same_number_of_frames() {
    let pdb = shared_or_skip!("trajectories/md_ascii_trj.pdb");
    let nmr = shared_or_skip!("trajectories/1LVZ.pdb");
    let dir = scratch("counts");
    let scene_path = dir.join("s.toml");
    std::fs::write(
        &scene_path,
        format!(
            "[camera]\nwidth = 8\nheight = 8\n[[include]]\npath = \"{}\"\n\n[[include]]\npath = \"{}\"\n",
            pdb.display(),
            nmr.display()
        ),
    )
    .expect("write");
    let e = err_of(SceneFrames::load(&scene_path, &SceneLoadOptions::default()));
    assert!(
        e.contains("s.toml:7") && e.contains("plays 20 frames") && e.contains("plays 51"),
        "{e}"
    );
    // Choosing 20 models of the first makes them agree; pinning one makes it static.
    std::fs::write(
        &scene_path,
        format!(
            "[camera]\nwidth = 8\nheight = 8\n[[include]]\npath = \"{}\"\nframes = \"0..40\"\nframe_step = 2\n\n[[include]]\npath = \"{}\"\n\n[[include]]\npath = \"{}\"\nmodel = 3\n",
            pdb.display(),
            nmr.display(),
            nmr.display()
        ),
    )
    .expect("write");
    let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
    assert_eq!(frames.frame_count(), Some(20));
    let f5 = frames.frame(5).expect("frame 5");
    assert_eq!(f5.particles.len(), 183 + 185 + 185);
}

#[test]
fn a_topology_whose_atom_count_differs_is_refused_naming_both_files() {
    let psf = shared_or_skip!("trajectories/tip125_tric_C36.psf");
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let e = err_of(open_frames(&trajectory_spec(&psf, &dcd)).map(|_| ()));
    assert!(
        e.contains("ala3.dcd")
            && e.contains("tip125_tric_C36.psf")
            && e.contains("42 atoms")
            && e.contains("375 atoms"),
        "{e}"
    );
}

#[test]
fn a_corrupt_dcd_frame_in_the_middle_is_an_error_naming_the_file_and_frame() {
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let psf = shared_or_skip!("trajectories/ala3.psf");
    let mut bytes = std::fs::read(&dcd).expect("read");
    // Header 276 bytes, then frames of 3·(4 + 168 + 4) = 528 bytes: frame 100's Y marker.
    let at = 276 + 100 * 528 + 176;
    bytes[at..at + 4].copy_from_slice(&999u32.to_le_bytes());
    let dir = scratch("dcd");
    let bad = dir.join("bad.dcd");
    std::fs::write(&bad, &bytes).expect("write");
    let source = open_frames(&trajectory_spec(&psf, &bad)).expect("opens");
    assert!(source.read_frame(99).is_ok() && source.read_frame(101).is_ok());
    let e = err_of(source.read_frame(100).map(|_| ()));
    assert!(
        e.contains("bad.dcd") && e.contains("frame 100") && e.contains(&format!("byte {at}")),
        "{e}"
    );
    // Truncated in the middle of frame 200: 201 frames, the last one an error.
    std::fs::write(&bad, &bytes[..276 + 200 * 528 + 300]).expect("write");
    let source = open_frames(&trajectory_spec(&psf, &bad)).expect("opens");
    assert_eq!(source.info().count, 201);
    assert!(source
        .warnings()
        .iter()
        .any(|w| w.contains("frame (200) is truncated")));
    let e = err_of(source.read_frame(200).map(|_| ()));
    assert!(
        e.contains("bad.dcd") && e.contains("frame 200 is truncated"),
        "{e}"
    );
}

#[test]
fn corrupt_and_truncated_xtc_frames_name_the_file_and_frame() {
    let xtc = shared_or_skip!("trajectories/ngl_md.xtc");
    let bytes = std::fs::read(&xtc).expect("read");
    let offsets = {
        let mut r = molly::XTCReader::open(&xtc).expect("molly");
        r.determine_offsets(None).expect("offsets")
    };
    let dir = scratch("xtc");
    let bad = dir.join("bad.xtc");
    // Frame 20's magic number broken: frames after it cannot be found.
    let mut b = bytes.clone();
    let at = offsets[20] as usize;
    b[at..at + 4].copy_from_slice(&77i32.to_be_bytes());
    std::fs::write(&bad, &b).expect("write");
    let e = err_of(open_trajectory_file(&bad).map(|_| ()));
    assert!(
        e.contains("bad.xtc") && e.contains("frame 20") && e.contains(&format!("byte {at}")),
        "{e}"
    );
    // Frame 10's compressed block cut short by its byte count: frame 11 is not where it was.
    let mut b = bytes.clone();
    let count_at = offsets[10] as usize + 88;
    b[count_at..count_at + 4].copy_from_slice(&64u32.to_be_bytes());
    std::fs::write(&bad, &b).expect("write");
    let e = err_of(open_trajectory_file(&bad).map(|_| ()));
    assert!(e.contains("bad.xtc") && e.contains("frame 11"), "{e}");
    // Frame 30's compressed bits zeroed: the frame decodes to an error or to other positions,
    // never a panic, and its neighbours still read.
    let mut b = bytes.clone();
    let start = offsets[30] as usize + 100;
    b[start..start + 4000].fill(0xff);
    std::fs::write(&bad, &b).expect("write");
    let t = open_trajectory_file(&bad).expect("opens");
    let mut p = Vec::new();
    let _ = t.read_positions(30, &mut p);
    assert!(t.read_positions(29, &mut p).is_ok() && t.read_positions(31, &mut p).is_ok());
    // Truncated in the middle of frame 40.
    std::fs::write(&bad, &bytes[..offsets[40] as usize + 1000]).expect("write");
    let t = open_trajectory_file(&bad).expect("opens");
    assert_eq!(t.frames(), 41);
    assert!(t.read_positions(39, &mut p).is_ok());
    let e = err_of(t.read_positions(40, &mut p));
    assert!(
        e.contains("bad.xtc") && e.contains("frame 40 is truncated"),
        "{e}"
    );
}

#[test]
fn trajectory_keys_are_checked_with_the_include_line() {
    let dir = scratch("keys");
    let cases = [
        ("[[include]]\nframe_step = 2\n", "set `path`"),
        (
            "[[include]]\npath = \"a.pdb\"\nframe = 1\nframes = \"0..4\"\n",
            "not both",
        ),
        (
            "[[include]]\npath = \"a.pdb\"\nframes = \"4..2\"\n",
            "empty",
        ),
        (
            "[[include]]\npath = \"a.pdb\"\nframe_step = 0\n",
            "frame_step must be ≥ 1",
        ),
        (
            "[[include]]\nsequence = \"f_*.csv\"\ntrajectory = \"t.xtc\"\n",
            "needs `path`",
        ),
        (
            "[[include]]\npath = \"a.pdb\"\ntrajectory = \"t.trr\"\n",
            "unsupported trajectory file type",
        ),
    ];
    for (text, expected) in cases {
        let e = err_of(Scene::from_toml_str(
            text,
            &dir.join("k.toml"),
            &SceneLoadOptions::default(),
        ));
        assert!(e.contains("k.toml") && e.contains(expected), "{text}: {e}");
    }
}

/// A reader that counts the bytes read through it.
struct Counting {
    inner: std::io::Cursor<Vec<u8>>,
    read: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl std::io::Read for Counting {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read
            .fetch_add(n as u64, std::sync::atomic::Ordering::Relaxed);
        Ok(n)
    }
}

impl std::io::Seek for Counting {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

#[test]
fn opening_and_reading_a_frame_reads_that_frame_not_the_trajectory() {
    use std::sync::atomic::Ordering;
    for (rel, frame) in [
        ("trajectories/ngl_md.xtc", 37usize),
        ("trajectories/ala3.dcd", 200),
    ] {
        let path = shared_or_skip!(rel);
        let bytes = std::fs::read(&path).expect("read");
        let len = bytes.len() as u64;
        let read = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let reader = Counting {
            inner: std::io::Cursor::new(bytes),
            read: read.clone(),
        };
        let source = pgt::formats::frames::ByteSource::from_reader(&path, len, Box::new(reader));
        let format = pgt::formats::Format::trajectory_of(&path).expect("a trajectory");
        let open = format.trajectory.expect("a trajectory reader");
        let t = open(source).expect("opens");
        let at_open = read.load(Ordering::Relaxed);
        let frames = t.frames() as u64;
        // Opening reads headers: at most 100 bytes a frame (XTC's scan) or the DCD header.
        assert!(
            at_open <= 100 * frames.max(4),
            "{rel}: {at_open} bytes read at open"
        );
        let mut p = Vec::new();
        t.read_positions(frame, &mut p).expect("frame");
        let for_frame = read.load(Ordering::Relaxed) - at_open;
        // One frame is at most twice the mean frame size of the file.
        assert!(
            for_frame <= 2 * len / frames,
            "{rel}: {for_frame} bytes for one frame of {len}"
        );
        assert!(for_frame > 0);
    }
}

#[test]
fn a_trajectory_of_one_frame_plays_as_a_sequence_of_one() {
    let psf = shared_or_skip!("trajectories/ala3.psf");
    let dcd = shared_or_skip!("trajectories/ala3.dcd");
    let dir = scratch("one-frame");
    // ala3.dcd's header (276 bytes, its frame count NSET at byte 8) and its first frame (528).
    let mut bytes = std::fs::read(&dcd).expect("read")[..276 + 528].to_vec();
    bytes[8..12].copy_from_slice(&1i32.to_le_bytes());
    let one = dir.join("one.dcd");
    std::fs::write(&one, &bytes).expect("write");
    let scene_path = dir.join("s.toml");
    std::fs::write(
        &scene_path,
        format!(
            "[camera]\nwidth = 16\nheight = 16\n\n[[include]]\npath = \"{}\"\ntrajectory = \"{}\"\n",
            psf.display(),
            one.display()
        ),
    )
    .expect("write");
    let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
    assert_eq!(frames.frame_count(), Some(1));
    let info = frames.frame_info().expect("a sequence of one");
    assert_eq!((info.count, info.atoms_per_frame), (1, Some(42)));
    let f0 = frames.frame(0).expect("frame 0");
    let direct = open_frames(&trajectory_spec(&psf, &dcd))
        .expect("opens")
        .read_frame(0)
        .expect("source frame 0");
    let centres: Vec<DVec3> = f0.particles.iter().map(|p| p.center).collect();
    let expected: Vec<DVec3> = direct.particles.records.iter().map(|r| r.center).collect();
    assert_eq!(centres, expected);
    // A PDB of one model is a particle file, not a sequence: it does not play.
    let pdb = shared_or_skip!("trajectories/ala3.pdb");
    std::fs::write(
        &scene_path,
        format!(
            "[camera]\nwidth = 16\nheight = 16\n\n[[include]]\npath = \"{}\"\n",
            pdb.display()
        ),
    )
    .expect("write");
    let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
    assert_eq!(frames.frame_count(), None);
}
