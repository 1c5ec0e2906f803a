//! Running a program on the GPU, in four parts: a [`Pipeline`] (the compiled method, built once
//! and reusable for any number of scenes and parameter values, e.g. across a sweep), a scene
//! upload ([`Upload`]), the pass schedule ([`PassSchedule`]: lavapipe's loop budget, pure logic
//! with unit tests that need no GPU) and the read-back of the image. Timing by timestamp
//! queries where the adapter has them, wall time otherwise.

use super::context::{human_bytes, GpuContext};
use super::contract::{
    BindingKind, BINDINGS, LOOP_BUDGET, OVERRIDE_HAS_ELLIPSOIDS, WORKGROUP_SIDE,
};
use super::layout::{
    GpuBvhNode, GpuEllipsoid, GpuFrame, GpuLight, GpuParticle, GpuSplat, GpuStats, SceneBuffers,
};
use super::shader::{ShaderProgram, ENTRY_POINT};
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use crate::scene::Scene;
use std::sync::OnceLock;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// Work items (for `thesis`: (particle, sample) pairs) of the first pass on a Cpu adapter
/// (lavapipe): each pair costs one shadow ray per light, each shadow ray some hundred loop
/// iterations in a large scene, and lavapipe allows `LOOP_LIMIT` per invocation in all.
pub const PAIRS_PER_PASS_CPU: u32 = 8;

/// How the GPU time was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// Timestamp queries around the compute pass (GPU time only).
    Timestamps,
    /// Wall time from submission to completion (includes driver overhead).
    Wall,
}

/// What one run produced.
#[derive(Debug, Clone)]
pub struct DispatchOutput {
    pub image: RgbImage,
    pub gpu_seconds: f64,
    pub timing: Timing,
    /// Pixels whose hit list overflowed (`MAX_HITS`), most in any pass.
    pub hit_overflows: u32,
    /// Pixels that reached the loop budget in some pass (most in any pass).
    pub loop_limited: u32,
    /// Dispatches it took.
    pub passes: u32,
}

/// What to do after a pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassVerdict {
    /// The pass took too many loop iterations: restore the image and redo it with fewer items.
    Redo,
    /// Accept it and run the next range.
    Next,
    /// Accept it; the image is complete.
    Done,
}

/// Which work items each pass computes. A method that splits its work (thesis: lit samples)
/// raises `more_work`; the next pass takes the next range of items. On lavapipe (a Cpu adapter)
/// all loops of an invocation together may run `LOOP_LIMIT` iterations, so a pass there takes a
/// few items: a pass whose busiest pixel counted more than [`LOOP_BUDGET`] is undone and redone
/// with half the items; a light pass (under a quarter of the budget) doubles them. A real GPU
/// takes all items in one pass.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PassSchedule {
    pairs_per_pass: u32,
    begin: u32,
    adaptive: bool,
}

impl PassSchedule {
    /// The schedule for a Cpu adapter (`cpu`: adaptive, from [`PAIRS_PER_PASS_CPU`]) or a GPU.
    pub fn new(cpu: bool) -> PassSchedule {
        PassSchedule {
            pairs_per_pass: if cpu { PAIRS_PER_PASS_CPU } else { u32::MAX },
            begin: 0,
            adaptive: cpu,
        }
    }

    /// [pair_begin, pair_end) of the next pass.
    pub fn range(&self) -> (u32, u32) {
        (self.begin, self.begin.saturating_add(self.pairs_per_pass))
    }

    /// Decides after a pass over [`Self::range`], from whether any pixel has more work and the
    /// most loop iterations any pixel counted.
    pub fn after_pass(&mut self, more_work: bool, max_loop_iterations: u32) -> PassVerdict {
        let (begin, end) = self.range();
        let split = more_work || begin > 0;
        if self.adaptive {
            if split && max_loop_iterations > LOOP_BUDGET && self.pairs_per_pass > 1 {
                self.pairs_per_pass = (self.pairs_per_pass / 2).max(1);
                return PassVerdict::Redo;
            }
            if max_loop_iterations < LOOP_BUDGET / 4 && self.pairs_per_pass < u32::MAX / 2 {
                self.pairs_per_pass *= 2;
            }
        }
        if !more_work || end == u32::MAX {
            return PassVerdict::Done;
        }
        self.begin = end;
        PassVerdict::Next
    }
}

/// A compiled method: shader module, bind group layout (from [`BINDINGS`]) and its compute
/// pipelines, one for scenes of spheres and one for scenes with ellipsoids
/// ([`OVERRIDE_HAS_ELLIPSOIDS`]), each compiled when a scene first needs it. Build it once and
/// [`run`] it on any number of scenes and parameter values.
pub struct Pipeline {
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    layout: wgpu::BindGroupLayout,
    /// [spheres only, with ellipsoids].
    variants: [OnceLock<wgpu::ComputePipeline>; 2],
}

impl std::fmt::Debug for Pipeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pipeline").finish_non_exhaustive()
    }
}

impl Pipeline {
    /// Compiles `program` (already validated with [`ShaderProgram::validate`]).
    pub fn new(ctx: &GpuContext, program: &ShaderProgram) -> Result<Pipeline> {
        let device = &ctx.device;
        let module = ctx.checked("compiling the WGSL", || {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("pgt method"),
                source: wgpu::ShaderSource::Wgsl(program.source().into()),
            })
        })?;
        // An explicit layout: a user's method need not use every binding.
        let entries: Vec<wgpu::BindGroupLayoutEntry> = BINDINGS
            .iter()
            .map(|b| wgpu::BindGroupLayoutEntry {
                binding: b.index,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: match b.kind {
                        BindingKind::Uniform => wgpu::BufferBindingType::Uniform,
                        BindingKind::StorageRead => {
                            wgpu::BufferBindingType::Storage { read_only: true }
                        }
                        BindingKind::StorageReadWrite => {
                            wgpu::BufferBindingType::Storage { read_only: false }
                        }
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        ctx.checked("creating the compute pipeline", || {
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("pgt scene"),
                entries: &entries,
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("pgt"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            Pipeline {
                module,
                pipeline_layout,
                layout,
                variants: [OnceLock::new(), OnceLock::new()],
            }
        })
    }

    /// The compute pipeline for a scene with (`true`) or without ellipsoids, compiled on first
    /// use, and whether this call compiled it (its first dispatch is then still to come).
    fn variant(
        &self,
        ctx: &GpuContext,
        ellipsoids: bool,
    ) -> Result<(&wgpu::ComputePipeline, bool)> {
        let slot = &self.variants[ellipsoids as usize];
        if let Some(p) = slot.get() {
            return Ok((p, false));
        }
        let constants = [(OVERRIDE_HAS_ELLIPSOIDS, if ellipsoids { 1.0 } else { 0.0 })];
        let compiled = ctx.checked("creating the compute pipeline", || {
            ctx.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("pgt method"),
                    layout: Some(&self.pipeline_layout),
                    module: &self.module,
                    entry_point: Some(ENTRY_POINT),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                })
        })?;
        // Another thread may have compiled it meanwhile: either copy serves.
        Ok((slot.get_or_init(|| compiled), true))
    }
}

/// The largest storage buffer the adapter binds and allocates (bytes):
/// [`GpuContext::storage_limit`].
pub fn storage_limit(ctx: &GpuContext) -> u64 {
    ctx.storage_limit()
}

/// What a user can do with a scene too large for the approximations' buffers.
pub const TOO_LARGE: &str =
    "render fewer particles, or choose an adapter with larger limits (--adapter)";

/// Checks the buffers whose sizes the particle count fixes (particles and ellipsoids) against
/// the adapter's limit before the BVH and the splatting methods' tile lists are built, which
/// for 10⁷ particles take a minute and gigabytes; [`Upload::new`] checks every buffer again
/// once their sizes are known.
pub fn check_scene_size(ctx: &GpuContext, scene: &Scene) -> Result<()> {
    let ellipsoids = scene
        .particles
        .iter()
        .filter(|p| p.ellipsoid.is_some())
        .count();
    ctx.check_buffers(
        &[
            ("particle", bytes::<GpuParticle>(scene.particles.len())),
            ("ellipsoid", bytes::<GpuEllipsoid>(ellipsoids)),
        ],
        TOO_LARGE,
    )
}

/// Bytes of one output pixel (a `vec4<f32>`).
const PIXEL_BYTES: u64 = 16;

/// Splits a `width`×`height` image into bands of whole rows, (row_begin, row_count), whose
/// output fits in `limit` bytes: one band where the image fits, else as many rows as fit,
/// rounded down to whole workgroups. Each pixel's result does not depend on the band it is in,
/// so a banded image is bit-identical to an unbanded one. An error only where one row alone
/// exceeds the limit.
pub fn bands(width: u32, height: u32, limit: u64) -> Result<Vec<(u32, u32)>> {
    let row_bytes = width as u64 * PIXEL_BYTES;
    let fit = limit / row_bytes.max(1);
    if fit == 0 {
        return Err(PgtError::Gpu(format!(
            "one image row of {width} pixels needs {}, the adapter allows {} per storage buffer",
            human_bytes(row_bytes),
            human_bytes(limit)
        )));
    }
    let side = WORKGROUP_SIDE as u64;
    let rows = if fit >= side { fit - fit % side } else { fit };
    let rows = rows.min(height.max(1) as u64) as u32;
    Ok((0..height.max(1))
        .step_by(rows as usize)
        .map(|begin| (begin, rows.min(height.max(1) - begin)))
        .collect())
}

/// A storage buffer from a slice; an empty slice still gets one zeroed element (wgpu forbids
/// zero-sized bindings; the shaders read counts from `frame`, never the array length).
fn storage<T: bytemuck::Pod + bytemuck::Zeroable>(
    ctx: &GpuContext,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    let zero = [T::zeroed()];
    let data = if data.is_empty() { &zero[..] } else { data };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

fn bytes<T>(n: usize) -> u64 {
    (n.max(1) * std::mem::size_of::<T>()) as u64
}

const STATS_BYTES: u64 = std::mem::size_of::<GpuStats>() as u64;
const TIMESTAMP_BYTES: u64 = 16;

fn buffer(ctx: &GpuContext, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// The scene's buffers, shared by every band.
struct SceneOnGpu {
    particles: wgpu::Buffer,
    ellipsoids: wgpu::Buffer,
    nodes: wgpu::Buffer,
    indices: wgpu::Buffer,
    lights: wgpu::Buffer,
    stats: wgpu::Buffer,
    splats: wgpu::Buffer,
    tile_entries: wgpu::Buffer,
}

/// One band of rows of the image: its frame uniform, its part of the output, the bind group
/// that joins them to the scene.
struct Band {
    row_begin: u32,
    row_count: u32,
    frame: wgpu::Buffer,
    output: wgpu::Buffer,
    /// A copy of the band before each pass, for [`PassVerdict::Redo`] (Cpu adapters).
    backup: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
    bytes: u64,
    groups: (u32, u32),
}

impl Band {
    fn new(
        ctx: &GpuContext,
        pipeline: &Pipeline,
        scene: &SceneOnGpu,
        frame: &GpuFrame,
        (row_begin, row_count): (u32, u32),
    ) -> Band {
        use wgpu::BufferUsages as U;
        let device = &ctx.device;
        let bytes = frame.width as u64 * row_count as u64 * PIXEL_BYTES;
        let frame_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pgt frame"),
            contents: bytemuck::bytes_of(frame),
            usage: U::UNIFORM | U::COPY_DST,
        });
        let output = buffer(
            ctx,
            "pgt output",
            bytes,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        // In BINDINGS order: frame, particles, nodes, leaf_indices, lights, output, stats,
        // ellipsoids, splats, tile_entries.
        let resources = [
            &frame_buf,
            &scene.particles,
            &scene.nodes,
            &scene.indices,
            &scene.lights,
            &output,
            &scene.stats,
            &scene.ellipsoids,
            &scene.splats,
            &scene.tile_entries,
        ];
        let entries: Vec<wgpu::BindGroupEntry> = BINDINGS
            .iter()
            .zip(&resources)
            .map(|(b, r)| wgpu::BindGroupEntry {
                binding: b.index,
                resource: r.as_entire_binding(),
            })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pgt scene"),
            layout: &pipeline.layout,
            entries: &entries,
        });
        Band {
            row_begin,
            row_count,
            frame: frame_buf,
            backup: ctx
                .adapter
                .is_cpu
                .then(|| buffer(ctx, "pgt output backup", bytes, U::COPY_SRC | U::COPY_DST)),
            output,
            bind_group,
            bytes,
            groups: (
                frame.width.div_ceil(WORKGROUP_SIDE),
                row_count.div_ceil(WORKGROUP_SIDE),
            ),
        }
    }
}

/// A scene on the GPU: its buffers bound to a pipeline's layout, once per band of the image,
/// and the buffers a run writes and reads back.
pub struct Upload {
    bands: Vec<Band>,
    stats: wgpu::Buffer,
    /// Query set and resolve buffer, where the adapter has timestamp queries.
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// Read-back of one band at a time (the largest band's size).
    out_read: wgpu::Buffer,
    stats_read: wgpu::Buffer,
    ts_read: wgpu::Buffer,
}

impl Upload {
    /// Checks the sizes against the adapter's limits, splits the image into bands that fit
    /// and uploads the scene.
    pub fn new(
        ctx: &GpuContext,
        pipeline: &Pipeline,
        scene: &SceneBuffers,
        frame: &GpuFrame,
    ) -> Result<Upload> {
        Upload::with_limit(ctx, pipeline, scene, frame, storage_limit(ctx))
    }

    /// [`Upload::new`] with a per-buffer limit of `limit` bytes (at most the adapter's).
    fn with_limit(
        ctx: &GpuContext,
        pipeline: &Pipeline,
        scene: &SceneBuffers,
        frame: &GpuFrame,
        limit: u64,
    ) -> Result<Upload> {
        let limit = limit.min(storage_limit(ctx));
        ctx.check_buffers_under(
            limit,
            &[
                ("particle", bytes::<GpuParticle>(scene.particles.len())),
                ("ellipsoid", bytes::<GpuEllipsoid>(scene.ellipsoids.len())),
                ("BVH node", bytes::<GpuBvhNode>(scene.nodes.len())),
                ("BVH index", bytes::<u32>(scene.leaf_indices.len())),
                ("light", bytes::<GpuLight>(scene.lights.len())),
                ("splat", bytes::<GpuSplat>(scene.splats.len())),
                ("tile list", bytes::<u32>(scene.tile_entries.len())),
            ],
            TOO_LARGE,
        )?;
        let rows = bands(frame.width, frame.height, limit)?;
        let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
        let groups = (
            frame.width.div_ceil(WORKGROUP_SIDE),
            rows[0].1.div_ceil(WORKGROUP_SIDE),
        );
        if groups.0 > max_groups || groups.1 > max_groups {
            return Err(PgtError::Gpu(format!(
                "image {}x{} needs {}x{} workgroups, the adapter allows {max_groups} per dimension",
                frame.width, frame.height, groups.0, groups.1
            )));
        }
        use wgpu::BufferUsages as U;
        ctx.checked("uploading the scene", || {
            let shared = SceneOnGpu {
                particles: storage(ctx, "pgt particles", &scene.particles),
                ellipsoids: storage(ctx, "pgt ellipsoids", &scene.ellipsoids),
                nodes: storage(ctx, "pgt bvh nodes", &scene.nodes),
                indices: storage(ctx, "pgt bvh indices", &scene.leaf_indices),
                lights: storage(ctx, "pgt lights", &scene.lights),
                splats: storage(ctx, "pgt splats", &scene.splats),
                tile_entries: storage(ctx, "pgt tile entries", &scene.tile_entries),
                stats: buffer(
                    ctx,
                    "pgt stats",
                    STATS_BYTES,
                    U::STORAGE | U::COPY_SRC | U::COPY_DST,
                ),
            };
            let bands: Vec<Band> = rows
                .iter()
                .map(|&r| Band::new(ctx, pipeline, &shared, frame, r))
                .collect();
            let timestamps = ctx.timestamps.then(|| {
                let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pgt timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                let resolve = buffer(
                    ctx,
                    "pgt timestamp resolve",
                    TIMESTAMP_BYTES,
                    U::QUERY_RESOLVE | U::COPY_SRC,
                );
                (set, resolve)
            });
            let read = U::MAP_READ | U::COPY_DST;
            let largest = bands.iter().map(|b| b.bytes).max().unwrap_or(PIXEL_BYTES);
            Upload {
                bands,
                stats: shared.stats,
                timestamps,
                out_read: buffer(ctx, "pgt output read-back", largest, read),
                stats_read: buffer(ctx, "pgt stats read-back", STATS_BYTES, read),
                ts_read: buffer(ctx, "pgt timestamps read-back", TIMESTAMP_BYTES, read),
            }
        })
    }
}

/// Maps a MAP_READ buffer and copies its first `size` bytes out.
pub fn read_back(ctx: &GpuContext, buffer: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, ..size, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| PgtError::Gpu(format!("waiting for the GPU: {e}")))?;
    rx.recv()
        .map_err(|_| PgtError::Gpu("the GPU never answered the read-back".into()))?
        .map_err(|e| PgtError::Gpu(format!("reading the result back: {e}")))?;
    let data = buffer
        .get_mapped_range(..size)
        .map_err(|e| PgtError::Gpu(format!("reading the result back: {e:?}")))?
        .to_vec();
    buffer.unmap();
    Ok(data)
}

/// Copies each band's `from` buffer to its `to` buffer on the GPU, in one submission (`what`
/// names the step in errors).
fn copy_bands<'a>(
    ctx: &GpuContext,
    what: &str,
    bands: &'a [Band],
    from_to: impl Fn(&'a Band) -> Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
) -> Result<()> {
    ctx.checked(what, || {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pgt") });
        for band in bands {
            if let Some((from, to)) = from_to(band) {
                encoder.copy_buffer_to_buffer(from, 0, to, 0, band.bytes);
            }
        }
        ctx.queue.submit([encoder.finish()]);
    })
}

/// A freshly compiled pipeline's first dispatch, one that computes nothing (a band of no rows:
/// every invocation returns at once), waited for, so that the pipeline's compilation stays out
/// of the timed passes: lavapipe compiles a pipeline at its first dispatch, which took 1–5 s of
/// a 0.02–0.08 s image. Later renders with the same pipeline (a sweep's runs, a sequence's
/// frames) need none.
fn warm_up(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    up: &Upload,
    frame: &GpuFrame,
) -> Result<()> {
    let band = &up.bands[0];
    let empty = GpuFrame {
        row_begin: band.row_begin,
        row_count: 0,
        ..*frame
    };
    ctx.queue
        .write_buffer(&band.frame, 0, bytemuck::bytes_of(&empty));
    ctx.checked("compiling the pipeline (a first, empty dispatch)", || {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pgt") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pgt warm-up"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &band.bind_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
    })?;
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| PgtError::Gpu(format!("waiting for the GPU: {e}")))?;
    Ok(())
}

/// One dispatch per band with `frame` (its row range set per band), all in one submission, so
/// that the counters in `stats` are those of the whole image; returns them and the timestamp
/// ticks from the first band's start to the last band's end.
fn run_pass(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    up: &Upload,
    frame: &GpuFrame,
) -> Result<(GpuStats, Option<u64>)> {
    for band in &up.bands {
        let band_frame = GpuFrame {
            row_begin: band.row_begin,
            row_count: band.row_count,
            ..*frame
        };
        ctx.queue
            .write_buffer(&band.frame, 0, bytemuck::bytes_of(&band_frame));
    }
    ctx.queue
        .write_buffer(&up.stats, 0, bytemuck::bytes_of(&GpuStats::default()));
    let last = up.bands.len() - 1;
    ctx.checked("running the compute pass", || {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pgt") });
        for (k, band) in up.bands.iter().enumerate() {
            if let Some(backup) = &band.backup {
                encoder.copy_buffer_to_buffer(&band.output, 0, backup, 0, band.bytes);
            }
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pgt method"),
                // The first band's start and the last band's end (wgpu refuses a pass with
                // neither index, so the bands between carry none).
                timestamp_writes: up.timestamps.as_ref().filter(|_| k == 0 || k == last).map(
                    |(set, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: (k == 0).then_some(0),
                        end_of_pass_write_index: (k == last).then_some(1),
                    },
                ),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &band.bind_group, &[]);
            pass.dispatch_workgroups(band.groups.0, band.groups.1, 1);
        }
        if let Some((set, resolve)) = &up.timestamps {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, &up.ts_read, 0, TIMESTAMP_BYTES);
        }
        encoder.copy_buffer_to_buffer(&up.stats, 0, &up.stats_read, 0, STATS_BYTES);
        ctx.queue.submit([encoder.finish()]);
    })?;
    let stats_data = read_back(ctx, &up.stats_read, STATS_BYTES)?;
    ctx.check_uncaptured("running the compute pass")?;
    let stats: GpuStats = bytemuck::pod_read_unaligned(&stats_data[..STATS_BYTES as usize]);
    let ticks = match up.timestamps {
        Some(_) => {
            let ts = read_back(ctx, &up.ts_read, TIMESTAMP_BYTES)?;
            let t: [u64; 2] = bytemuck::pod_read_unaligned(&ts[..TIMESTAMP_BYTES as usize]);
            Some(t[1].saturating_sub(t[0]))
        }
        None => None,
    };
    Ok((stats, ticks))
}

/// Reads the finished image back band by band (RGB of the vec4 per pixel).
fn read_image(ctx: &GpuContext, up: &Upload, width: u32, height: u32) -> Result<RgbImage> {
    let mut image = RgbImage::new(width, height);
    for band in &up.bands {
        copy_bands(
            ctx,
            "reading the image back",
            std::slice::from_ref(band),
            |b| Some((&b.output, &up.out_read)),
        )?;
        let data = read_back(ctx, &up.out_read, band.bytes)?;
        ctx.check_uncaptured("reading the image back")?;
        let floats: &[[f32; 4]] = bytemuck::try_cast_slice(&data)
            .map_err(|e| PgtError::Gpu(format!("reading the result back: {e}")))?;
        let first = band.row_begin as usize * width as usize;
        let pixels = &mut image.pixels[first..first + floats.len()];
        for (dst, src) in pixels.iter_mut().zip(floats) {
            *dst = [src[0], src[1], src[2]];
        }
    }
    Ok(image)
}

/// Uploads the scene and runs `pipeline` over every pixel, in as many passes as
/// [`PassSchedule`] decides, each pass over every band of the image ([`bands`]).
pub fn run(
    ctx: &GpuContext,
    pipeline: &Pipeline,
    scene: &SceneBuffers,
    frame: &GpuFrame,
) -> Result<DispatchOutput> {
    run_with_limit(ctx, pipeline, scene, frame, storage_limit(ctx))
}

/// [`run`] as if the adapter allowed only `limit` bytes per storage buffer (never more than it
/// does): tests force small bands with it and compare with an unbanded run.
#[doc(hidden)]
pub fn run_with_limit(
    ctx: &GpuContext,
    pipeline: &Pipeline,
    scene: &SceneBuffers,
    frame: &GpuFrame,
    limit: u64,
) -> Result<DispatchOutput> {
    run_with_progress(ctx, pipeline, scene, frame, limit, &mut |_| {})
}

/// Where a run stands after a pass (a long approximation on lavapipe runs for
/// minutes in passes; the CLI shows them). The number of passes is not known in advance: the
/// schedule adapts to each pass's cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassProgress {
    /// Passes run so far, this one included (redone ones too).
    pub passes: u32,
    /// Work items (for `thesis`: (particle, sample) pairs) of every pixel done so far.
    pub items_done: u32,
    /// Whether this pass was too heavy and is redone with fewer items.
    pub redone: bool,
}

/// [`run_with_limit`], calling `progress` after every pass (on the calling thread, between
/// passes; it costs the GPU nothing).
pub fn run_with_progress(
    ctx: &GpuContext,
    pipeline: &Pipeline,
    scene: &SceneBuffers,
    frame: &GpuFrame,
    limit: u64,
    progress: &mut dyn FnMut(PassProgress),
) -> Result<DispatchOutput> {
    let up = Upload::with_limit(ctx, pipeline, scene, frame, limit)?;
    let (compiled, fresh) = pipeline.variant(ctx, !scene.ellipsoids.is_empty())?;
    if fresh {
        warm_up(ctx, compiled, &up, frame)?;
    }
    let mut schedule = PassSchedule::new(ctx.adapter.is_cpu);
    let start = Instant::now();
    let mut gpu_ticks: Option<f64> = up.timestamps.as_ref().map(|_| 0.0);
    let (mut hit_overflows, mut loop_limited, mut passes) = (0u32, 0u32, 0u32);
    loop {
        let mut pass_frame = *frame;
        (pass_frame.pair_begin, pass_frame.pair_end) = schedule.range();
        let (stats, ticks) = run_pass(ctx, compiled, &up, &pass_frame)?;
        if let (Some(total), Some(t)) = (gpu_ticks.as_mut(), ticks) {
            *total += t as f64;
        }
        passes += 1;
        let verdict = schedule.after_pass(stats.more_work > 0, stats.max_loop_iterations);
        progress(PassProgress {
            passes,
            items_done: match verdict {
                PassVerdict::Redo => pass_frame.pair_begin,
                _ => pass_frame.pair_end,
            },
            redone: verdict == PassVerdict::Redo,
        });
        if verdict == PassVerdict::Redo {
            copy_bands(ctx, "restoring the image", &up.bands, |b| {
                b.backup.as_ref().map(|backup| (backup, &b.output))
            })?;
            continue;
        }
        hit_overflows = hit_overflows.max(stats.hit_overflows);
        loop_limited = loop_limited.max(stats.loop_limited);
        if verdict == PassVerdict::Done {
            break;
        }
    }
    let image = read_image(ctx, &up, frame.width, frame.height)?;
    let wall = start.elapsed().as_secs_f64();
    let period_ns = ctx.queue.get_timestamp_period() as f64;
    let (gpu_seconds, timing) = match gpu_ticks {
        // A zero reading means the adapter's timestamps are not usable.
        Some(ticks) if ticks > 0.0 && period_ns > 0.0 => {
            (ticks * period_ns * 1e-9, Timing::Timestamps)
        }
        _ => (wall, Timing::Wall),
    };
    Ok(DispatchOutput {
        image,
        gpu_seconds,
        timing,
        hit_overflows,
        loop_limited,
        passes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gpu_takes_all_work_in_one_pass() {
        let mut s = PassSchedule::new(false);
        assert_eq!(s.range(), (0, u32::MAX));
        // Even a pass far over the budget is accepted: only lavapipe has the limit.
        assert_eq!(s.after_pass(true, 10 * LOOP_BUDGET), PassVerdict::Done);
    }

    #[test]
    fn a_single_pass_method_takes_one_pass_on_lavapipe() {
        let mut s = PassSchedule::new(true);
        assert_eq!(s.after_pass(false, 2 * LOOP_BUDGET), PassVerdict::Done);
    }

    #[test]
    fn light_passes_double_the_range_and_continue_where_the_last_ended() {
        let mut s = PassSchedule::new(true);
        assert_eq!(s.range(), (0, PAIRS_PER_PASS_CPU));
        assert_eq!(s.after_pass(true, 10), PassVerdict::Next);
        assert_eq!(s.range(), (8, 24));
        assert_eq!(s.after_pass(true, LOOP_BUDGET / 2), PassVerdict::Next);
        assert_eq!(s.range(), (24, 40), "a medium pass keeps its size");
        assert_eq!(s.after_pass(false, 10), PassVerdict::Done);
    }

    #[test]
    fn a_heavy_pass_is_redone_with_half_the_range_down_to_one() {
        let mut s = PassSchedule::new(true);
        assert_eq!(s.after_pass(true, LOOP_BUDGET + 1), PassVerdict::Redo);
        assert_eq!(s.range(), (0, 4));
        assert_eq!(s.after_pass(true, LOOP_BUDGET + 1), PassVerdict::Redo);
        assert_eq!(s.after_pass(true, LOOP_BUDGET + 1), PassVerdict::Redo);
        assert_eq!(s.range(), (0, 1));
        // One item that is still too heavy cannot be split further: accept it (it is reported).
        assert_eq!(s.after_pass(true, LOOP_BUDGET + 1), PassVerdict::Next);
        assert_eq!(s.range().0, 1);
    }

    #[test]
    fn the_schedule_ends_when_the_range_reaches_the_end_of_u32() {
        let mut s = PassSchedule::new(true);
        for _ in 0..64 {
            match s.after_pass(true, 0) {
                PassVerdict::Done => return,
                PassVerdict::Next => {}
                PassVerdict::Redo => panic!("a light pass is never redone"),
            }
        }
        panic!("no end after 64 doublings: {s:?}");
    }

    #[test]
    fn an_image_that_fits_is_one_band() {
        assert_eq!(bands(64, 48, 64 * 48 * 16).unwrap(), vec![(0, 48)]);
        assert_eq!(bands(64, 48, u64::MAX).unwrap(), vec![(0, 48)]);
    }

    #[test]
    fn bands_are_whole_workgroups_of_rows_and_cover_the_image_once() {
        // 20 rows fit; 16 (two workgroups of 8) are taken.
        let b = bands(10, 45, 10 * 16 * 20).unwrap();
        assert_eq!(b, vec![(0, 16), (16, 16), (32, 13)]);
        // Fewer rows than a workgroup fit: as many as fit.
        assert_eq!(
            bands(10, 7, 10 * 16 * 3).unwrap(),
            vec![(0, 3), (3, 3), (6, 1)]
        );
        // 8192² in lavapipe's 128 MiB: 8 bands of 1024 rows.
        let b = bands(8192, 8192, 128 << 20).unwrap();
        assert_eq!(b.len(), 8);
        assert!(b.iter().all(|&(_, n)| n == 1024));
    }

    #[test]
    fn a_row_beyond_the_limit_is_an_error_with_both_sizes() {
        let e = bands(1000, 10, 1000).unwrap_err().to_string();
        assert!(e.contains("one image row of 1000 pixels"), "{e}");
        assert!(
            e.contains("needs 15.6 KiB, the adapter allows 1000 bytes"),
            "{e}"
        );
        assert_eq!(human_bytes(128 << 20), "128.0 MiB");
    }
}
