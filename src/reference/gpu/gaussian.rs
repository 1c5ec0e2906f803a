//! The GPU reference for Gaussian particles (docs/design.md §12, §9 "Gaussian density"): the
//! emission model of `reference::gaussian` computed in f64 by `shaders/reference_gaussian.wgsl`,
//! one invocation per camera ray, with the CPU renderer's k (`gaussian_cutoff`), far depth,
//! windows, pieces and shares of tol (`reference::budget::gaussian`), without its optimisations
//! (series polynomials, the front-to-back narrowing gather).
//!
//! **err** has the CPU's meaning, a bound on |stored − true| per pixel channel, and the CPU's
//! parts ([`ray_error`]): the ray stop, the deviations bounded in closed form, the quadrature's
//! estimate, M·(1 − e^{−Δ}) for the depth Δ left out (far, faint, tails); and the device's own:
//! the profiles' and the pieces' depth uncertainty as M per unit of depth (t*'s through the
//! position derivative of L, which only other gas makes matter), and the composite's
//! rounding, doubled for the second-order terms. A ray takes its windows in batches of
//! [`WINDOWS_MAX`] over the shared traversal (`shaders/nearest_events.wgsl`). A ray the
//! program cannot finish (more windows open at one depth than a batch holds; a piece beyond
//! the loop budget of a pass, and on lavapipe every ray of that ray's workgroup) is not
//! converged with err = |L| + M, the bound that holds for any value; a ray whose quadrature
//! could not meet its share keeps its estimate in err and is counted not converged, as on the
//! CPU.

use super::math::{ERFC_NORMAL, ERFC_ULPS, EXPM1_ULPS, EXP_ULPS, U};
use super::pipeline::{check_f64, compile};
use super::program::{f64_program, generated_declarations, SAFETY};
use super::run::{pass_limits, ray_chunk, storage_init, Passes, RaySample, TOO_LARGE};
use crate::approx::contract::{STACK_DEPTH, STACK_SIZE};
use crate::approx::layout::{bvh_depth, gpu_nodes, GpuBvhNode};
use crate::approx::shader::ShaderProgram;
use crate::approx::GpuContext;
use crate::error::{PgtError, Result};
use crate::reference::budget::gaussian as share;
use crate::reference::gaussian::GaussianRenderer;
use crate::reference::Integrator;
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use wgpu::BufferUsages as Usage;

/// `shaders/reference_gaussian.wgsl`.
pub const GAUSSIAN_WGSL: &str = include_str!("../../../shaders/reference_gaussian.wgsl");

/// The entry point of the Gaussian GPU reference.
pub const ENTRY_POINT: &str = "gaussian_main";

/// The most windows one ray holds at once (a batch): the kept windows open at one depth; a ray
/// with more open at some depth is not converged. A ray takes any number in all, batch by batch.
pub const WINDOWS_MAX: u32 = 256;
/// Segments the quadrature's stack holds (a piece halved this many times at most, less one).
pub const QSTACK: u32 = 48;
/// Invocations per workgroup (one ray each, 1D).
pub const WORKGROUP: u32 = 64;
/// A t beyond every cut.
const HUGE: f64 = 1e300;

/// `gauss_data`: per Gaussian its centre (3), the rows of M = S⁻¹Rᵀ (9, S the standard
/// deviations), σᵢ, the emitted colour (3) and M's Frobenius norm, as f64.
pub const GAUSS_STRIDE: usize = 17;
pub const G_MATRIX: usize = 3;
pub const G_SIGMA: usize = 12;
pub const G_COLOR: usize = 13;
pub const G_FROBENIUS: usize = 16;

/// `scene_data`: the rays' origin, that origin relative to the camera (the BVH boxes are
/// camera-relative), the background, M (per channel max(max k·Cᵢ, L_bg)), tol, the cut-off k,
/// how far the rays' computed unit directions may lie from the exact ones and the far depth (of
/// the Gaussians a ray passes beyond k σ).
pub const GS_ORIGIN: usize = 0;
pub const GS_RELATIVE_ORIGIN: usize = 3;
pub const GS_BACKGROUND: usize = 6;
pub const GS_BOUND: usize = 9;
pub const GS_TOL: usize = 12;
pub const GS_CUTOFF: usize = 13;
pub const GS_DIRECTION_ERROR: usize = 14;
pub const GS_FAR_DEPTH: usize = 15;
pub const GS_LEN: usize = 16;

/// `state`, per ray: radiance (3), its rounding bound (3), the bounded deviations' half-widths
/// (3), the quadrature's estimate (3), the ray stop's half (3), T, T's relative error bound,
/// the start of the next piece, the pieces' depth uncertainty, the status, whether the
/// quadrature fell short, the depth left out, the profiles' uncertainty, the windows' span,
/// the candidates' and the kept windows' counts, the ray's phase (`GPHASE_*`) and a bound on
/// the density on the ray of the Gaussians outside their windows, and what the shifts of t*
/// may change behind a ray stop per unit of transmittance.
pub const GST_STRIDE: usize = 29;
pub const GST_RADIANCE: usize = 0;
pub const GST_ROUNDING: usize = 3;
pub const GST_BOUNDED: usize = 6;
pub const GST_QUADRATURE: usize = 9;
pub const GST_RAY_STOP: usize = 12;
pub const GST_TRANSMITTANCE: usize = 15;
pub const GST_TRANSMITTANCE_REL: usize = 16;
pub const GST_A: usize = 17;
pub const GST_DEPTH: usize = 18;
pub const GST_STATUS: usize = 19;
pub const GST_UNCONVERGED: usize = 20;
pub const GST_LEFT_OUT: usize = 21;
pub const GST_PERT: usize = 22;
pub const GST_SPAN: usize = 23;
pub const GST_COUNT: usize = 24;
pub const GST_KEPT: usize = 25;
pub const GST_PHASE: usize = 26;
pub const GST_EDGE: usize = 27;
pub const GST_REST_SHIFT: usize = 28;

/// A ray's status in `state`.
pub const GSTATUS_RUNNING: u32 = 0;
pub const GSTATUS_DONE: u32 = 1;
pub const GSTATUS_OVERFLOW: u32 = 2;
pub const GSTATUS_LOOP_LIMITED: u32 = 3;

/// A running ray's phase: counting its candidates, summing what its windows leave out, taking
/// its pieces batch by batch (each phase a traversal of its own, so that a pass holds it).
pub const GPHASE_COUNT: u32 = 0;
pub const GPHASE_SUM: u32 = 1;
pub const GPHASE_PIECES: u32 = 2;

const _: () = assert!(G_FROBENIUS < GAUSS_STRIDE && GS_FAR_DEPTH < GS_LEN);
const _: () = assert!(GST_REST_SHIFT < GST_STRIDE);

/// The uniform `params`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct GaussParams {
    /// Rays in this dispatch.
    pub ray_count: u32,
    pub gaussian_count: u32,
    /// Loop iterations after which a ray stops at the end of a piece and waits for the next
    /// pass.
    pub pass_yield: u32,
    /// Loop iterations of one pass beyond which a ray is reported (lavapipe's loop limit).
    pub loop_budget: u32,
}

/// (binding, name, address space, WGSL type) of group 0.
pub const BINDINGS: [(u32, &str, &str, &str); 8] = [
    (0, "params", "uniform", "GaussParams"),
    (1, "scene_data", "storage, read", "array<f64>"),
    (2, "gauss_data", "storage, read", "array<f64>"),
    (3, "nodes", "storage, read", "array<BvhNode>"),
    (4, "leaf_indices", "storage, read", "array<u32>"),
    (5, "rays", "storage, read", "array<f64>"),
    (6, "state", "storage, read_write", "array<f64>"),
    (7, "counters", "storage, read_write", "GaussCounters"),
];

/// The declarations the shader takes from Rust.
pub fn declarations() -> String {
    let u32s: [(&str, usize); 44] = [
        ("GR_WINDOWS_MAX", WINDOWS_MAX as usize),
        ("GR_QSTACK", QSTACK as usize),
        ("GR_WORKGROUP", WORKGROUP as usize),
        ("STACK_SIZE", STACK_SIZE as usize),
        ("GR_GAUSS_STRIDE", GAUSS_STRIDE),
        ("GR_G_MATRIX", G_MATRIX),
        ("GR_G_SIGMA", G_SIGMA),
        ("GR_G_COLOR", G_COLOR),
        ("GR_G_FROBENIUS", G_FROBENIUS),
        ("GS_ORIGIN", GS_ORIGIN),
        ("GS_RELATIVE_ORIGIN", GS_RELATIVE_ORIGIN),
        ("GS_BACKGROUND", GS_BACKGROUND),
        ("GS_BOUND", GS_BOUND),
        ("GS_TOL", GS_TOL),
        ("GS_CUTOFF", GS_CUTOFF),
        ("GS_DIRECTION_ERROR", GS_DIRECTION_ERROR),
        ("GS_FAR_DEPTH", GS_FAR_DEPTH),
        ("GST_STRIDE", GST_STRIDE),
        ("GST_RADIANCE", GST_RADIANCE),
        ("GST_ROUNDING", GST_ROUNDING),
        ("GST_BOUNDED", GST_BOUNDED),
        ("GST_QUADRATURE", GST_QUADRATURE),
        ("GST_RAY_STOP", GST_RAY_STOP),
        ("GST_TRANSMITTANCE", GST_TRANSMITTANCE),
        ("GST_TRANSMITTANCE_REL", GST_TRANSMITTANCE_REL),
        ("GST_A", GST_A),
        ("GST_DEPTH", GST_DEPTH),
        ("GST_STATUS", GST_STATUS),
        ("GST_UNCONVERGED", GST_UNCONVERGED),
        ("GST_LEFT_OUT", GST_LEFT_OUT),
        ("GST_PERT", GST_PERT),
        ("GST_SPAN", GST_SPAN),
        ("GST_COUNT", GST_COUNT),
        ("GST_KEPT", GST_KEPT),
        ("GST_PHASE", GST_PHASE),
        ("GST_EDGE", GST_EDGE),
        ("GST_REST_SHIFT", GST_REST_SHIFT),
        ("GPHASE_COUNT", GPHASE_COUNT as usize),
        ("GPHASE_SUM", GPHASE_SUM as usize),
        ("GPHASE_PIECES", GPHASE_PIECES as usize),
        ("GSTATUS_RUNNING", GSTATUS_RUNNING as usize),
        ("GSTATUS_DONE", GSTATUS_DONE as usize),
        ("GSTATUS_OVERFLOW", GSTATUS_OVERFLOW as usize),
        ("GSTATUS_LOOP_LIMITED", GSTATUS_LOOP_LIMITED as usize),
    ];
    let f64s: [(&str, f64); 11] = [
        ("GR_SAFETY", SAFETY),
        ("REF_HUGE_G", HUGE),
        ("GR_EXP_ULPS", EXP_ULPS),
        ("GR_EXPM1_ULPS", EXPM1_ULPS),
        ("GR_ERFC_ULPS", ERFC_ULPS),
        ("GR_ERFC_NORMAL", ERFC_NORMAL),
        ("GR_FAINT", share::FAINT),
        ("GR_TAILS", share::TAILS),
        ("GR_BOUNDED", share::BOUNDED),
        ("GR_QUADRATURE", share::QUADRATURE),
        ("GR_RAY_STOP", share::RAY_STOP),
    ];
    generated_declarations(
        "src/reference/gpu/gaussian.rs",
        &u32s,
        &f64s,
        "struct GaussParams {\n    ray_count: u32,\n    gaussian_count: u32,\n    pass_yield: u32,\n    loop_budget: u32,\n}\n\n\
         struct GaussCounters {\n    running: atomic<u32>,\n}\n\n",
        &BINDINGS,
    )
}

/// The Gaussian GPU reference's program: the declarations, the f64 functions, the shared
/// traversal (`shaders/nearest_events.wgsl`), the renderer.
pub fn program() -> ShaderProgram {
    f64_program(
        "src/reference/gpu/gaussian.rs",
        declarations(),
        "shaders/reference_gaussian.wgsl",
        GAUSSIAN_WGSL,
    )
}

/// The scene as the program reads it.
struct GaussData {
    scene: Vec<f64>,
    gaussians: Vec<f64>,
    nodes: Vec<GpuBvhNode>,
    indices: Vec<u32>,
    bound: DVec3,
    far_depth: f64,
    count: u32,
}

fn gauss_data(scene: &Scene, origin: DVec3, direction_error: f64) -> Result<GaussData> {
    let renderer = GaussianRenderer::new(scene, Integrator::Adaptive)?;
    let depth = bvh_depth(&renderer.bvh);
    if depth > STACK_DEPTH {
        return Err(PgtError::Gpu(format!(
            "the BVH of the Gaussians is {depth} levels deep, the GPU reference's traversal stack holds {STACK_DEPTH}: render it on the CPU (without --gpu)"
        )));
    }
    let mut gaussians = vec![0.0; renderer.gaussians.len().max(1) * GAUSS_STRIDE];
    for (row, g) in gaussians
        .chunks_exact_mut(GAUSS_STRIDE)
        .zip(&renderer.gaussians)
    {
        row[..3].copy_from_slice(&g.center.to_array());
        let m = g.shape.to_unit_matrix();
        let rows = [m.row(0), m.row(1), m.row(2)];
        for (k, r) in rows.iter().enumerate() {
            row[G_MATRIX + 3 * k..G_MATRIX + 3 * k + 3].copy_from_slice(&r.to_array());
        }
        row[G_SIGMA] = g.sigma;
        row[G_COLOR..G_COLOR + 3].copy_from_slice(&g.emitted.to_array());
        let frobenius = rows.iter().map(|r| r.length_squared()).sum::<f64>().sqrt();
        row[G_FROBENIUS] = frobenius * (1.0 + 1e-12);
    }
    let camera = scene.camera.position;
    let nodes = gpu_nodes(&renderer.bvh, camera);
    let mut data = vec![0.0; GS_LEN];
    data[GS_ORIGIN..GS_ORIGIN + 3].copy_from_slice(&origin.to_array());
    let relative = origin - camera;
    data[GS_RELATIVE_ORIGIN..GS_RELATIVE_ORIGIN + 3].copy_from_slice(&relative.to_array());
    data[GS_BACKGROUND..GS_BACKGROUND + 3].copy_from_slice(&renderer.background.to_array());
    data[GS_BOUND..GS_BOUND + 3].copy_from_slice(&renderer.bound.to_array());
    data[GS_TOL] = renderer.tol;
    data[GS_CUTOFF] = renderer.cutoff;
    data[GS_DIRECTION_ERROR] = direction_error;
    data[GS_FAR_DEPTH] = renderer.far_depth;
    let indices = if renderer.bvh.indices.is_empty() {
        vec![0]
    } else {
        renderer.bvh.indices.clone()
    };
    Ok(GaussData {
        scene: data,
        gaussians,
        nodes,
        indices,
        bound: renderer.bound,
        far_depth: renderer.far_depth,
        count: renderer.gaussians.len() as u32,
    })
}

/// A ray's err from its state (docs/design.md §12): the CPU's parts (ray stop, bounded
/// deviations, quadrature, M·(1 − e^{−Δ}) for the depth left out) plus M per unit of the
/// profiles' and pieces' depth uncertainty and twice the composite's rounding; at most
/// |L| + M per channel, which holds for any L since the truth lies in [0, M], and that where
/// the ray did not finish.
pub fn ray_error(ray: &[f64], bound: DVec3, far_depth: f64) -> DVec3 {
    let v = |at: usize| DVec3::new(ray[at], ray[at + 1], ray[at + 2]);
    let trivial = (v(GST_RADIANCE).abs() + bound) * (1.0 + 4.0 * U);
    if ray[GST_STATUS] as u32 != GSTATUS_DONE {
        return trivial;
    }
    let delta = (far_depth + ray[GST_LEFT_OUT]) * (1.0 + 1e-10);
    let left_out = bound * -(-delta).exp_m1() * (1.0 + 1e-12);
    let uncertain = 2.0 * SAFETY * (ray[GST_DEPTH] + ray[GST_PERT]);
    let device = bound * uncertain + 2.0 * v(GST_ROUNDING);
    let total = v(GST_RAY_STOP) + v(GST_BOUNDED) + v(GST_QUADRATURE) + left_out + device;
    (total * (1.0 + 16.0 * U)).min(trivial)
}

/// One ray's answer and whether it converged.
pub struct GaussTraced {
    pub samples: Vec<RaySample>,
    /// Per ray, whether it fell short (unfinished, err |L| + M; or a quadrature over its share).
    pub unconverged: Vec<bool>,
    pub passes: u32,
}

/// The rays from `origin` along `directions` through the Gaussian `scene` with the GPU
/// reference (as `run::trace` for spheres).
pub fn trace(
    ctx: &GpuContext,
    scene: &Scene,
    origin: DVec3,
    directions: &[DVec3],
    direction_error: f64,
) -> Result<GaussTraced> {
    check_f64(ctx)?;
    let data = gauss_data(scene, origin, direction_error)?;
    let pipeline = compile(ctx, &program(), "Gaussian GPU reference", ENTRY_POINT)?;
    ctx.check_buffers(
        &[
            (
                "Gaussian",
                std::mem::size_of_val(&data.gaussians[..]) as u64,
            ),
            ("BVH node", std::mem::size_of_val(&data.nodes[..]) as u64),
            (
                "leaf index",
                std::mem::size_of_val(&data.indices[..]) as u64,
            ),
        ],
        TOO_LARGE,
    )?;
    let chunk = ray_chunk(ctx, GST_STRIDE);
    let buffers = ctx.checked("uploading the scene to the Gaussian GPU reference", || {
        SceneGpu::new(ctx, &data)
    })?;
    let mut out = GaussTraced {
        samples: Vec::with_capacity(directions.len()),
        unconverged: Vec::with_capacity(directions.len()),
        passes: 0,
    };
    for part in directions.chunks(chunk) {
        let (mut state, passes) = run_chunk(ctx, &pipeline, &buffers, part)?;
        out.passes = out.passes.max(passes);
        if ctx.adapter.is_cpu {
            taint_loop_limited_workgroups(&mut state);
        }
        for ray in state.chunks_exact(GST_STRIDE) {
            let radiance = DVec3::new(
                ray[GST_RADIANCE],
                ray[GST_RADIANCE + 1],
                ray[GST_RADIANCE + 2],
            );
            let error = ray_error(ray, data.bound, data.far_depth);
            out.unconverged
                .push(ray[GST_STATUS] as u32 != GSTATUS_DONE || ray[GST_UNCONVERGED] != 0.0);
            out.samples.push(RaySample { radiance, error });
        }
    }
    Ok(out)
}

/// On a Cpu adapter (lavapipe), every ray of a workgroup in which one ray ran past the loop
/// budget is marked loop-limited: lavapipe counts the loop iterations of SIMD lanes together
/// and, past its limit, ends the loops of all of them with wrong values, so a ray that finished
/// beside one that did not may be wrong without knowing it (docs/design.md §12). Such rays get
/// err = |L| + M and are counted not converged.
fn taint_loop_limited_workgroups(state: &mut [f64]) {
    for group in state.chunks_mut(GST_STRIDE * WORKGROUP as usize) {
        let limited = group
            .chunks_exact(GST_STRIDE)
            .any(|ray| ray[GST_STATUS] as u32 == GSTATUS_LOOP_LIMITED);
        if limited {
            for ray in group.chunks_exact_mut(GST_STRIDE) {
                ray[GST_STATUS] = f64::from(GSTATUS_LOOP_LIMITED);
            }
        }
    }
}

/// The buffers every chunk of rays shares.
struct SceneGpu {
    scene: wgpu::Buffer,
    gaussians: wgpu::Buffer,
    nodes: wgpu::Buffer,
    indices: wgpu::Buffer,
    gaussian_count: u32,
}

impl SceneGpu {
    fn new(ctx: &GpuContext, data: &GaussData) -> SceneGpu {
        let s = Usage::STORAGE;
        SceneGpu {
            scene: storage_init(ctx, "pgt gaussian scene", &data.scene, s),
            gaussians: storage_init(ctx, "pgt gaussian data", &data.gaussians, s),
            nodes: storage_init(ctx, "pgt gaussian nodes", &data.nodes, s),
            indices: storage_init(ctx, "pgt gaussian leaf indices", &data.indices, s),
            gaussian_count: data.count,
        }
    }
}

/// The per-ray state a chunk starts with: T = 1, at t = 0, running.
fn initial_state(rays: usize) -> Vec<f64> {
    let mut state = vec![0.0; rays * GST_STRIDE];
    for ray in state.chunks_exact_mut(GST_STRIDE) {
        ray[GST_TRANSMITTANCE] = 1.0;
    }
    state
}

/// Runs passes over one chunk of rays until every ray has finished (or the passes run out: the
/// state is then taken as it stands); the final state and the number of passes.
fn run_chunk(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    gpu: &SceneGpu,
    directions: &[DVec3],
) -> Result<(Vec<f64>, u32)> {
    let (pass_yield, loop_budget) = pass_limits(ctx);
    let params = GaussParams {
        ray_count: directions.len() as u32,
        gaussian_count: gpu.gaussian_count,
        pass_yield,
        loop_budget,
    };
    let scene = [&gpu.scene, &gpu.gaussians, &gpu.nodes, &gpu.indices];
    let run = Passes {
        what: "Gaussian GPU reference",
        pipeline,
        scene: &scene,
    };
    let (state, passes, _) = run.run(ctx, params, directions, initial_state(directions.len()))?;
    Ok((state, passes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gaussian_program_validates_with_f64() {
        let caps = naga::valid::Capabilities::FLOAT64;
        if let Err(e) = program().validate_with(caps) {
            panic!("{e}");
        }
    }
}
