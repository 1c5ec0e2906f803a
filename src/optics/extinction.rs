//! Extinction σ of a particle (DESIGN.md §1).

/// σ = −ln(1 − Θmax)/(2r) (DESIGN.md §1, thesis eq. 5.1 with σ = λκ): the extinction that makes
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
}
