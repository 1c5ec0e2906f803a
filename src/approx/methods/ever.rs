//! # `ever` — EVER's exact ellipsoid volume rendering in float32, with its cut-offs
//!
//! The algorithm of EVER (Mai et al. 2024, "EVER: Exact Volumetric Ellipsoid Rendering for
//! Real-time View Synthesis"), docs/design.md §4: the entry and exit events of the particles
//! along the camera ray in order of t, the gas constant between two events (σ the sum over the
//! particles the ray is inside, the colour their σ-weighted mean), each segment composited with
//! the emission model's closed form (`shaders/ever.wgsl`). Overlaps are exact; what differs from
//! the reference is float32 (the running sums, added at entries and subtracted at exits, as EVER
//! keeps them) and EVER's cut-offs, here parameters so that their cost is measured: the events
//! per batch (one BVH traversal each), the transmittance at which a ray stops, and the most
//! batches a ray takes. Volume mode, emission model; spheres and ellipsoids.
//!
//! | parameter | default | range | meaning |
//! |---|---|---|---|
//! | `batch` | 16 | 1..=64 | events per BVH traversal (EVER: 16 hits per trace) |
//! | `stop_below` | 4000 | 0..=1000000 | the ray stops when its transmittance falls below this many millionths (EVER: 0.004) |
//! | `max_batches` | 400 | 1..=16777216 | batches (traversals) a ray takes at most (EVER: 400 iterations) |
//!
//! `--param stop_below=0 --param max_batches=16777216` removes the cut-offs: what remains is
//! float32's share.
//!
//! ```sh
//! pgt approx scene.toml --method ever --model emission -o ever.exr
//! ```

use crate::approx::shader::{WgslModule, NEAREST_EVENTS};
use super::{ApproxMethod, Computes};
use crate::approx::contract::EVER_MAX_BATCH;
use crate::approx::param_spec::ParamSpec;
use crate::optics::models;

/// The `ever` method (see the module docs).
pub struct Ever;

/// The parameters; `batch` is bounded by the shader's batch arrays ([`EVER_MAX_BATCH`]).
const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "batch",
        quiet_default: false,
        default: 16,
        min: 1,
        max: EVER_MAX_BATCH,
        doc: "events per BVH traversal (EVER: 16 hits per trace)",
    },
    ParamSpec {
        name: "stop_below",
        quiet_default: false,
        default: 4000,
        min: 0,
        max: 1_000_000,
        doc: "the ray stops when its transmittance falls below this many millionths (EVER: 0.004)",
    },
    ParamSpec {
        name: "max_batches",
        quiet_default: false,
        default: 400,
        min: 1,
        max: 1 << 24,
        doc: "batches (traversals) a ray takes at most (EVER: 400 iterations)",
    },
];

impl ApproxMethod for Ever {
    fn name(&self) -> &'static str {
        "ever"
    }
    fn summary(&self) -> &'static str {
        "EVER's algorithm in float32: entry/exit events in order, piecewise-constant σ and colour, its cut-offs as parameters; volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/ever.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/ever.wgsl")
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn modules(&self) -> &'static [WgslModule] {
        &[NEAREST_EVENTS]
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
}
