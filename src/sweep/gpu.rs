//! The GPU approximations (docs/design.md §4) as sweep methods: every method of the approximation
//! registry (`approx::methods::METHODS`) is sweepable with every parameter it declares, through
//! one adapter from the sweep's [`SweepMethod`] to `approx::render_approx_with` on the sweep's
//! one GPU context. Nothing here names a method: a new registry entry is sweepable as it is.

use super::method::{ParamDefault, ParamValue, RunImage, SweepContext, SweepMethod, SweepParam};
use crate::approx::methods::{ApproxMethod, METHODS};
use crate::approx::{render_approx_with, ApproxParams, ParamSpec, MAX_HITS, N_EXACT_ALL};
use crate::error::Result;
use crate::scene::Scene;
use std::sync::OnceLock;

/// A registered GPU method with its parameters in the sweep's terms.
pub struct GpuMethod {
    method: &'static dyn ApproxMethod,
    params: Vec<SweepParam>,
}

/// The sweep's view of a registry parameter: `"all"` is a value where the range ends at
/// [`N_EXACT_ALL`].
fn sweep_param(spec: &ParamSpec) -> SweepParam {
    let accepts_all = spec.max == N_EXACT_ALL;
    let default = if accepts_all && spec.default == N_EXACT_ALL {
        ParamValue::All
    } else {
        ParamValue::Count(spec.default)
    };
    SweepParam {
        name: spec.name,
        default: ParamDefault::Value(default),
        min: spec.min,
        // "all" is the sentinel N_EXACT_ALL = u32::MAX; counts stay below it.
        max: if accepts_all { u32::MAX - 1 } else { spec.max },
        accepts_all,
        quiet_default: spec.quiet_default,
        doc: spec.doc,
    }
}

/// Every registered method, built once per process.
pub fn gpu_methods() -> &'static [GpuMethod] {
    static METHODS_FOR_SWEEP: OnceLock<Vec<GpuMethod>> = OnceLock::new();
    METHODS_FOR_SWEEP.get_or_init(|| {
        METHODS
            .iter()
            .map(|&method| GpuMethod {
                method,
                params: method.params().iter().map(sweep_param).collect(),
            })
            .collect()
    })
}

impl SweepMethod for GpuMethod {
    fn name(&self) -> &'static str {
        self.method.name()
    }

    fn params(&self) -> &[SweepParam] {
        &self.params
    }

    fn check_scene(&self, scene: &Scene) -> Result<()> {
        self.method.check_scene(scene)
    }

    fn render(
        &self,
        ctx: &mut SweepContext,
        scene: &Scene,
        values: &[(&'static str, u32)],
    ) -> Result<RunImage> {
        let params = ApproxParams::for_method(self.method.name(), values)?;
        let out = render_approx_with(ctx.gpu()?, scene, &params)?;
        let mut warnings = Vec::new();
        if out.hit_overflow_pixels > 0 {
            warnings.push(format!(
                "{} pixels crossed more than {MAX_HITS} particles; their farthest particles were dropped",
                out.hit_overflow_pixels
            ));
        }
        if out.loop_limited_pixels > 0 {
            warnings.push(format!(
                "{} pixels reached lavapipe's limit of 65535 loop iterations per pixel, so they are wrong",
                out.loop_limited_pixels
            ));
        }
        Ok(RunImage {
            image: out.image,
            gpu_seconds: Some(out.gpu_seconds),
            warnings,
        })
    }
}
