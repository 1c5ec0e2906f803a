//! `pgt bench --workloads orbit,xtc`: what a frame of a sequence costs against a single render
//! of that frame (docs/design.md §10), and how much of it is building the frame's scene.
//!
//! | workload | scene |
//! |---|---|
//! | `orbit` | 1UUN chains A+B (`DATA/pdb/1uun_opm_oriented.pdb`), lit, the bench's two lights, the camera on an orbit of 3.6° a frame |
//! | `xtc` | `DATA/trajectories/ngl_md.gro` moved by `ngl_md.xtc` (17,411 atoms, 51 frames), emission model |
//!
//! Per workload, three timings of the same frames (`--frames N`, the first N; the trajectory's
//! 51 by default): the sequence (`pgt render --frames`: one scene load, every frame built,
//! rendered and written), the frames one at a time as `pgt render` of that frame would (the scene
//! file loaded again, the frame built, rendered and written), and the frames' scenes built alone
//! (for `xtc`: reading and decoding the frame, the topology's particles) and their render
//! hashes. The table gives the sequence's time a frame as a ratio to the single renders' (the
//! target: ≤ 1.05), and the building's and the hash's shares of the sequence.

use crate::parts::render_hash;
use crate::reference::{self, Device, RenderOptions};
use crate::scene::{SceneFrames, SceneLoadOptions};
use crate::sequence::render::{render_frames, write_frame, FrameDone};
use crate::sequence::SequencePattern;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Degrees a frame of the `orbit` workload.
const ORBIT_DEGREES: f64 = 3.6;

/// The scene file of a sequence workload, or `None` where its data is missing (with a message).
fn scene_text(workload: &str, size: u32, tol: f64, data: &Path) -> Option<String> {
    let (include, render) = match workload {
        "orbit" => {
            let pdb = data.join("pdb/1uun_opm_oriented.pdb");
            if !pdb.is_file() {
                eprintln!("bench: {} not found; orbit skipped", pdb.display());
                return None;
            }
            (
                format!(
                    "path = {:?}\nchains = [\"A\", \"B\"]\n",
                    pdb.display().to_string()
                ),
                format!("model = \"lit\"\ntol = {tol}\n"),
            )
        }
        _ => {
            let gro = data.join("trajectories/ngl_md.gro");
            let xtc = data.join("trajectories/ngl_md.xtc");
            if !(gro.is_file() && xtc.is_file()) {
                eprintln!(
                    "bench: {} or its .xtc not found; xtc skipped",
                    gro.display()
                );
                return None;
            }
            (
                format!(
                    "path = {:?}\ntrajectory = {:?}\n",
                    gro.display().to_string(),
                    xtc.display().to_string()
                ),
                "model = \"emission\"\n".to_string(),
            )
        }
    };
    let orbit = if workload == "orbit" {
        format!("[camera.orbit]\naxis = [0, 1, 0]\ndegrees_per_frame = {ORBIT_DEGREES}\n")
    } else {
        String::new()
    };
    Some(format!(
        "[camera]\nwidth = {size}\nheight = {size}\n{orbit}\n[render]\n{render}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [0.0, 1.0, 0.0]\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, 1.0, 0.0]\nirradiance = [0.0, 0.0, 1.0]\n\n\
         [defaults]\nopacity = 0.5\n\n[[include]]\n{include}"
    ))
}

/// One workload's figures.
struct FrameRow {
    workload: &'static str,
    frames: usize,
    atoms: usize,
    sequence: f64,
    single: f64,
    build: f64,
    hash: f64,
}

/// Runs the sequence workloads named in `workloads` (lit ones at `tol`) and returns their
/// table (Markdown).
pub fn bench_frames(
    workloads: &[&'static str],
    size: u32,
    frames: Option<usize>,
    tol: f64,
    threads: Option<usize>,
    data: &Path,
) -> anyhow::Result<String> {
    let options = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    let mut rows = Vec::new();
    for &w in workloads {
        let Some(text) = scene_text(w, size, tol, data) else {
            continue;
        };
        let dir = tempfile::tempdir()?;
        let scene_path = dir.path().join(format!("{w}.toml"));
        std::fs::write(&scene_path, text)?;
        let load = || SceneFrames::load(&scene_path, &SceneLoadOptions::default());
        let seq = load()?;
        let n = frames
            .unwrap_or(seq.frame_count().unwrap_or(4))
            .min(seq.frame_count().unwrap_or(usize::MAX))
            .max(1);
        let list: Vec<usize> = (0..n).collect();
        eprintln!("bench: {w}, {n} frames of {size}x{size}");

        let start = Instant::now();
        let pattern = SequencePattern::parse(&dir.path().join("seq/f_%04d.exr"))?;
        let seq = load()?;
        render_frames(
            &seq,
            &list,
            &pattern,
            &options,
            Device::Cpu,
            0.0,
            &|_: &FrameDone| {},
        )?;
        let sequence = start.elapsed().as_secs_f64();

        let start = Instant::now();
        for &k in &list {
            let scene = load()?.frame(k)?;
            let out = reference::render(&scene, &options)?;
            let path = dir.path().join(format!("single/f_{k:04}.exr"));
            let hash = render_hash(&scene, &options);
            write_frame(&path, k, &hash, &out.image, out.error.as_ref(), 0.0)?;
        }
        let single = start.elapsed().as_secs_f64();

        let (mut build, mut hash, mut atoms) = (0.0, 0.0, 0);
        for &k in &list {
            let start = Instant::now();
            let scene = seq.frame(k)?;
            build += start.elapsed().as_secs_f64();
            atoms = scene.particles.len();
            let start = Instant::now();
            std::hint::black_box(render_hash(&scene, &options));
            hash += start.elapsed().as_secs_f64();
        }
        rows.push(FrameRow {
            workload: w,
            frames: n,
            atoms,
            sequence,
            single,
            build,
            hash,
        });
    }
    let mut t = String::from(
        "\n| sequence | frames | spheres | s a frame in the sequence | s a frame alone | ratio | reading and building a frame's scene | its render hash |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        let per = |v: f64| v / r.frames as f64;
        let _ = writeln!(
            t,
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.4} s ({:.1} %) | {:.4} s ({:.1} %) |",
            r.workload,
            r.frames,
            r.atoms,
            per(r.sequence),
            per(r.single),
            r.sequence / r.single.max(1e-12),
            per(r.build),
            100.0 * r.build / r.sequence.max(1e-12),
            per(r.hash),
            100.0 * r.hash / r.sequence.max(1e-12)
        );
    }
    Ok(t)
}
