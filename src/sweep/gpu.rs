//! The GPU approximations (DESIGN.md §4) as sweep methods: an adapter from the sweep's
//! [`SweepMethod`] to `approx::render_approx_with`, on the sweep's one GPU context.
//!
//! | method     | parameters (default)                 |
//! |------------|--------------------------------------|
//! | `emission` | —                                    |
//! | `opaque`   | —                                    |
//! | `thesis`   | `samples` (100), `n_exact` (`"all"`) |
//!
//! When the approximation registry (`approx::methods`) exists, this table and [`GpuMethod`]'s
//! body become a lookup in it: `params()` from the method's `ParamSpec`s, `render` building
//! `ApproxParams` from `(name, values)`.

use super::method::{
    value_of, ParamDefault, ParamValue, RunImage, SweepContext, SweepMethod, SweepParam,
};
use crate::approx::{render_approx_with, ApproxParams, Method, MAX_HITS, N_EXACT_ALL};
use crate::error::Result;
use crate::scene::Scene;

/// A built-in GPU method with the parameters a sweep may list.
pub struct GpuMethod {
    name: &'static str,
    method: Method,
    params: &'static [SweepParam],
}

const THESIS_PARAMS: [SweepParam; 2] = [
    SweepParam {
        name: "samples",
        default: ParamDefault::Value(ParamValue::Count(100)),
        min: 1,
        accepts_all: false,
        doc: "midpoint-rule samples per particle chord",
    },
    SweepParam {
        name: "n_exact",
        default: ParamDefault::Value(ParamValue::All),
        min: 1,
        accepts_all: true,
        doc: "particles from the eye that use the lit model (the thesis's N)",
    },
];

/// The GPU methods a sweep can run.
pub static GPU_METHODS: [GpuMethod; 3] = [
    GpuMethod {
        name: "emission",
        method: Method::Emission,
        params: &[],
    },
    GpuMethod {
        name: "opaque",
        method: Method::Opaque,
        params: &[],
    },
    GpuMethod {
        name: "thesis",
        method: Method::Thesis,
        params: &THESIS_PARAMS,
    },
];

impl SweepMethod for GpuMethod {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> &'static [SweepParam] {
        self.params
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
        let params = ApproxParams {
            method: Some(self.method.clone()),
            samples: value_of(values, "samples", 100),
            n_exact: value_of(values, "n_exact", N_EXACT_ALL),
            adapter: None,
        };
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
