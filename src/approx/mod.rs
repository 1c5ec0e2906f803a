//! The GPU approximation renderer (DESIGN.md §4): wgpu compute shaders over the same scene,
//! camera and pixel sampling as the reference, in f32. pgt exists to measure approximations;
//! this module runs them.
//!
//! * [`context`]: adapter, device, error scopes (no panics, a clear message without an adapter).
//! * [`layout`]: the structs shared with `shaders/common.wgsl`, byte for byte.
//! * [`shader`]: prelude + method + entry point, validated with naga, errors by file and line.
//! * [`methods`]: `emission`, `opaque`, `thesis` and their parameters.
//! * [`user_shader`]: users' own methods (docs/user-shaders.md).
//! * [`dispatch`]: upload, dispatch, read-back, timing.
//!
//! [`render_approx`] is the library entry point that `pgt approx` and `pgt sweep` share.

pub mod context;
pub mod dispatch;
pub mod layout;
pub mod methods;
pub mod shader;
pub mod user_shader;

pub use context::{GpuContext, NO_ADAPTER};
pub use dispatch::Timing;
pub use methods::{ApproxParams, Method, N_EXACT_ALL};

use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use crate::scene::Scene;

/// A finished approximation.
#[derive(Debug, Clone)]
pub struct ApproxOutput {
    /// Linear RGB, row 0 at the top, like the reference's image.
    pub image: RgbImage,
    /// Time of the compute pass, in seconds (see `timing`).
    pub gpu_seconds: f64,
    pub timing: Timing,
    /// The adapter that ran it, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub adapter_name: String,
    /// The method that ran.
    pub method: Method,
    /// Pixels where a ray crossed more than `MAX_HITS` (128) particles: the farthest were
    /// dropped for that ray. Non-zero means the image is not what the method would give.
    pub hit_overflow_pixels: u32,
    /// Pixels whose loops reached 65535 iterations: lavapipe cuts them short there, so on a Cpu
    /// adapter these pixels are wrong (pgt splits the thesis method into passes to avoid it).
    pub loop_limited_pixels: u32,
    /// Dispatches the method took (the thesis method on lavapipe takes several).
    pub passes: u32,
}

/// Opens a GPU context ([`GpuContext::new`] with `params.adapter`) and renders the scene.
/// The method's WGSL is checked first, so a broken shader is reported even without a GPU.
pub fn render_approx(scene: &Scene, params: &ApproxParams) -> Result<ApproxOutput> {
    let (method, program) = prepare(scene, params)?;
    let ctx = GpuContext::new(params.adapter.as_deref())?;
    run(&ctx, scene, params, method, &program)
}

/// Renders with an open context (a sweep opens one and renders many parameter sets).
/// `params.adapter` is ignored here: the context has already chosen.
pub fn render_approx_with(
    ctx: &GpuContext,
    scene: &Scene,
    params: &ApproxParams,
) -> Result<ApproxOutput> {
    let (method, program) = prepare(scene, params)?;
    run(ctx, scene, params, method, &program)
}

/// Resolves the method, checks it against the scene and the parameters, validates its WGSL.
fn prepare(scene: &Scene, params: &ApproxParams) -> Result<(Method, shader::ShaderProgram)> {
    let method = params
        .method
        .clone()
        .unwrap_or_else(|| Method::default_for(scene));
    method.check_scene(scene)?;
    if params.samples == 0 {
        return Err(PgtError::Usage("--samples must be at least 1".into()));
    }
    let program = method.program()?;
    program.validate()?;
    Ok((method, program))
}

fn run(
    ctx: &GpuContext,
    scene: &Scene,
    params: &ApproxParams,
    method: Method,
    program: &shader::ShaderProgram,
) -> Result<ApproxOutput> {
    let bvh = scene.build_bvh();
    let buffers = layout::SceneBuffers::new(scene, &bvh);
    if buffers.bvh_depth > STACK_DEPTH {
        return Err(PgtError::Gpu(format!(
            "the BVH is {} levels deep, the shaders' traversal stack holds {STACK_DEPTH}",
            buffers.bvh_depth
        )));
    }
    let frame = layout::GpuFrame::new(scene, params.samples, params.n_exact);
    let out = dispatch::run(ctx, program, &buffers, &frame)?;
    Ok(ApproxOutput {
        image: out.image,
        gpu_seconds: out.gpu_seconds,
        timing: out.timing,
        adapter_name: ctx.adapter.name.clone(),
        method,
        hit_overflow_pixels: out.hit_overflows,
        loop_limited_pixels: if ctx.adapter.is_cpu {
            out.loop_limited
        } else {
            0
        },
        passes: out.passes,
    })
}

/// Deepest BVH the WGSL traversal handles: `STACK_SIZE` (64) in `shaders/common.wgsl` minus
/// one, since a node's two children are pushed together.
pub const STACK_DEPTH: u32 = 63;

/// Most hits one ray list holds: `MAX_HITS` in `shaders/common.wgsl`.
pub const MAX_HITS: u32 = 128;
