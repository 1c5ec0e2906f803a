//! Uploading the scene, building the compute pipeline, one dispatch over the image, reading the
//! image back, and timing it (timestamp queries where the adapter has them, wall time otherwise).

use super::context::GpuContext;
use super::layout::{GpuFrame, GpuStats, SceneBuffers};
use super::shader::{ShaderProgram, ENTRY_POINT};
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// Side of the square workgroup in `shaders/entry.wgsl` (`@workgroup_size(8, 8, 1)`).
const WORKGROUP_SIDE: u32 = 8;

/// (particle, sample) pairs of the thesis method per pass on a Cpu adapter (lavapipe): each
/// pair costs one shadow ray per light, each shadow ray some hundred loop iterations in a large
/// scene, and lavapipe allows 65535 per invocation in all.
pub const PAIRS_PER_PASS_CPU: u32 = 8;

/// Loop iterations a pixel may count in one pass on a Cpu adapter before the pass is redone with
/// fewer pairs: `LOOP_LIMIT_REPORT` of the prelude (half of lavapipe's 65535, a margin for
/// lavapipe counting per group of 8 pixels).
pub const LOOP_BUDGET: u32 = 32768;

/// How the GPU time was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// Timestamp queries around the compute pass (GPU time only).
    Timestamps,
    /// Wall time from submission to completion (includes driver overhead).
    Wall,
}

/// What one dispatch produced.
#[derive(Debug, Clone)]
pub struct DispatchOutput {
    pub image: RgbImage,
    pub gpu_seconds: f64,
    pub timing: Timing,
    /// Pixels whose hit list overflowed (`MAX_HITS` in the prelude), most in any pass.
    pub hit_overflows: u32,
    /// Pixels that reached lavapipe's loop limit in some pass (most in any pass).
    pub loop_limited: u32,
    /// Dispatches it took.
    pub passes: u32,
}

/// Sizes of the storage buffers, checked against the device's limits before any allocation so
/// that a scene that is too large is refused with a message, not a wgpu validation error.
fn check_limits(ctx: &GpuContext, buffers: &[(&str, u64)]) -> Result<()> {
    let limits = ctx.device.limits();
    let binding = limits.max_storage_buffer_binding_size;
    let buffer = limits.max_buffer_size;
    for &(name, size) in buffers {
        let allowed = binding.min(buffer);
        if size > allowed {
            return Err(PgtError::Gpu(format!(
                "too large for {}: the {name} buffer needs {:.1} MiB, the adapter allows {:.1} MiB per storage buffer \
                 (max_storage_buffer_binding_size); render a smaller part of the scene or a smaller image, or use an adapter with larger limits",
                ctx.adapter.name,
                size as f64 / 1048576.0,
                allowed as f64 / 1048576.0
            )));
        }
    }
    Ok(())
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

/// Maps a MAP_READ buffer and copies its bytes out.
fn read_back(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| PgtError::Gpu(format!("waiting for the GPU: {e}")))?;
    rx.recv()
        .map_err(|_| PgtError::Gpu("the GPU never answered the read-back".into()))?
        .map_err(|e| PgtError::Gpu(format!("reading the result back: {e}")))?;
    let data = buffer
        .get_mapped_range(..)
        .map_err(|e| PgtError::Gpu(format!("reading the result back: {e:?}")))?
        .to_vec();
    buffer.unmap();
    Ok(data)
}

/// Runs `program` (already validated with [`ShaderProgram::validate`]) over every pixel.
pub fn run(
    ctx: &GpuContext,
    program: &ShaderProgram,
    scene: &SceneBuffers,
    frame: &GpuFrame,
) -> Result<DispatchOutput> {
    let pixels = frame.width as usize * frame.height as usize;
    let out_bytes = bytes::<[f32; 4]>(pixels);
    check_limits(
        ctx,
        &[
            (
                "particle",
                bytes::<super::layout::GpuParticle>(scene.particles.len()),
            ),
            (
                "BVH node",
                bytes::<super::layout::GpuBvhNode>(scene.nodes.len()),
            ),
            ("BVH index", bytes::<u32>(scene.leaf_indices.len())),
            (
                "light",
                bytes::<super::layout::GpuLight>(scene.lights.len()),
            ),
            ("output image", out_bytes),
        ],
    )?;
    let groups_x = frame.width.div_ceil(WORKGROUP_SIDE);
    let groups_y = frame.height.div_ceil(WORKGROUP_SIDE);
    let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
    if groups_x > max_groups || groups_y > max_groups {
        return Err(PgtError::Gpu(format!(
            "image {}x{} needs {groups_x}x{groups_y} workgroups, the adapter allows {max_groups} per dimension",
            frame.width, frame.height
        )));
    }

    let device = &ctx.device;
    let module = ctx.checked("compiling the WGSL", || {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pgt method"),
            source: wgpu::ShaderSource::Wgsl(program.source().into()),
        })
    })?;
    let storage_entry = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let (pipeline, layout) = ctx.checked("creating the compute pipeline", || {
        // An explicit layout: a user's method need not use every binding.
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pgt scene"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, false),
                storage_entry(6, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pgt"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("pgt method"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(ENTRY_POINT),
            compilation_options: Default::default(),
            cache: None,
        });
        (pipeline, layout)
    })?;

    let (bind_group, frame_buf, output, stats, timestamps) =
        ctx.checked("uploading the scene", || {
            let frame_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pgt frame"),
                contents: bytemuck::bytes_of(frame),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
            let particles = storage(ctx, "pgt particles", &scene.particles);
            let nodes = storage(ctx, "pgt bvh nodes", &scene.nodes);
            let indices = storage(ctx, "pgt bvh indices", &scene.leaf_indices);
            let lights = storage(ctx, "pgt lights", &scene.lights);
            let output = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pgt output"),
                size: out_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let stats = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pgt stats"),
                contents: bytemuck::bytes_of(&GpuStats::default()),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pgt scene"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: frame_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: particles.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: nodes.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: indices.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: lights.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: output.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: stats.as_entire_binding(),
                    },
                ],
            });
            let timestamps = ctx.timestamps.then(|| {
                let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pgt timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pgt timestamp resolve"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                (set, resolve)
            });
            (bind_group, frame_buf, output, stats, timestamps)
        })?;

    let readback = |label: &str, size: u64| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let (out_read, stats_read, ts_read) = ctx.checked("allocating read-back buffers", || {
        (
            readback("pgt output read-back", out_bytes),
            readback(
                "pgt stats read-back",
                std::mem::size_of::<GpuStats>() as u64,
            ),
            readback("pgt timestamps read-back", 16),
        )
    })?;

    // Passes: a method that splits its work (thesis: lit samples) raises `more_work`; the next
    // pass takes the next range of (particle, sample) pairs. On lavapipe (a Cpu adapter) all
    // loops of an invocation together may run 65535 iterations, so a pass there takes a few
    // pairs: a pass whose busiest pixel counted more than LOOP_BUDGET is undone (the image is
    // restored from a copy) and redone with half the pairs; a light pass doubles them. A real
    // GPU takes all pairs in one pass.
    let cpu = ctx.adapter.is_cpu;
    let mut pairs_per_pass = if cpu { PAIRS_PER_PASS_CPU } else { u32::MAX };
    let backup = cpu.then(|| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pgt output backup"),
            size: out_bytes,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    });
    let start = Instant::now();
    let mut gpu_ticks: Option<f64> = timestamps.as_ref().map(|_| 0.0);
    let mut hit_overflows = 0u32;
    let mut loop_limited = 0u32;
    let mut pass_frame = *frame;
    pass_frame.pair_begin = 0;
    let mut passes = 0u32;
    loop {
        pass_frame.pair_end = pass_frame.pair_begin.saturating_add(pairs_per_pass);
        ctx.queue
            .write_buffer(&frame_buf, 0, bytemuck::bytes_of(&pass_frame));
        ctx.queue
            .write_buffer(&stats, 0, bytemuck::bytes_of(&GpuStats::default()));
        ctx.checked("running the compute pass", || {
            let mut encoder = device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pgt") });
            if let Some(backup) = &backup {
                encoder.copy_buffer_to_buffer(&output, 0, backup, 0, out_bytes);
            }
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("pgt method"),
                    timestamp_writes: timestamps.as_ref().map(|(set, _)| {
                        wgpu::ComputePassTimestampWrites {
                            query_set: set,
                            beginning_of_pass_write_index: Some(0),
                            end_of_pass_write_index: Some(1),
                        }
                    }),
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(groups_x, groups_y, 1);
            }
            if let Some((set, resolve)) = &timestamps {
                encoder.resolve_query_set(set, 0..2, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, &ts_read, 0, 16);
            }
            encoder.copy_buffer_to_buffer(
                &stats,
                0,
                &stats_read,
                0,
                std::mem::size_of::<GpuStats>() as u64,
            );
            ctx.queue.submit([encoder.finish()]);
        })?;
        let stats_data = read_back(ctx, &stats_read)?;
        ctx.check_uncaptured("running the compute pass")?;
        let pass_stats: GpuStats =
            bytemuck::pod_read_unaligned(&stats_data[..std::mem::size_of::<GpuStats>()]);
        if let Some(total) = gpu_ticks.as_mut() {
            let ts = read_back(ctx, &ts_read)?;
            let t: [u64; 2] = bytemuck::pod_read_unaligned(&ts[..16]);
            *total += t[1].saturating_sub(t[0]) as f64;
        }
        passes += 1;
        let split = pass_stats.more_work > 0 || pass_frame.pair_begin > 0;
        if let Some(backup) = &backup {
            if split && pass_stats.max_loop_iterations > LOOP_BUDGET && pairs_per_pass > 1 {
                // Undo and redo this pass with fewer pairs.
                ctx.checked("restoring the image", || {
                    let mut encoder =
                        device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("pgt"),
                        });
                    encoder.copy_buffer_to_buffer(backup, 0, &output, 0, out_bytes);
                    ctx.queue.submit([encoder.finish()]);
                })?;
                pairs_per_pass = (pairs_per_pass / 2).max(1);
                continue;
            }
            if pass_stats.max_loop_iterations < LOOP_BUDGET / 4 && pairs_per_pass < u32::MAX / 2 {
                pairs_per_pass *= 2;
            }
        }
        hit_overflows = hit_overflows.max(pass_stats.hit_overflows);
        loop_limited = loop_limited.max(pass_stats.loop_limited);
        if pass_stats.more_work == 0 || pass_frame.pair_end == u32::MAX {
            break;
        }
        pass_frame.pair_begin = pass_frame.pair_end;
    }
    ctx.checked("reading the image back", || {
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pgt") });
        encoder.copy_buffer_to_buffer(&output, 0, &out_read, 0, out_bytes);
        ctx.queue.submit([encoder.finish()]);
    })?;
    let out_data = read_back(ctx, &out_read)?;
    let wall = start.elapsed().as_secs_f64();
    ctx.check_uncaptured("reading the image back")?;
    let period_ns = ctx.queue.get_timestamp_period() as f64;
    let (gpu_seconds, timing) = match gpu_ticks {
        // A zero reading means the adapter's timestamps are not usable.
        Some(ticks) if ticks > 0.0 && period_ns > 0.0 => {
            (ticks * period_ns * 1e-9, Timing::Timestamps)
        }
        _ => (wall, Timing::Wall),
    };

    let floats: &[[f32; 4]] = bytemuck::try_cast_slice(&out_data[..pixels * 16])
        .map_err(|e| PgtError::Gpu(format!("reading the result back: {e}")))?;
    let mut image = RgbImage::new(frame.width, frame.height);
    for (dst, src) in image.pixels.iter_mut().zip(floats) {
        *dst = [src[0], src[1], src[2]];
    }
    Ok(DispatchOutput {
        image,
        gpu_seconds,
        timing,
        hit_overflows,
        loop_limited,
        passes,
    })
}
