//! `riemann`: the exact reference renderer (exact intervals, docs/design.md §3) with the thesis's
//! midpoint Riemann sums instead of adaptive quadrature (`Integrator::Riemann`), so the thesis's
//! integrator can be measured apart from its other approximations. Runs on the CPU.
//!
//! | parameter | default              | meaning |
//! |-----------|----------------------|---------|
//! | `samples` | 100                  | midpoint samples per interval (the thesis's Stützpunktanzahl) |
//! | `spp`     | the reference's spp  | stratified k×k samples per pixel |

use super::method::{
    value_of, ParamDefault, ParamValue, RunImage, SweepContext, SweepMethod, SweepParam,
};
use crate::error::Result;
use crate::reference::{self, Integrator, RenderOptions};
use crate::scene::Scene;

/// The reference with Riemann sums.
pub struct Riemann;

/// The one instance the method table holds.
pub static RIEMANN: Riemann = Riemann;

const PARAMS: [SweepParam; 2] = [
    SweepParam {
        name: "samples",
        default: ParamDefault::Value(ParamValue::Count(100)),
        min: 1,
        max: u32::MAX - 1,
        accepts_all: false,
        quiet_default: false,
        doc: "midpoint samples per interval",
    },
    SweepParam {
        name: "spp",
        default: ParamDefault::ReferenceSpp,
        min: 1,
        max: crate::reference::MAX_SPP,
        accepts_all: false,
        quiet_default: false,
        doc: "stratified k×k samples per pixel",
    },
];

impl SweepMethod for Riemann {
    fn name(&self) -> &'static str {
        "riemann"
    }

    fn params(&self) -> &[SweepParam] {
        &PARAMS
    }

    fn check_scene(&self, _scene: &Scene) -> Result<()> {
        Ok(())
    }

    fn render(
        &self,
        ctx: &mut SweepContext,
        scene: &Scene,
        values: &[(&'static str, u32)],
    ) -> Result<RunImage> {
        let options = RenderOptions {
            spp: value_of(values, "spp", 1),
            threads: ctx.threads,
            progress: false,
            integrator: Integrator::Riemann {
                samples: value_of(values, "samples", 100),
            },
        };
        Ok(RunImage {
            image: reference::render(scene, &options)?.image,
            gpu_seconds: None,
            warnings: Vec::new(),
        })
    }
}
