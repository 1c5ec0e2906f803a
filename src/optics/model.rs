//! What an optical model is (docs/design.md §2): the source term Q of
//!
//!   L = L_bg·T(0,∞) + ∫₀^∞ T(0,t)·σ(x_t)·Q(x_t) dt
//!
//! split into a part that is constant inside an interval of fixed particles, k·E(x), and a part
//! that is a sum over the lights of what the shadow ray towards each light found. The models
//! are in `models/`, one file each, listed in the registry `models::ALL`; the renderer asks the
//! model and never matches on its name.

use super::intervals::Interval;
use super::source::{LightSample, SourceParams};
use glam::DVec3;
use std::fmt;

/// What a model's per-light part needs from the shadow ray towards each light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightNeed {
    /// No per-light part: Q = k·E is constant inside an interval, so the emission closed form
    /// L_in = L_out·e^{−σΔ} + Q·(1 − e^{−σΔ}) is exact and no shadow ray is traced.
    None,
    /// L_l(x): the emission model along the shadow ray, the light as its background (lit).
    Radiance,
    /// E_l(x)·T_l(x): the unoccluded irradiance and the transmittance to the light
    /// (single-scatter). The renderer then traces the transmittance alone, one sum of σᵢ·chordᵢ
    /// per shadow ray, and leaves [`LightSample::radiance`] at zero: such a model must not read
    /// it (a test in `optics::models` checks every model).
    ///
    /// [`LightSample::radiance`]: super::source::LightSample::radiance
    IrradianceTransmittance,
}

/// An optical model of docs/design.md §2: Q(x) = k·E(x) + Σ_l q_l(x), where E is the σ-weighted
/// emission colour of the particles at x and q_l the part of light l.
///
/// The renderer integrates the per-light parts one light at a time (Q is linear in the lights)
/// and the constant part in closed form; [`OpticalModel::source`] is the whole Q, for the Riemann sums
/// and the Θmax = 1 limit. Each implementation's file opens with a table citing docs/design.md §2.
pub trait OpticalModel: Sync + Send {
    /// The name in scene files and on the command line (`model = "lit"`, `--model lit`).
    fn name(&self) -> &'static str;
    /// One line for `--help` and the docs.
    fn summary(&self) -> &'static str;
    /// What [`OpticalModel::light_source`] reads from each light's shadow ray.
    fn light_need(&self) -> LightNeed;
    /// k of the constant part k·E(x) of Q.
    fn emission_factor(&self, params: &SourceParams) -> f64;
    /// q_l(x), the part of Q that one light contributes, at a point inside `interval`.
    ///
    /// Must be ≥ 0 and non-decreasing in the sample's radiance, irradiance and transmittance and
    /// in the interval's emission and albedo (true of every model of docs/design.md §2, which are
    /// products and sums of them with non-negative weights): the renderer bounds the far end of
    /// a nearly opaque ray by this function of their largest values, and puts that bound into
    /// err instead of integrating it (`reference::volume`, `VolumeRenderer::tail_cut`). It must
    /// also be linear in the shadow ray's radiance and transmittance together, at a fixed
    /// irradiance (lit: w·L_l; single-scatter: α·E_l·T_l/4π), so that a shadow ray cut where
    /// its transmittance has fallen to ε changes q_l by at most ε/2 of that bound
    /// (`VolumeRenderer::shadow_cut`; a test in `optics::models` checks every model).
    fn light_source(
        &self,
        params: &SourceParams,
        interval: &Interval,
        light: &LightSample,
    ) -> DVec3;
    /// Q(x) whole, given the samples of every light that reaches x, at a point inside
    /// `interval`. Equal to k·E + Σ q_l up to rounding (each model writes it in the order its
    /// equation does).
    fn source(&self, params: &SourceParams, interval: &Interval, lights: &[LightSample]) -> DVec3;
    /// Q∞, the Θmax = 1 (σ → ∞) limit of Q at the surface where the ray enters an opaque
    /// particle, given each light's sample already taken to its surface limit
    /// ([`LightSample::surface_limit`]). Q is linear in the samples for every model of
    /// docs/design.md §2, so the limit is Q of the limit samples; a model that is not overrides this.
    fn opaque_limit(
        &self,
        params: &SourceParams,
        interval: &Interval,
        lights: &[LightSample],
    ) -> DVec3 {
        self.source(params, interval, lights)
    }
}

/// The `model` of a scene (docs/design.md §1 `[render]`): a handle on one entry of the registry
/// `models::ALL`. Copy, compared by name, read from TOML and the command line by name; an
/// unknown name is an error that lists the valid ones.
#[derive(Clone, Copy)]
pub struct Model(&'static dyn OpticalModel);

impl Model {
    /// Wraps a model; the registry does this once per model.
    pub const fn new(model: &'static dyn OpticalModel) -> Self {
        Model(model)
    }

    /// The model behind the handle.
    #[inline]
    pub fn model(self) -> &'static dyn OpticalModel {
        self.0
    }
}

impl std::ops::Deref for Model {
    type Target = dyn OpticalModel;
    #[inline]
    fn deref(&self) -> &(dyn OpticalModel + 'static) {
        self.0
    }
}

impl PartialEq for Model {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Model {}

impl std::hash::Hash for Model {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state)
    }
}

impl fmt::Debug for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Model({:?})", self.name())
    }
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
