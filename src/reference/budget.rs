//! The error budget of a pixel (docs/design.md §3 "What err guarantees", §9): how each exact
//! renderer shares out `tol`, per pixel and channel, among the parts of err. Every share is a
//! named fraction of `tol` (of each light's share of it, for the constant-density renderer);
//! each renderer's shares sum to at most 1, so a pixel whose parts each keep to their share has
//! err ≤ tol (apart from the float32 rounding of the stored value, which is added on top, and
//! the parts each renderer names as unbudgeted).
//!
//! **Constant density** (`reference::volume`), per light, of the light's share tol/m:
//!
//! | share | fraction | what it pays for |
//! |---|---|---|
//! | [`volume::RAY_TAIL`] | 1e-3 | the far end of the camera ray, bounded instead of integrated; half of the bound is err |
//! | [`volume::SHADOW_STOP`] | 1e-3 | shadow rays stopped where their transmittance has fallen to ε |
//! | [`volume::QUADRATURE`] | the rest | the adaptive quadrature's error estimate |
//!
//! **Gaussian density** (`reference::gaussian`), of tol:
//!
//! | share | fraction | what it pays for |
//! |---|---|---|
//! | [`gaussian::QUADRATURE`] | 5/16 | the quadrature's estimate of the colour deviations and the scattered light |
//! | [`gaussian::BOUNDED`] | 1/8 | colour deviations of pieces bounded in closed form where no light scatters |
//! | [`gaussian::SERIES`] | 1/16 | wide windows of a piece summed as polynomials where no light scatters (their remainder's bound) |
//! | [`gaussian::SHADOW_STOP`] | 1/16 | shadow rays stopped at depth D (the quadrature's where no shadow ray can stop) |
//! | [`gaussian::FAINT`] | 1/8 | faint Gaussians left out whole |
//! | [`gaussian::TAILS`] | 1/8 | the tails outside the kept Gaussians' windows |
//! | [`gaussian::FAR`] | 1/8 | Gaussians the ray does not meet within k σ (the default k) |
//! | [`gaussian::RAY_STOP`] | 1/16 | the far end of a ray stopped behind nearly opaque gas: half of its bound T·M ≤ tol/8 |
//!
//! Unbudgeted, and reported per pixel: the Gaussian renderer's shadow rays miss the same depth
//! as its camera rays, which makes the scattered radiance high by at most (L + err)·(1 − e^{−Δ_far}),
//! about tol/8 (§9).

/// The shares of the constant-density renderer, of each light's share of `tol`.
pub mod volume {
    /// The far end of a camera ray behind nearly opaque gas, taken as a bound instead of
    /// integrated; half of the bound is added to the value, half to err.
    pub const RAY_TAIL: f64 = 1e-3;
    /// Shadow rays that stop where their transmittance has fallen to ε.
    pub const SHADOW_STOP: f64 = 1e-3;
    /// The quadrature's error estimate: what the bounded parts leave.
    pub const QUADRATURE: f64 = 1.0 - 0.5 * RAY_TAIL - SHADOW_STOP;
    /// Every share as err spends it, with its name.
    pub const SHARES: [(&str, f64); 3] = [
        ("ray tail (err half)", 0.5 * RAY_TAIL),
        ("shadow stop", SHADOW_STOP),
        ("quadrature", QUADRATURE),
    ];
}

/// The shares of the Gaussian renderer, of `tol`.
pub mod gaussian {
    /// The quadrature's estimate of the colour deviations and the scattered light.
    pub const QUADRATURE: f64 = 5.0 / 16.0;
    /// The colour deviations of pieces bounded in closed form instead of integrated (where no
    /// light scatters), taken front to back while their half-widths fit.
    pub const BOUNDED: f64 = 1.0 / 8.0;
    /// The windows wide on a piece, summed as one Taylor polynomial in the quadrature's
    /// integrand where no light scatters: the bound on what that changes in the piece's
    /// integral (`reference::series`).
    pub const SERIES: f64 = 1.0 / 16.0;
    /// Shadow rays stopped once e^{−D}·Σ_l q̂_l ≤ this share; where no shadow ray can stop, the
    /// quadrature's.
    pub const SHADOW_STOP: f64 = 1.0 / 16.0;
    /// Faint Gaussians a ray meets, left out whole (their depth in front of the eye, ×M).
    pub const FAINT: f64 = 1.0 / 8.0;
    /// The tails of the kept Gaussians outside their windows (×M).
    pub const TAILS: f64 = 1.0 / 8.0;
    /// The Gaussians a ray does not meet within k σ: the default k is the smallest ≥ 3 that
    /// keeps M·Σᵢ σᵢ·s_max,i·√(2π)·e^{−k²/2} within this share.
    pub const FAR: f64 = 1.0 / 8.0;
    /// Half of the bound T·M of what lies behind a ray stopped where T·M ≤ 2·RAY_STOP·tol.
    pub const RAY_STOP: f64 = 1.0 / 16.0;
    /// Every share as err spends it, with its name.
    pub const SHARES: [(&str, f64); 8] = [
        ("quadrature", QUADRATURE),
        ("bounded deviations", BOUNDED),
        ("wide windows as polynomials", SERIES),
        ("shadow stop", SHADOW_STOP),
        ("faint Gaussians", FAINT),
        ("tails", TAILS),
        ("far Gaussians", FAR),
        ("ray stop (err half)", RAY_STOP),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_renderers_shares_sum_to_at_most_one() {
        for (renderer, shares) in [
            ("volume", &volume::SHARES[..]),
            ("gaussian", &gaussian::SHARES[..]),
        ] {
            let sum: f64 = shares.iter().map(|s| s.1).sum();
            assert!(sum <= 1.0, "{renderer}: the shares sum to {sum}");
            assert!(
                shares.iter().all(|s| s.1 > 0.0),
                "{renderer}: a share is not positive"
            );
        }
    }
}
