//! The benchmark of `pgt bench` (and `pgt.bench`): the speed of the exact reference on standard workloads, as one table of ratios
//! (docs/design.md §7), so that one run on a noisy machine shows what changed.
//!
//! | workload | scene |
//! |---|---|
//! | `1uun` | 1UUN chains A+B (2,758 atoms) from `DATA/pdb/1uun_opm_oriented.pdb`, or, where the file is missing, a generated protein-sized set (2,758 spheres, radii 1.2–1.9 Å, one per 20 Å³) |
//! | `random` | the thesis's random set "cool random" (73,642 spheres, `DATA/mmpld/cool_random.mmpld`), or, where the file is missing, `pgt gen random`'s set of the same size |
//! | `million` | 1,000,000 random spheres (`pgt gen random --count 1000000`), emission model only |
//! | `million-lit` | the same, lit (not in the default list: minutes on two cores) |
//! | `1uun-scatter` | 1UUN as `1uun`, single-scatter model, two point lights: one at the centre of the particles' bounding sphere (inside the gas) and one above it (not in the default list) |
//! | `1uun-ellipsoids` | 1UUN as `1uun`, each atom an ellipsoid of the same volume: semi-axes r·k·(1, u, v), u and v uniform in [1/4, 1], k = (uv)^{−1/3}, a uniformly random orientation, Θmax 0.5 along the shortest diameter (SplitMix64 seed 1; not in the default list) |
//! | `gaussians` | 100,000 Gaussians of `pgt gen random --count 100000` (centres in the 200-unit cube, standard deviations 0.5–2 as the radii), opacity 0.5 along the shortest axis (docs/design.md §9), emission model (not in the default list) |
//! | `orbit`, `xtc` | sequences of frames: a frame of a sequence against a single render of it ([`frames`]; not in the default list) |
//!
//! Every scene is the bare-file default (docs/design.md §1): the camera frames the bounding sphere,
//! the thesis's two directional lights (green down, blue up), black background, Θmax = 0.5, lit
//! model, `tol` 1e-4. Each lit workload is rendered three times: adaptive (the reference), the
//! thesis's Riemann sums with 100 samples per interval, and the emission model, and the table
//! gives the adaptive time as a ratio to both. `--accuracy` adds a tol 1e-9 render and the
//! largest error of the adaptive and Riemann images against it (the target: adaptive ≥ 100×
//! smaller). `--repeat N` renders the workload's renderers N times in turn and keeps the
//! fastest run of each: on shared cores one render's time moves with the load, and the
//! fastest of a few interleaved runs is the steadier basis for a ratio.

pub mod frames;

use crate::formats::random::{generate, RandomSpec, SplitMix64, THESIS_COUNT};
use crate::optics::extinction::sigma_from_opacity;
use crate::optics::model::LightNeed;
use crate::optics::models;
use crate::reference::{self, Integrator, RenderOptions, RenderOutput};
use crate::scene::{
    bounding_sphere, default_camera, thesis_lights, Falloff, Light, Model, Particle,
    RenderSettings, Scene, SceneLoadOptions,
};
use anyhow::Context;
use clap::ValueEnum;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Θmax of every bench particle.
const OPACITY: f64 = 0.5;
/// Quadrature tolerance of the bench's lit renders.
const TOL: f64 = 1e-4;
/// Tolerance of the `--accuracy` truth.
const TRUTH_TOL: f64 = 1e-9;
/// Samples per interval of the Riemann baseline (the thesis's scheme).
const RIEMANN_SAMPLES: u32 = 100;
/// Atoms of 1UUN chains A+B, and of the generated stand-in.
const PROTEIN_ATOMS: usize = 2758;
/// Å³ per atom of the stand-in: about a protein's density.
const VOLUME_PER_ATOM: f64 = 20.0;
/// Gaussians of the `gaussians` workload.
const GAUSSIANS: usize = 100_000;
/// Spheres of the `million` workloads.
const MILLION: usize = 1_000_000;

/// A standard workload of `pgt bench`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Workload {
    /// 1UUN chains A+B, lit (or a generated protein-sized set).
    #[value(name = "1uun")]
    Protein,
    /// The thesis's random set "cool random" (73,642 spheres), lit.
    Random,
    /// 1,000,000 random spheres, emission model.
    Million,
    /// 1,000,000 random spheres, lit.
    MillionLit,
    /// 1UUN (or the protein-sized set), single-scatter, point lights inside and above.
    #[value(name = "1uun-scatter")]
    ProteinScatter,
    /// 1UUN (or the protein-sized set) as ellipsoids of the atoms' volumes, lit.
    #[value(name = "1uun-ellipsoids")]
    ProteinEllipsoids,
    /// 100,000 random Gaussians, emission model.
    Gaussians,
    /// 1UUN chains A+B, lit, on an orbiting camera: a frame of the sequence against a single
    /// render.
    Orbit,
    /// ngl_md.gro moved by ngl_md.xtc, emission: a frame of the sequence against a single render.
    Xtc,
}

impl Workload {
    /// The workload of a name as `--workloads` spells it (`1uun`, `million-lit`, …).
    pub fn named(name: &str) -> Option<Workload> {
        Workload::from_str(name, false).ok()
    }

    /// Every workload's name, as `--workloads` spells them.
    pub fn names() -> Vec<String> {
        Workload::value_variants()
            .iter()
            .filter_map(|w| w.to_possible_value().map(|v| v.get_name().to_string()))
            .collect()
    }
}

/// What `pgt bench` runs: its options.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Image side in pixels (square images).
    pub size: u32,
    /// Workloads to run, in order.
    pub workloads: Vec<Workload>,
    /// Skip the Riemann-100 and emission baselines (only the adaptive renders).
    pub no_baselines: bool,
    /// Also render a tol 1e-9 truth and report the largest errors against it.
    pub accuracy: bool,
    /// Worker threads (default: rayon's, one per core).
    pub threads: Option<usize>,
    /// Renders of each renderer per workload, taken in turn; the table gives the fastest of each.
    pub repeat: u32,
    /// Frames of the sequence workloads (`orbit`: 4; `xtc`: all 51).
    pub frames: Option<usize>,
    /// Folder with `pdb/1uun_opm_oriented.pdb`, `mmpld/cool_random.mmpld` and
    /// `trajectories/`.
    pub data: PathBuf,
}

/// Runs the workloads and hands each table to `print` as it is done: the table of the single
/// renders, then that of the sequences (`frames`), each only where it has a row. Progress goes
/// to stderr, one line per workload.
pub fn run(
    options: &BenchOptions,
    print: &mut dyn FnMut(&str) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if options.repeat > 1 {
        eprintln!(
            "bench: each renderer {} times in turn, the fastest run of each in the table",
            options.repeat
        );
    }
    let mut rows = Vec::new();
    let mut sequences = Vec::new();
    for &w in &options.workloads {
        match w {
            Workload::Orbit => sequences.push("orbit"),
            Workload::Xtc => sequences.push("xtc"),
            _ => {}
        }
        if matches!(w, Workload::Orbit | Workload::Xtc) {
            continue;
        }
        let (name, scene) = workload_scene(w, options.size, &options.data)?;
        eprintln!(
            "bench: {name}, {}, {}x{}",
            scene.particles_text(),
            options.size,
            options.size
        );
        rows.extend(bench_scene(&name, &scene, options)?);
    }
    if !rows.is_empty() {
        print(&table(&rows))?;
    }
    if !sequences.is_empty() {
        let t = frames::bench_frames(
            &sequences,
            options.size,
            options.frames,
            TOL,
            options.threads,
            &options.data,
        )?;
        print(&t)?;
    }
    Ok(())
}

/// One line of the table.
struct Row {
    workload: String,
    renderer: String,
    size: u32,
    spheres: usize,
    out: RenderOutput,
    /// Wall seconds of the whole render, BVH build included (`out.stats.seconds` is the
    /// pixels alone).
    wall: f64,
    /// Seconds of the Riemann-100 and emission renders of the same scene, where run.
    riemann: Option<f64>,
    emission: Option<f64>,
    /// Largest |value − truth| over pixels and channels, where `--accuracy` asked for it.
    max_error: Option<f64>,
}

/// Renders `scene` with `integrator` (and `model` instead of the scene's, if given).
fn render(
    scene: &Scene,
    model: Option<Model>,
    integrator: Integrator,
    tol: f64,
    threads: Option<usize>,
) -> anyhow::Result<(RenderOutput, f64)> {
    let start = std::time::Instant::now();
    let mut s = scene.clone();
    if let Some(m) = model {
        s.render.model = m;
    }
    s.render.tol = tol;
    let options = RenderOptions {
        spp: 1,
        threads,
        progress: false,
        integrator,
    };
    let out = reference::render(&s, &options)?;
    Ok((out, start.elapsed().as_secs_f64()))
}

/// The rows of one workload: adaptive, and (unless skipped) Riemann-100 and emission.
fn bench_scene(name: &str, scene: &Scene, args: &BenchOptions) -> anyhow::Result<Vec<Row>> {
    let threads = args.threads;
    let row = |renderer: &str, (out, wall): (RenderOutput, f64)| Row {
        workload: name.to_string(),
        renderer: renderer.to_string(),
        size: args.size,
        spheres: scene.particles.len(),
        out,
        wall,
        riemann: None,
        emission: None,
        max_error: None,
    };
    let lit = scene.render.model.light_need() != LightNeed::None;
    let riemann_100 = Integrator::Riemann {
        samples: RIEMANN_SAMPLES,
    };
    // (model, integrator) of each renderer of this workload, in the order they take turns:
    // the scene's own model alone where it has no lights to integrate or no baselines are
    // asked for.
    let renderers: &[(Option<Model>, Integrator)] = if !lit || args.no_baselines {
        &[(None, Integrator::Adaptive)]
    } else {
        &[
            (None, Integrator::Adaptive),
            (None, riemann_100),
            (Some(models::EMISSION), Integrator::Adaptive),
        ]
    };
    let mut fastest: Vec<Option<(RenderOutput, f64)>> = vec![None; renderers.len()];
    for _ in 0..args.repeat {
        for (best, &(model, integrator)) in fastest.iter_mut().zip(renderers) {
            let run = render(scene, model, integrator, TOL, threads)?;
            if best.as_ref().is_none_or(|(_, wall)| run.1 < *wall) {
                *best = Some(run);
            }
        }
    }
    let mut fastest = fastest.into_iter().flatten();
    let mut next = |renderer: &str| {
        fastest
            .next()
            .map(|run| row(renderer, run))
            .ok_or_else(|| anyhow::anyhow!("--repeat must be at least 1"))
    };
    if !lit {
        return Ok(vec![next("emission")?]);
    }
    let mut adaptive = next("adaptive tol 1e-4")?;
    let mut rows = Vec::new();
    if !args.no_baselines {
        let mut riemann = next("riemann-100")?;
        let emission = next("emission")?;
        adaptive.riemann = Some(riemann.wall);
        adaptive.emission = Some(emission.wall);
        riemann.riemann = Some(riemann.wall);
        riemann.emission = Some(emission.wall);
        if args.accuracy {
            let (truth, _) = render(scene, None, Integrator::Adaptive, TRUTH_TOL, threads)?;
            adaptive.max_error = Some(max_difference(&adaptive.out, &truth));
            riemann.max_error = Some(max_difference(&riemann.out, &truth));
        }
        rows.push(adaptive);
        rows.push(riemann);
        rows.push(emission);
    } else {
        rows.push(adaptive);
    }
    Ok(rows)
}

/// Largest |a − b| over pixels and channels.
fn max_difference(a: &RenderOutput, b: &RenderOutput) -> f64 {
    a.image
        .pixels
        .iter()
        .zip(&b.image.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).abs()))
        .fold(0.0, f64::max)
}

/// The scene of a workload and its name in the table.
fn workload_scene(w: Workload, size: u32, data: &Path) -> anyhow::Result<(String, Scene)> {
    match w {
        Workload::Protein | Workload::ProteinScatter | Workload::ProteinEllipsoids => {
            let pdb = data.join("pdb").join("1uun_opm_oriented.pdb");
            let (name, mut scene) = if pdb.is_file() {
                ("1UUN A+B".to_string(), protein_scene(&pdb, size)?)
            } else {
                eprintln!(
                    "bench: {} not found; using a generated protein-sized set",
                    pdb.display()
                );
                let particles = protein_like();
                ("protein-like".to_string(), bare_scene(particles, size))
            };
            if w == Workload::ProteinScatter {
                scene.render.model = models::SINGLE_SCATTER;
                scene.lights = inside_and_above(&scene.particles);
                let short = if pdb.is_file() { "1UUN" } else { "protein" };
                return Ok((format!("{short} scatter"), scene));
            }
            if w == Workload::ProteinEllipsoids {
                as_ellipsoids(&mut scene.particles);
                return Ok((format!("{name} ellipsoids"), scene));
            }
            Ok((name, scene))
        }
        Workload::Orbit | Workload::Xtc => {
            anyhow::bail!("{w:?} is a sequence workload, timed by bench_frames")
        }
        Workload::Random => {
            let mmpld = data.join("mmpld").join("cool_random.mmpld");
            if mmpld.is_file() {
                return Ok(("cool random 73,642".into(), set_scene(&mmpld, size)?));
            }
            eprintln!(
                "bench: {} not found; using pgt gen random's set of the same size",
                mmpld.display()
            );
            Ok((
                "random 73,642".into(),
                bare_scene(random_set(THESIS_COUNT), size),
            ))
        }
        Workload::Gaussians => {
            let mut particles = random_set(GAUSSIANS);
            for p in &mut particles {
                p.profile = crate::optics::Profile::Gaussian;
                p.sigma = crate::optics::gaussian::sigma_from_peak_opacity(OPACITY, p.radius);
            }
            let mut s = bare_scene(particles, size);
            s.render.model = models::EMISSION;
            Ok(("gaussians 100,000".into(), s))
        }
        Workload::Million | Workload::MillionLit => {
            let mut s = bare_scene(random_set(MILLION), size);
            if w == Workload::Million {
                s.render.model = models::EMISSION;
            }
            Ok(("random 1,000,000".into(), s))
        }
    }
}

/// The point lights of `1uun-scatter`: one at the centre c of the particles' bounding sphere
/// (radius R), inside the gas, whose unoccluded irradiance at distance R is (0.5, 0.4, 0.3),
/// and a white one at c + 1.5·R·ŷ with irradiance 1 at c.
fn inside_and_above(particles: &[Particle]) -> Vec<Light> {
    let (c, r) = bounding_sphere(particles);
    vec![
        Light::Point {
            position: c,
            intensity: DVec3::new(0.5, 0.4, 0.3) * (r * r),
            falloff: Falloff::InverseSquare,
        },
        Light::Point {
            position: c + DVec3::new(0.0, 1.5 * r, 0.0),
            intensity: DVec3::ONE * (1.5 * r).powi(2),
            falloff: Falloff::InverseSquare,
        },
    ]
}

/// 1UUN chains A and B with the bare-file defaults (docs/design.md §1), through the scene loader.
fn protein_scene(pdb: &Path, size: u32) -> anyhow::Result<Scene> {
    thesis_scene(pdb, "chains = [\"A\", \"B\"]\n", size)
}

/// The thesis's scene around the particle file `path` (its own colours and radii).
fn set_scene(path: &Path, size: u32) -> anyhow::Result<Scene> {
    thesis_scene(path, "", size)
}

/// The thesis's lights, Θmax and tolerance around the file `path`, with `include` lines added
/// to its `[[include]]` table.
fn thesis_scene(path: &Path, include: &str, size: u32) -> anyhow::Result<Scene> {
    let text = format!(
        "[render]\ntol = {TOL:e}\n\n[defaults]\nopacity = {OPACITY}\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [0.0, 1.0, 0.0]\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, 1.0, 0.0]\nirradiance = [0.0, 0.0, 1.0]\n\n\
         [[include]]\npath = {:?}\n{include}",
        path.display().to_string()
    );
    let options = SceneLoadOptions {
        size: Some((size, size)),
        ..SceneLoadOptions::default()
    };
    Scene::from_toml_str(&text, Path::new("bench.toml"), &options)
        .with_context(|| format!("loading {}", path.display()))
}

/// The default scene of a bare particle file (docs/design.md §1) around `particles`, lit, tol 1e-4.
fn bare_scene(particles: Vec<Particle>, size: u32) -> Scene {
    Scene {
        source: PathBuf::from("bench"),
        camera: default_camera(&particles, size, size),
        render: RenderSettings {
            tol: TOL,
            ..RenderSettings::default()
        },
        lights: thesis_lights(),
        particles,
        warnings: Vec::new(),
        provenance: Default::default(),
    }
}

fn particle(center: DVec3, radius: f64, color: DVec3) -> Particle {
    Particle {
        ellipsoid: None,
        profile: crate::optics::Profile::Constant,
        center,
        radius,
        color,
        sigma: sigma_from_opacity(OPACITY, radius),
        albedo: color,
        ks: 0.0,
        shininess: 32.0,
    }
}

/// Turns each sphere into an ellipsoid of the same volume (the `1uun-ellipsoids` workload): semi-axes
/// r·k·(1, u, v) with u, v uniform in [1/4, 1] and k = (uv)^{−1/3}, a uniformly random unit
/// quaternion (normalised Gaussian components, by Box–Muller), σ for Θmax = [`OPACITY`] along
/// the shortest diameter.
pub fn as_ellipsoids(particles: &mut [Particle]) {
    let mut rng = SplitMix64::new(1);
    for p in particles {
        let (u, v) = (0.25 + 0.75 * rng.next_f64(), 0.25 + 0.75 * rng.next_f64());
        let k = (u * v).powf(-1.0 / 3.0);
        let semi_axes = DVec3::new(1.0, u, v) * (p.radius * k);
        let mut gaussian = || {
            let (a, b) = (1.0 - rng.next_f64(), rng.next_f64());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        let q = glam::DVec4::new(gaussian(), gaussian(), gaussian(), gaussian());
        let rotation = glam::DQuat::from_vec4(q.normalize());
        let ellipsoid = crate::geometry::Ellipsoid::new(semi_axes, rotation);
        p.radius = ellipsoid.bounding_radius();
        p.sigma = sigma_from_opacity(OPACITY, ellipsoid.shortest_semi_axis());
        p.ellipsoid = Some(ellipsoid);
    }
}

/// `pgt gen random --count n` with its other defaults.
fn random_set(count: usize) -> Vec<Particle> {
    let spec = RandomSpec {
        count,
        ..RandomSpec::default()
    };
    generate(&spec)
        .into_iter()
        .map(|p| particle(p.center, p.radius, p.color))
        .collect()
}

/// A protein-sized stand-in for 1UUN: 2,758 spheres, radii in [1.2, 1.9] Å, centres uniform in
/// a cube of 2,758·20 Å³, random colours.
fn protein_like() -> Vec<Particle> {
    let side = (PROTEIN_ATOMS as f64 * VOLUME_PER_ATOM).cbrt();
    let mut rng = SplitMix64::new(1);
    let vec3 = |rng: &mut SplitMix64, scale: f64| {
        DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * scale
    };
    (0..PROTEIN_ATOMS)
        .map(|_| {
            let r = 1.2 + 0.7 * rng.next_f64();
            let c = vec3(&mut rng, side);
            let color = vec3(&mut rng, 1.0);
            particle(c, r, color)
        })
        .collect()
}

/// Peak resident memory of this process in MiB (Linux `VmHWM`), where the system says.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// The table: one row per render, ratios of each time to the Riemann-100 and emission renders
/// of the same scene.
fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<18} {:<18} {:>5} {:>9} {:>9} {:>8} {:>10} {:>8} {:>9} {:>9} {:>10} {:>10}",
        "workload",
        "renderer",
        "size",
        "spheres",
        "time s",
        "setup s",
        "shadow/px",
        "Mrays/s",
        "/riemann",
        "/emission",
        "max err",
        "vs truth"
    );
    for r in rows {
        let st = &r.out.stats;
        let rays = st.primary_rays + st.shadow_rays;
        let ratio = |base: Option<f64>| {
            base.map_or("-".to_string(), |b| format!("{:.3}", r.wall / b.max(1e-9)))
        };
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2e}"));
        let _ = writeln!(
            s,
            "{:<18} {:<18} {:>5} {:>9} {:>9.2} {:>8.2} {:>10.1} {:>8.2} {:>9} {:>9} {:>10} {:>10}",
            r.workload,
            r.renderer,
            r.size,
            r.spheres,
            r.wall,
            r.wall - st.seconds,
            st.shadow_rays as f64 / st.pixels.max(1) as f64,
            rays as f64 / st.seconds.max(1e-9) / 1e6,
            ratio(r.riemann),
            ratio(r.emission),
            opt(st.max_error),
            opt(r.max_error),
        );
    }
    for r in rows {
        if let Some(w) = crate::reference::unconverged_warning(&r.out.stats, TOL) {
            let _ = writeln!(s, "warning: {} {}: {w}", r.workload, r.renderer);
        }
    }
    if let Some(mib) = peak_memory_mib() {
        let _ = writeln!(s, "peak resident memory {mib:.0} MiB");
    }
    s
}
