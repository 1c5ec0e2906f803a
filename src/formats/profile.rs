//! The density profile of a particle (docs/design.md §9): how its density fills its shape. It
//! is here, with what files say about particles, so that the readers and the optics both name
//! it (the optics build on `formats`, never the reverse).

/// The density profile of a particle (docs/design.md §9 "Gaussian density").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// σ inside the sphere or ellipsoid, 0 outside (the thesis).
    #[default]
    Constant,
    /// σ·exp(−½·m(x)²), m the Mahalanobis distance whose axes are the radius or the semi-axes
    /// taken as standard deviations; `sigma` is the peak density at the centre. The support is
    /// unbounded: the shape is the 1-σ ellipsoid, not an edge.
    Gaussian,
}

impl Profile {
    /// The name in scene files (`density = "gaussian"`).
    pub fn name(self) -> &'static str {
        match self {
            Profile::Constant => "constant",
            Profile::Gaussian => "gaussian",
        }
    }
}

impl Profile {
    /// The optical depth through the centre of a particle along its shortest axis, of extent
    /// `shortest` (the radius, the shortest semi-axis or the shortest standard deviation) and
    /// (peak) density `sigma`: 2·r·σ for constant density (docs/design.md §1), √(2π)·s·σ for a
    /// Gaussian (§9). The particle's opacity is 1 − e^{−depth}.
    pub fn centre_depth(self, shortest: f64, sigma: f64) -> f64 {
        match self {
            Profile::Constant => 2.0 * shortest * sigma,
            Profile::Gaussian => SQRT_TAU * shortest * sigma,
        }
    }
}

/// √(2π).
const SQRT_TAU: f64 = 2.506_628_274_631_000_5;
