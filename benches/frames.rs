//! `cargo bench --bench frames`: what decoding a trajectory frame costs next to rendering it
//! (issue 32: decoding an XTC or DCD frame costs ≤ 5 % of rendering it). Prints the figures and
//! checks the 5 % bound on the XTC workload of the issue (ngl_md.xtc with ngl_md.gro, 17,411
//! atoms, emission, 256²). Needs `trajectories/` of the shared data (`../shared/data`, or
//! `$PGT_SHARED_DATA`); without it the bench says what is absent and measures nothing.

#[path = "../tests/support/mod.rs"]
mod support;

use pgt::formats::topology::open_trajectory_file;
use pgt::reference::{render, RenderOptions};
use pgt::scene::{SceneFrames, SceneLoadOptions};
use std::time::Instant;
use support::shared;

/// Best of `n` runs of `f`, seconds.
fn best_of(n: usize, mut f: impl FnMut()) -> f64 {
    (0..n)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let (Some(gro), Some(xtc), Some(psf), Some(dcd)) = (
        shared("trajectories/ngl_md.gro"),
        shared("trajectories/ngl_md.xtc"),
        shared("trajectories/tip125_tric_C36.psf"),
        shared("trajectories/tip125_tric_C36.dcd"),
    ) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("pgt-frames-timing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("mkdir");
    let mut ratios = Vec::new();
    for (name, topology, trajectory, frame) in
        [("xtc", &gro, &xtc, 25usize), ("dcd", &psf, &dcd, 5)]
    {
        let scene_path = dir.join(format!("{name}.toml"));
        std::fs::write(
            &scene_path,
            format!(
                "[camera]\nwidth = 256\nheight = 256\n[render]\nmodel = \"emission\"\n[[include]]\npath = \"{}\"\ntrajectory = \"{}\"\n",
                topology.display(),
                trajectory.display()
            ),
        )
        .expect("write");
        let frames = SceneFrames::load(&scene_path, &SceneLoadOptions::default()).expect("loads");
        let traj = open_trajectory_file(trajectory).expect("opens");
        let mut positions = Vec::new();
        let decode = best_of(20, || {
            traj.read_positions(frame, &mut positions).expect("decodes");
        });
        let build = best_of(5, || {
            frames.frame(frame).expect("frame");
        });
        let scene = frames.frame(frame).expect("frame");
        let draw = best_of(3, || {
            render(&scene, &RenderOptions::default()).expect("renders");
        });
        let ratio = decode / draw;
        println!(
            "{name}: {} atoms, decode {:.3} ms, frame scene (decode + records + particles) {:.3} ms, render 256² emission {:.1} ms: decode/render = {:.3} %",
            traj.atoms(),
            decode * 1e3,
            build * 1e3,
            draw * 1e3,
            100.0 * ratio
        );
        ratios.push((name, ratio));
    }
    pgt_against_molly(&xtc);
    let (_, xtc_ratio) = ratios[0];
    assert!(
        xtc_ratio <= 0.05,
        "decoding an XTC frame costs {:.2} % of rendering it",
        100.0 * xtc_ratio
    );
}

/// Every frame of `xtc` decoded by pgt's decoder and by the `molly` crate (issue 44: keep
/// whichever decodes what libxdrfile decodes and is not slower), best of 5 each, alternately.
fn pgt_against_molly(xtc: &std::path::Path) {
    let traj = open_trajectory_file(xtc).expect("opens");
    let mut positions = Vec::new();
    let (mut ours, mut theirs) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        ours = ours.min(best_of(1, || {
            for k in 0..traj.frames() {
                traj.read_positions(k, &mut positions).expect("decodes");
            }
        }));
        theirs = theirs.min(best_of(1, || {
            let mut reader = molly::XTCReader::open(xtc).expect("molly opens");
            let mut frame = molly::Frame::default();
            while reader.read_frame(&mut frame).is_ok() {}
        }));
    }
    println!(
        "xtc, all {} frames of {} atoms: pgt {:.1} ms, molly {:.1} ms (pgt/molly {:.2})",
        traj.frames(),
        traj.atoms(),
        ours * 1e3,
        theirs * 1e3,
        ours / theirs
    );
}
