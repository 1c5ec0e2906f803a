//! The GPU approximation renderer (docs/design.md §4): wgpu compute shaders over the same scene,
//! camera and pixel sampling as the reference, in f32. pgt exists to measure approximations;
//! this module runs them.
//!
//! * [`context`]: adapter, device, error scopes (no panics, a clear message without an adapter).
//! * [`contract`]: the constants and bindings shared with WGSL, and the WGSL generated from them.
//! * [`layout`]: the structs shared with WGSL, byte for byte.
//! * [`shader`]: generated contract + prelude + method + entry point, validated with naga,
//!   errors by file and line.
//! * [`methods`]: the [`ApproxMethod`] trait and the registry of built-in methods, one file each.
//! * [`params`]: parameter specs, the chosen method and its parameter values.
//! * [`user_shader`]: users' own methods (docs/user-shaders.md).
//! * [`dispatch`]: pipeline, upload, pass schedule, read-back, timing.
//! * [`splat_tiles`]: the splatting methods' projection and tile lists (CPU, before the
//!   dispatch).
//!
//! [`render_approx`] is the library entry point that `pgt approx` and `pgt sweep` share;
//! [`ApproxPipeline`] keeps a compiled method for many renders.

pub mod context;
pub mod contract;
pub mod dispatch;
pub mod layout;
pub mod methods;
pub mod param_spec;
pub mod params;
pub mod shader;
pub mod splat_tiles;
pub mod user_shader;
pub mod wgsl;
pub mod wgsl_generic;

pub use context::{GpuContext, NO_ADAPTER};
pub use contract::{MAX_HITS, STACK_DEPTH};
pub use dispatch::Timing;
pub use methods::{find_method, ApproxMethod, METHODS};
pub use param_spec::{ParamSpec, N_EXACT_ALL};
pub use params::{ApproxParams, Method};

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
    /// Its parameters with the values used (chosen or default), in slot order.
    pub params: Vec<(String, u32)>,
    /// Pixels where a ray crossed more than [`MAX_HITS`] particles: the farthest were
    /// dropped for that ray. Non-zero means the image is not what the method would give.
    pub hit_overflow_pixels: u32,
    /// Pixels whose loops reached the loop budget (`contract::LOOP_BUDGET`): lavapipe cuts loops
    /// short at `contract::LOOP_LIMIT`, so on a Cpu adapter these pixels may be wrong (pgt
    /// splits the thesis method into passes to avoid it).
    pub loop_limited_pixels: u32,
    /// Dispatches the method took (the thesis method on lavapipe takes several).
    pub passes: u32,
}

impl ApproxOutput {
    /// What the user must be told about this image: pixels whose farthest particles were
    /// dropped, pixels that lavapipe's loop limit may have cut short.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.hit_overflow_pixels > 0 {
            out.push(format!(
                "{} pixels crossed more than {} particles; their farthest particles were dropped",
                self.hit_overflow_pixels, MAX_HITS
            ));
        }
        if self.loop_limited_pixels > 0 {
            out.push(format!(
                "{} pixels reached lavapipe's limit of {} loop iterations per pixel; lavapipe cuts such loops short, so these pixels are wrong (use fewer samples or a real GPU)",
                self.loop_limited_pixels,
                contract::LOOP_LIMIT
            ));
        }
        out
    }
}

/// Opens a GPU context ([`GpuContext::new`] with `params.adapter`) and renders the scene.
/// The method's WGSL is checked first, so a broken shader is reported even without a GPU.
pub fn render_approx(scene: &Scene, params: &ApproxParams) -> Result<ApproxOutput> {
    render_approx_with_progress(scene, params, &mut |_| {})
}

/// [`render_approx`], calling `progress` after every pass of the dispatch (the CLI's spinner).
pub fn render_approx_with_progress(
    scene: &Scene,
    params: &ApproxParams,
    progress: &mut dyn FnMut(dispatch::PassProgress),
) -> Result<ApproxOutput> {
    let (method, values, program) = prepare(scene, params)?;
    let ctx = GpuContext::new(params.adapter.as_deref())?;
    ApproxPipeline::from_program(&ctx, method, &values, &program)?
        .render_with_progress(&ctx, scene, params, progress)
}

/// Renders with an open context (a sweep opens one and renders many parameter sets).
/// `params.adapter` is ignored here: the context has already chosen.
pub fn render_approx_with(
    ctx: &GpuContext,
    scene: &Scene,
    params: &ApproxParams,
) -> Result<ApproxOutput> {
    let (method, values, program) = prepare(scene, params)?;
    ApproxPipeline::from_program(ctx, method, &values, &program)?.render(ctx, scene, params)
}

/// A method ready to compile: the method, its parameter values in slot order, its program.
type Prepared = (Method, Vec<(String, u32)>, shader::ShaderProgram);

/// Resolves the method, checks it against the scene and the parameters, validates its WGSL.
fn prepare(scene: &Scene, params: &ApproxParams) -> Result<Prepared> {
    let method = params
        .method
        .clone()
        .unwrap_or_else(|| Method::default_for(scene));
    method.check_scene(scene)?;
    let values = params.resolve(&method)?;
    let program = method.program(&values)?;
    program.validate()?;
    Ok((method, values, program))
}

/// A method compiled for one context: build it once, render any scene with any values of its
/// parameters (the sweep's runs of one method share one).
#[derive(Debug)]
pub struct ApproxPipeline {
    method: Method,
    /// The parameter names the program was generated with, in slot order.
    names: Vec<String>,
    pipeline: dispatch::Pipeline,
}

impl ApproxPipeline {
    /// Validates and compiles `method` with the parameter names `params` resolves to.
    pub fn new(ctx: &GpuContext, method: &Method, params: &ApproxParams) -> Result<ApproxPipeline> {
        let values = params.resolve(method)?;
        let program = method.program(&values)?;
        program.validate()?;
        ApproxPipeline::from_program(ctx, method.clone(), &values, &program)
    }

    fn from_program(
        ctx: &GpuContext,
        method: Method,
        values: &[(String, u32)],
        program: &shader::ShaderProgram,
    ) -> Result<ApproxPipeline> {
        Ok(ApproxPipeline {
            method,
            names: values.iter().map(|(n, _)| n.clone()).collect(),
            pipeline: dispatch::Pipeline::new(ctx, program)?,
        })
    }

    /// The method it runs.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// Renders `scene` with `params`' values (`params.method` is ignored: this pipeline's
    /// method runs).
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        params: &ApproxParams,
    ) -> Result<ApproxOutput> {
        self.render_with_progress(ctx, scene, params, &mut |_| {})
    }

    /// [`Self::render`], calling `progress` after every pass of the dispatch.
    pub fn render_with_progress(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        params: &ApproxParams,
        progress: &mut dyn FnMut(dispatch::PassProgress),
    ) -> Result<ApproxOutput> {
        self.method.check_scene(scene)?;
        let values = params.resolve(&self.method)?;
        if values.iter().map(|(n, _)| n).ne(self.names.iter()) {
            return Err(PgtError::Usage(format!(
                "{}: this pipeline was built for the parameters {:?}",
                self.method.name(),
                self.names
            )));
        }
        dispatch::check_scene_size(ctx, scene)?;
        let prep = self.method.preparation();
        let bvh = match prep.traced_sigmas {
            Some(k) => layout::widened_gaussians(scene, k).build_bvh(),
            None => scene.build_bvh(),
        };
        let mut buffers = layout::SceneBuffers::new(scene, &bvh);
        if let Some(k) = prep.traced_sigmas {
            buffers.widen_gaussians(k);
        }
        if buffers.bvh_depth > STACK_DEPTH {
            return Err(PgtError::Gpu(format!(
                "the BVH is {} levels deep, the shaders' traversal stack holds {STACK_DEPTH}",
                buffers.bvh_depth
            )));
        }
        let slots: Vec<u32> = values.iter().map(|(_, v)| *v).collect();
        let mut frame = layout::GpuFrame::new(scene, &slots);
        // The splatting methods' projection and tile lists, on the CPU: their time counts in
        // the method's (it is 3DGS's preprocessing and sorting pass).
        let prepare_seconds = if prep.splat_tiles {
            let t = std::time::Instant::now();
            let constants = splat_tiles::SplatConstants::from_values(&values);
            constants.apply_to(&mut frame);
            splat_tiles::build(&mut buffers, &frame, &constants);
            t.elapsed().as_secs_f64()
        } else {
            0.0
        };
        let limit = dispatch::storage_limit(ctx);
        let out =
            dispatch::run_with_progress(ctx, &self.pipeline, &buffers, &frame, limit, progress)?;
        Ok(ApproxOutput {
            image: out.image,
            gpu_seconds: out.gpu_seconds + prepare_seconds,
            timing: out.timing,
            adapter_name: ctx.adapter.name.clone(),
            method: self.method.clone(),
            params: values,
            hit_overflow_pixels: out.hit_overflows,
            loop_limited_pixels: if ctx.adapter.is_cpu {
                out.loop_limited
            } else {
                0
            },
            passes: out.passes,
        })
    }
}
