//! f64 exp, expm1, log1p and erfc on the GPU (`shaders/f64_math.wgsl`, docs/design.md §12) and
//! their error bounds.
//!
//! Vulkan's extended instructions have exp and log for 16- and 32-bit floats only, so the GPU
//! reference computes them from +, −, ×, ÷, fma and ldexp: Cody–Waite range reduction
//! x = k·ln 2 + r, |r| ≤ ln2/2, a Taylor polynomial for expm1(r) whose first omitted term is
//! below 3e-19 of the result, and a scaling by 2^k that is exact for normal results; log1p
//! splits 1 + x = 2^k·m and takes log(m) = 2·atanh(f/(2 + f)) in fdlibm's form; erfc is
//! FreeBSD's (the `libm` crate's) rational approximations on four ranges, its e^{−x²} from
//! `f64_exp` with x split so that the square is exact.
//!
//! The bounds below are what `tests/gpu/reference.rs` measures against the CPU's libm (glibc,
//! within an ulp of the truth) over dense and random arguments, tails included, plus that ulp:
//! the test fails if a measured error exceeds its bound less one. The GPU reference's err uses
//! them where an exponential enters (`shaders/reference_emission.wgsl`).

use crate::approx::dispatch::read_back;
use crate::approx::shader::{ShaderPart, ShaderProgram};
use crate::approx::GpuContext;
use crate::error::{PgtError, Result};
use std::borrow::Cow;
use wgpu::util::DeviceExt;

/// `shaders/f64_math.wgsl`.
pub const F64_MATH_WGSL: &str = include_str!("../../../shaders/f64_math.wgsl");

/// The unit roundoff of f64, 2^−53: half an ulp of 1.
pub const U: f64 = 1.1102230246251565e-16;

/// The error of `f64_exp` on the GPU in ulps of the result (normal results), bound.
pub const EXP_ULPS: f64 = 3.0;
/// The error of `f64_expm1` on the GPU in ulps of the result, bound.
pub const EXPM1_ULPS: f64 = 3.0;
/// The error of `f64_log1p` on the GPU in ulps of the result, bound.
pub const LOG1P_ULPS: f64 = 3.0;
/// The error of `f64_erfc` on the GPU in ulps of the result, bound, for results of at least
/// [`ERFC_NORMAL`]; below it, within [`ERFC_NORMAL`] in absolute terms (the results there are
/// subnormal or nearly, and the two exponentials of the far tail lose their last digits).
pub const ERFC_ULPS: f64 = 7.0;
/// The smallest erfc result to which [`ERFC_ULPS`] applies: 2^−1000.
pub const ERFC_NORMAL: f64 = 9.332636185032189e-302;

const HARNESS_WGSL: &str = "
@group(0) @binding(0) var<storage, read> math_in: array<f64>;
@group(0) @binding(1) var<storage, read_write> math_out: array<f64>;

@compute @workgroup_size(64, 1, 1)
fn math_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&math_in)) {
        return;
    }
    let x = math_in[i];
    math_out[4u * i] = f64_exp(x);
    math_out[4u * i + 1u] = f64_expm1(x);
    var l = 0.0lf;
    if (x > -1.0lf) {
        l = f64_log1p(x);
    }
    math_out[4u * i + 2u] = l;
    math_out[4u * i + 3u] = f64_erfc(x);
}
";

/// The program that evaluates the four functions over an array (the test harness).
pub fn harness_program() -> ShaderProgram {
    ShaderProgram::from_parts(vec![
        ShaderPart {
            name: "shaders/f64_math.wgsl".into(),
            text: Cow::Borrowed(F64_MATH_WGSL),
        },
        ShaderPart {
            name: "<the f64 math harness, src/reference/gpu/math.rs>".into(),
            text: Cow::Borrowed(HARNESS_WGSL),
        },
    ])
}

/// (exp x, expm1 x, log1p x, erfc x) for every x, computed on the GPU by
/// `shaders/f64_math.wgsl` (log1p: 0 where x ≤ −1). At most 65535·64 arguments a call.
pub fn evaluate(ctx: &GpuContext, xs: &[f64]) -> Result<Vec<[f64; 4]>> {
    super::pipeline::check_f64(ctx)?;
    if xs.is_empty() {
        return Ok(Vec::new());
    }
    let groups = (xs.len() as u32).div_ceil(64);
    if groups > 65535 {
        return Err(PgtError::Gpu("at most 65535·64 arguments a call".into()));
    }
    let pipeline =
        super::pipeline::compile(ctx, &harness_program(), "f64 math harness", "math_main")?;
    let device = &ctx.device;
    let out_bytes = (xs.len() * 4 * 8) as u64;
    let (bind_group, output, read) = ctx.checked("the f64 math harness", || {
        let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pgt f64 math in"),
            contents: bytemuck::cast_slice(xs),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pgt f64 math out"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pgt f64 math read-back"),
            size: out_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pgt f64 math"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: input.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        (bind_group, output, read)
    })?;
    ctx.checked("running the f64 math harness", || {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &read, 0, out_bytes);
        ctx.queue.submit([encoder.finish()]);
    })?;
    let data = read_back(ctx, &read, out_bytes)?;
    let values: Vec<f64> = bytemuck::pod_collect_to_vec(&data);
    Ok(values
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}
