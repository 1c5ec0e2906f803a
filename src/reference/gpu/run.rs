//! The GPU reference's buffers, passes and read-back (docs/design.md §12).

use super::pipeline::{check_f64, compile};
use super::program::{
    program, RefParams, ELLIPSOID_STRIDE, ENTRY_POINT, PARTICLE_STRIDE, P_COLOR, P_RADIUS, P_SHAPE,
    P_SIGMA, SCENE_BACKGROUND, SCENE_CMAX, SCENE_DIRECTION_ERROR, SCENE_LEN, SCENE_ORIGIN,
    SCENE_RELATIVE_ORIGIN, SCENE_SIGMA_TOTAL, STATE_DEPTH, STATE_ERROR, STATE_RADIANCE,
    STATE_STATUS, STATE_STRIDE, STATE_TRANSMITTANCE, STATE_T_LAST, STATUS_DONE,
    STATUS_INSIDE_OVERFLOW, STATUS_LOOP_LIMITED, WORKGROUP,
};
use super::ray_error;
use crate::approx::contract::{LOOP_BUDGET, STACK_DEPTH};
use crate::approx::dispatch::read_back;
use crate::approx::layout::SceneBuffers;
use crate::approx::GpuContext;
use crate::error::{PgtError, Result};
use crate::optics::source::SourceParams;
use crate::scene::Scene;
use glam::DVec3;
use std::mem::size_of_val;
use wgpu::util::DeviceExt;
use wgpu::BufferUsages as Usage;

/// One ray's answer: its radiance and the bound on its distance from the truth (f64, before
/// the storage as float32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaySample {
    pub radiance: DVec3,
    pub error: DVec3,
}

/// What [`trace`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Traced {
    /// One per direction, in order.
    pub samples: Vec<RaySample>,
    /// The most passes a chunk of rays took (the rays' work split by the loop budget).
    pub passes: u32,
}

/// Passes after which a ray that has not finished is an error (each pass takes at least one
/// batch of events of every unfinished ray, so only a scene with very many events per ray
/// reaches it).
pub(super) const MAX_PASSES: u32 = 100_000;

/// The scene as the GPU reference reads it: f64 particles and ellipsoids, the approximations'
/// BVH, and the per-scene values.
struct SceneData {
    scene: Vec<f64>,
    particles: Vec<f64>,
    ellipsoids: Vec<f64>,
    buffers: SceneBuffers,
    cmax: DVec3,
}

fn scene_data(scene: &Scene, origin: DVec3, direction_error: f64) -> Result<SceneData> {
    let bvh = scene.build_gas_bvh();
    let buffers = SceneBuffers::new(scene, &bvh);
    if buffers.bvh_depth > STACK_DEPTH {
        return Err(PgtError::Gpu(format!(
            "the BVH is {} levels deep, the GPU reference's traversal stack holds {STACK_DEPTH}",
            buffers.bvh_depth
        )));
    }
    let render = &scene.render;
    let source = SourceParams::new(
        render.light_weight,
        scene.lights.len(),
        render.emission_weight,
    );
    let k = render.model.emission_factor(&source);
    let mut particles = vec![0.0; scene.particles.len().max(1) * PARTICLE_STRIDE];
    let mut ellipsoids = Vec::new();
    let mut cmax = scene.render.background;
    let mut sigma_total = 0.0;
    for (i, p) in scene.particles.iter().enumerate() {
        let row = &mut particles[i * PARTICLE_STRIDE..(i + 1) * PARTICLE_STRIDE];
        row[..3].copy_from_slice(&p.center.to_array());
        row[P_RADIUS] = p.radius;
        row[P_SIGMA] = if p.sigma.is_finite() { p.sigma } else { -1.0 };
        let color = k * p.color;
        row[P_COLOR..P_COLOR + 3].copy_from_slice(&color.to_array());
        row[P_SHAPE] = match &p.ellipsoid {
            None => -1.0,
            Some(e) => {
                let m = e.to_unit_matrix();
                let rows = [m.row(0), m.row(1), m.row(2)];
                let index = ellipsoids.len() / ELLIPSOID_STRIDE;
                for r in rows {
                    ellipsoids.extend_from_slice(&r.to_array());
                }
                let frobenius = rows.iter().map(|r| r.length_squared()).sum::<f64>().sqrt();
                ellipsoids.push(frobenius * (1.0 + 1e-12));
                index as f64
            }
        };
        if p.sigma > 0.0 {
            cmax = cmax.max(color);
            if p.sigma.is_finite() {
                sigma_total += p.sigma;
            }
        }
    }
    if ellipsoids.is_empty() {
        ellipsoids.resize(ELLIPSOID_STRIDE, 0.0);
    }
    let mut data = vec![0.0; SCENE_LEN];
    data[SCENE_ORIGIN..SCENE_ORIGIN + 3].copy_from_slice(&origin.to_array());
    let relative = origin - scene.camera.position;
    data[SCENE_RELATIVE_ORIGIN..SCENE_RELATIVE_ORIGIN + 3].copy_from_slice(&relative.to_array());
    let background = scene.render.background;
    data[SCENE_BACKGROUND..SCENE_BACKGROUND + 3].copy_from_slice(&background.to_array());
    data[SCENE_CMAX..SCENE_CMAX + 3].copy_from_slice(&cmax.to_array());
    data[SCENE_SIGMA_TOTAL] = sigma_total * (1.0 + 1e-12);
    data[SCENE_DIRECTION_ERROR] = direction_error;
    Ok(SceneData {
        scene: data,
        particles,
        ellipsoids,
        buffers,
        cmax,
    })
}

/// The rays from `origin` along `directions` (unit length, as `Camera::ray_at` makes them, each
/// within `direction_error` of the exact unit vector its truth is defined by:
/// [`super::direction_error`]) through `scene` with the GPU reference: radiance and error bound
/// of each, in order.
pub fn trace(
    ctx: &GpuContext,
    scene: &Scene,
    origin: DVec3,
    directions: &[DVec3],
    direction_error: f64,
) -> Result<Traced> {
    check_f64(ctx)?;
    super::check_scene_size(ctx, scene)?;
    let data = scene_data(scene, origin, direction_error)?;
    let pipeline = compile(ctx, &program(), "GPU reference", ENTRY_POINT)?;
    ctx.check_buffers(
        &[
            ("particle", size_of_val(&data.particles[..]) as u64),
            ("ellipsoid", size_of_val(&data.ellipsoids[..]) as u64),
            ("BVH node", size_of_val(&data.buffers.nodes[..]) as u64),
            (
                "leaf index",
                size_of_val(&data.buffers.leaf_indices[..]) as u64,
            ),
        ],
        TOO_LARGE,
    )?;
    let chunk = ray_chunk(ctx, STATE_STRIDE);
    let scene_buffers = ctx.checked("uploading the scene to the GPU reference", || {
        SceneGpu::new(ctx, &data)
    })?;
    let mut out = Vec::with_capacity(directions.len());
    let mut passes = 0;
    for part in directions.chunks(chunk) {
        let (state, chunk_passes) = run_chunk(ctx, &pipeline, &scene_buffers, part)?;
        passes = passes.max(chunk_passes);
        for ray in state.chunks_exact(STATE_STRIDE) {
            check_finished(ctx, ray[STATE_STATUS] as u32)?;
            let v = |at: usize| DVec3::new(ray[at], ray[at + 1], ray[at + 2]);
            let radiance = v(STATE_RADIANCE);
            out.push(RaySample {
                radiance,
                error: ray_error(v(STATE_ERROR), ray[STATE_DEPTH], radiance, data.cmax),
            });
        }
    }
    Ok(Traced {
        samples: out,
        passes,
    })
}

/// What a user can do with a scene too large for the GPU reference's buffers.
pub(super) const TOO_LARGE: &str =
    "render it on the CPU (without --gpu), or choose an adapter with larger limits (--adapter)";

/// The rays of one chunk of a trace whose per-ray state is `state_stride` f64s: as many as
/// fit the adapter's storage limit with their state and their directions, and one dispatch.
pub(super) fn ray_chunk(ctx: &GpuContext, state_stride: usize) -> usize {
    let per_ray = ((state_stride.max(3)) * 8) as u64;
    let groups = ctx.device.limits().max_compute_workgroups_per_dimension as u64;
    (ctx.storage_limit() / per_ray).clamp(1, groups * WORKGROUP as u64) as usize
}

/// An error naming why a ray did not finish, if it did not.
fn check_finished(ctx: &GpuContext, status: u32) -> Result<()> {
    match status {
        STATUS_DONE => Ok(()),
        STATUS_INSIDE_OVERFLOW => Err(PgtError::Gpu(format!(
            "a ray is inside more than {} particles at once, more than the GPU reference holds: render this scene on the CPU (without --gpu)",
            super::program::INSIDE_MAX
        ))),
        STATUS_LOOP_LIMITED => Err(PgtError::Gpu(format!(
            "one batch of a ray's events took more than the {LOOP_BUDGET} loop iterations {} allows in a pass: render this scene on the CPU (without --gpu)",
            ctx.adapter.name
        ))),
        other => Err(PgtError::Gpu(format!(
            "a ray ended the GPU reference with status {other}"
        ))),
    }
}

/// The buffers every chunk of rays shares.
struct SceneGpu {
    scene: wgpu::Buffer,
    particles: wgpu::Buffer,
    ellipsoids: wgpu::Buffer,
    nodes: wgpu::Buffer,
    indices: wgpu::Buffer,
    particle_count: u32,
}

pub(super) fn storage_init<T: bytemuck::Pod>(
    ctx: &GpuContext,
    label: &str,
    data: &[T],
    usage: Usage,
) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(data),
            usage,
        })
}

impl SceneGpu {
    fn new(ctx: &GpuContext, data: &SceneData) -> SceneGpu {
        let s = Usage::STORAGE;
        let indices: &[u32] = if data.buffers.leaf_indices.is_empty() {
            &[0]
        } else {
            &data.buffers.leaf_indices
        };
        SceneGpu {
            scene: storage_init(ctx, "pgt reference scene", &data.scene, s),
            particles: storage_init(ctx, "pgt reference particles", &data.particles, s),
            ellipsoids: storage_init(ctx, "pgt reference ellipsoids", &data.ellipsoids, s),
            nodes: storage_init(ctx, "pgt reference nodes", &data.buffers.nodes, s),
            indices: storage_init(ctx, "pgt reference leaf indices", indices, s),
            particle_count: data.buffers.leaf_indices.len() as u32,
        }
    }
}

/// The per-ray state a chunk starts with: T = 1, before every event (t = −1), running.
fn initial_state(rays: usize) -> Vec<f64> {
    let mut state = vec![0.0; rays * STATE_STRIDE];
    for ray in state.chunks_exact_mut(STATE_STRIDE) {
        ray[STATE_TRANSMITTANCE] = 1.0;
        ray[STATE_T_LAST] = -1.0;
    }
    state
}

/// Runs passes over one chunk of rays until every ray has finished; the final state and the
/// number of passes.
fn run_chunk(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    gpu: &SceneGpu,
    directions: &[DVec3],
) -> Result<(Vec<f64>, u32)> {
    let (pass_yield, loop_budget) = pass_limits(ctx);
    let params = RefParams {
        ray_count: directions.len() as u32,
        particle_count: gpu.particle_count,
        pass_yield,
        loop_budget,
    };
    let scene = [
        &gpu.scene,
        &gpu.particles,
        &gpu.ellipsoids,
        &gpu.nodes,
        &gpu.indices,
    ];
    let run = Passes {
        what: "GPU reference",
        pipeline,
        scene: &scene,
    };
    match run.run(ctx, params, directions, initial_state(directions.len()))? {
        (state, passes, true) => Ok((state, passes)),
        _ => Err(PgtError::Gpu(format!(
            "rays of the GPU reference still unfinished after {MAX_PASSES} passes"
        ))),
    }
}

/// A pass's yield (the loop iterations after which a ray stops for the pass) and loop budget:
/// lavapipe's loop limit on a CPU adapter, none elsewhere.
pub(super) fn pass_limits(ctx: &GpuContext) -> (u32, u32) {
    if ctx.adapter.is_cpu {
        (LOOP_BUDGET / 2, LOOP_BUDGET)
    } else {
        (1 << 20, u32::MAX)
    }
}

/// A GPU reference program run in passes over chunks of rays: its bindings are the params
/// (uniform), the `scene` buffers in order, then the rays, the per-ray state (f64) and four
/// counters, the first of which a pass sets while rays are still running.
pub(super) struct Passes<'a> {
    /// The program's name in messages.
    pub what: &'a str,
    pub pipeline: &'a wgpu::ComputePipeline,
    pub scene: &'a [&'a wgpu::Buffer],
}

impl Passes<'_> {
    /// Runs passes over `directions` from the per-ray state `initial` until every ray has
    /// finished or [`MAX_PASSES`]: the final state, the passes and whether every ray finished.
    pub fn run<P: bytemuck::Pod>(
        &self,
        ctx: &GpuContext,
        params: P,
        directions: &[DVec3],
        initial: Vec<f64>,
    ) -> Result<(Vec<f64>, u32, bool)> {
        let what = self.what;
        let device = &ctx.device;
        let rays: Vec<f64> = directions.iter().flat_map(|d| d.to_array()).collect();
        let state_bytes = (initial.len() * 8) as u64;
        ctx.check_buffers(
            &[
                ("ray", size_of_val(&rays[..]) as u64),
                ("per-ray state", state_bytes),
            ],
            TOO_LARGE,
        )?;
        let (bind_group, state, counters, counters_read, state_read) =
            ctx.checked(&format!("uploading the {what}'s rays"), || {
                let params = storage_init(ctx, "pgt reference params", &[params], Usage::UNIFORM);
                let rays = storage_init(ctx, "pgt reference rays", &rays, Usage::STORAGE);
                let state = storage_init(
                    ctx,
                    "pgt reference state",
                    &initial,
                    Usage::STORAGE | Usage::COPY_SRC,
                );
                let counters = storage_init(
                    ctx,
                    "pgt reference counters",
                    &[0u32; 4],
                    Usage::STORAGE | Usage::COPY_SRC | Usage::COPY_DST,
                );
                let read = |label, size| {
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size,
                        usage: Usage::MAP_READ | Usage::COPY_DST,
                        mapped_at_creation: false,
                    })
                };
                let mut buffers = vec![&params];
                buffers.extend(self.scene);
                buffers.extend([&rays, &state, &counters]);
                let entries: Vec<wgpu::BindGroupEntry> = buffers
                    .iter()
                    .enumerate()
                    .map(|(i, b)| wgpu::BindGroupEntry {
                        binding: i as u32,
                        resource: b.as_entire_binding(),
                    })
                    .collect();
                let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("pgt reference"),
                    layout: &self.pipeline.get_bind_group_layout(0),
                    entries: &entries,
                });
                let counters_read = read("pgt reference counters read-back", 16);
                let state_read = read("pgt reference state read-back", state_bytes);
                (bind_group, state, counters, counters_read, state_read)
            })?;
        let groups = (directions.len() as u32).div_ceil(WORKGROUP);
        let (mut passes, mut finished) = (0, false);
        while passes < MAX_PASSES && !finished {
            passes += 1;
            ctx.checked(&format!("running the {what}"), || {
                ctx.queue
                    .write_buffer(&counters, 0, bytemuck::cast_slice(&[0u32; 4]));
                let mut encoder = device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(self.pipeline);
                    pass.set_bind_group(0, &bind_group, &[]);
                    pass.dispatch_workgroups(groups, 1, 1);
                }
                encoder.copy_buffer_to_buffer(&counters, 0, &counters_read, 0, 16);
                ctx.queue.submit([encoder.finish()]);
            })?;
            let running: Vec<u32> =
                bytemuck::pod_collect_to_vec(&read_back(ctx, &counters_read, 16)?);
            finished = running[0] == 0;
        }
        ctx.checked(&format!("reading the {what} back"), || {
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&state, 0, &state_read, 0, state_bytes);
            ctx.queue.submit([encoder.finish()]);
        })?;
        let state = bytemuck::pod_collect_to_vec(&read_back(ctx, &state_read, state_bytes)?);
        Ok((state, passes, finished))
    }
}
