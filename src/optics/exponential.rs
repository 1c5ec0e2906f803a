//! 1 − e^{−τ} of thin pieces for the composites of shadow rays (docs/design.md §2, emission
//! model: one exponential per interval).
//!
//! Why not `f64::exp_m1`: glibc's `expm1` costs several times its `exp`, and thin pieces
//! (chords that end close together) are common in a shadow ray's composite through
//! overlapping atoms; the polynomial below, inlined, costs a fraction of it. Thicker pieces
//! keep `f64::exp` (docs/performance.md, "Exponentials").

/// 1 − e^{−τ} = −expm1(−τ) for 0 ≤ τ < [`SMALL_DEPTH`] (and NaN for NaN), as τ·p(τ) with p
/// the Taylor series Σ_{k<9} (−τ)^k/(k+1)!. The first term left out, τ⁹/10!, is below 6e-19
/// of p (τ < 0.05), and p ≥ 0.975 with terms of alternating sign and falling size, so its
/// Estrin evaluation rounds to within about 1 ulp of `expm1` (tested over the range). Thin
/// pieces (chords that end close together) are common in a shadow ray's composite through
/// overlapping atoms.
#[inline]
pub fn small_opacity(tau: f64) -> f64 {
    // c_k = (−1)^k/(k+1)!, k = 0..8.
    const C: [f64; 9] = [
        1.0,
        -1.0 / 2.0,
        1.0 / 6.0,
        -1.0 / 24.0,
        1.0 / 120.0,
        -1.0 / 720.0,
        1.0 / 5040.0,
        -1.0 / 40320.0,
        1.0 / 362880.0,
    ];
    let t2 = tau * tau;
    let t4 = t2 * t2;
    let low = (C[0] + C[1] * tau) + t2 * (C[2] + C[3] * tau);
    let high = (C[4] + C[5] * tau) + t2 * (C[6] + C[7] * tau);
    tau * (low + t4 * (high + t4 * C[8]))
}

/// The optical depth below which [`small_opacity`] is meant (and exact to its last digits).
pub const SMALL_DEPTH: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative difference in units of ε.
    fn ulps(got: f64, want: f64) -> f64 {
        ((got - want) / want).abs() / f64::EPSILON
    }

    #[test]
    fn small_opacity_has_the_digits_of_expm1() {
        // Against glibc's expm1 (correct to an ulp), over [0, SMALL_DEPTH) on a log and a
        // linear grid, and at the ends.
        let mut worst = 0.0f64;
        let log = (0..=3000).map(|k| 1e-300 * 10f64.powf(k as f64 * 298.7 / 3000.0));
        let linear = (0..=3000).map(|k| SMALL_DEPTH * k as f64 / 3000.0);
        for tau in log.chain(linear).filter(|&t| t < SMALL_DEPTH) {
            let (got, want) = (small_opacity(tau), -(-tau).exp_m1());
            if want == 0.0 {
                assert_eq!(got, 0.0, "τ = {tau}");
            } else {
                worst = worst.max(ulps(got, want));
            }
        }
        assert!(worst <= 1.0, "small_opacity off by {worst} ε");
        let below = SMALL_DEPTH * (1.0 - f64::EPSILON);
        assert!(ulps(small_opacity(below), -(-below).exp_m1()) <= 1.0);
        assert!(small_opacity(f64::NAN).is_nan());
    }
}
