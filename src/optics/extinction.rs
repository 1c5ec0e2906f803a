//! Extinction σ of a particle: the whole of docs/design.md §1's rule (thesis eq. 5.1).
//!
//! A particle states its extinction as Θmax, the opacity along a diameter, or as κ. Then
//! σ = λ·κ, and for Θmax, κ = −ln(1 − Θmax)/(λ·2r), so σ = −ln(1 − Θmax)/(2r): λ matters only
//! where κ is given directly.

/// How a particle states its extinction (docs/design.md §1): `opacity` Θmax ∈ [0, 1] or `kappa` κ ≥ 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Extinction {
    /// Θmax, the opacity along a diameter.
    Opacity(f64),
    /// κ in 1/m, scaled by the scene's λ.
    Kappa(f64),
}

impl Extinction {
    /// docs/design.md §1, thesis eq. 5.1: σ = λκ with κ = −ln(1−Θmax)/(λ·2r) for an opacity, so λ
    /// cancels there (computed as [`sigma_from_opacity`], never through κ, which would round
    /// twice); σ = λκ for a κ given directly. `radius` in metres, λ ∈ (0, 1].
    #[inline]
    pub fn sigma(self, radius: f64, lambda: f64) -> f64 {
        match self {
            Extinction::Opacity(o) => sigma_from_opacity(o, radius),
            Extinction::Kappa(k) => lambda * k,
        }
    }

    /// The peak density σᵢ of a Gaussian particle (docs/design.md §9): from an opacity by the
    /// mapping of `optics::gaussian::sigma_from_peak_opacity` with `shortest` the shortest
    /// standard deviation; σ = λκ for a κ given directly, as for every shape.
    #[inline]
    pub fn peak_sigma(self, shortest: f64, lambda: f64) -> f64 {
        match self {
            Extinction::Opacity(o) => super::gaussian::sigma_from_peak_opacity(o, shortest),
            Extinction::Kappa(k) => lambda * k,
        }
    }
}

/// σ = −ln(1 − Θmax)/(2r) (docs/design.md §1, thesis eq. 5.1 with σ = λκ): the extinction that makes
/// a ray through the centre keep 1 − Θmax of its light. Θmax = 1 gives +∞ (a perfectly
/// absorbing ball), Θmax = 0 gives 0. `ln_1p` keeps small opacities exact.
pub fn sigma_from_opacity(opacity: f64, radius: f64) -> f64 {
    if opacity >= 1.0 {
        f64::INFINITY
    } else {
        -(-opacity).ln_1p() / (2.0 * radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmittance_through_the_centre_is_one_minus_opacity() {
        for &o in &[0.0, 1e-12, 0.3, 0.5, 0.999999] {
            let r = 1.7;
            let t = (-sigma_from_opacity(o, r) * 2.0 * r).exp();
            assert!((t - (1.0 - o)).abs() < 1e-15, "{o}: {t}");
        }
        assert_eq!(sigma_from_opacity(1.0, 2.0), f64::INFINITY);
    }

    #[test]
    fn lambda_scales_kappa_but_cancels_for_opacity() {
        assert_eq!(Extinction::Kappa(3.0).sigma(2.0, 0.5), 1.5);
        let o = Extinction::Opacity(0.5);
        assert_eq!(o.sigma(2.0, 0.5), o.sigma(2.0, 1.0));
        assert!((o.sigma(2.0, 0.5) - 2f64.ln() / 4.0).abs() < 1e-15);
        assert_eq!(Extinction::Opacity(1.0).sigma(1.0, 0.3), f64::INFINITY);
    }
}
