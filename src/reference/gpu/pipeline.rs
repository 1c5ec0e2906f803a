//! Opening a GPU reference program on a device (docs/design.md §12): the context must have f64
//! in shaders, and the program is validated with f64 and compiled into its pipeline. Shared by
//! the sphere and Gaussian programs and the f64 math harness.

use crate::approx::shader::ShaderProgram;
use crate::approx::GpuContext;
use crate::error::{PgtError, Result};

/// Refuses a context opened without f64 in shaders.
pub(super) fn check_f64(ctx: &GpuContext) -> Result<()> {
    if ctx.f64 {
        return Ok(());
    }
    Err(PgtError::Gpu(format!(
        "{} was opened without f64 (GpuContext::with_f64)",
        ctx.adapter
    )))
}

/// A GPU reference `program` validated with f64 and compiled into the pipeline of its `entry`
/// point; `what` names it in messages.
pub(super) fn compile(
    ctx: &GpuContext,
    program: &ShaderProgram,
    what: &str,
    entry: &str,
) -> Result<wgpu::ComputePipeline> {
    program.validate_with(naga::valid::Capabilities::FLOAT64)?;
    let label = format!("pgt {what}");
    ctx.checked(&format!("compiling the {what}"), || {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&label),
                source: wgpu::ShaderSource::Wgsl(program.source().into()),
            });
        ctx.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&label),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
    })
}
