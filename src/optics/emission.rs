//! The emission model in closed form (docs/design.md §2, thesis eq. 4.11), composited exactly over
//! the intervals of a ray.

use super::exponential::{small_opacity, SMALL_DEPTH};
use super::intervals::Interval;
use glam::DVec3;

/// Opacity 1 − e^{−σΔ} of a homogeneous piece of optical depth τ = σΔ, via `expm1` so that thin
/// pieces (τ ≪ 1) keep their digits. τ = +∞ (a Θmax = 1 particle) gives exactly 1.
#[inline]
pub fn opacity(tau: f64) -> f64 {
    if tau.is_infinite() {
        1.0
    } else {
        -(-tau).exp_m1()
    }
}

/// Opacity a = 1 − e^{−τ} and transmittance e^{−τ} of a piece of optical depth τ ≥ 0 from one
/// exponential. Below τ = [`SMALL_DEPTH`], a comes from its Taylor series ([`small_opacity`])
/// with its digits, and e = 1 − a is exact to an ulp (e ≥ 0.95); above it `exp` gives e, and
/// a = 1 − e loses at most log2(1/0.05) ≈ 4.3 bits to cancellation, a relative error below
/// 20ε, under the round-off floor (50ε of ∫|f|) that the quadrature's estimate already carries.
/// τ = +∞ gives (1, 0).
#[inline]
pub fn opacity_and_transmittance(tau: f64) -> (f64, f64) {
    if tau < SMALL_DEPTH {
        let a = small_opacity(tau);
        (a, 1.0 - a)
    } else {
        let e = (-tau).exp();
        (1.0 - e, e)
    }
}

/// Radiance and transmittance of a ray through `intervals` (in ray order) towards a background
/// of radiance `background`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Composite {
    /// L = L_bg·T + Σ_k T(0,t0_k)·E_k·(1 − e^{−σ_kΔ_k}).
    pub radiance: DVec3,
    /// T(0, end) = Π_k e^{−σ_kΔ_k}; exactly 0 behind a Θmax = 1 particle.
    pub transmittance: f64,
}

/// docs/design.md §2, emission model, per interval L_in = L_out·e^{−σΔ} + E·(1 − e^{−σΔ}), composited
/// front to back (the same sum, and it stops at the first opaque interval): a Θmax = 1 interval
/// contributes its colour E with weight T and makes everything behind it invisible, without
/// ever forming ∞·0.
pub fn composite(intervals: &[Interval], background: DVec3) -> Composite {
    composite_by(intervals, background, |iv| iv.emission)
}

/// [`composite`] with the constant source Q of each interval given by `source` instead of its
/// emission colour E (docs/design.md §2: the closed form holds for any Q constant per interval;
/// a model without a per-light part has Q = k·E).
#[inline]
pub fn composite_by(
    intervals: &[Interval],
    background: DVec3,
    source: impl Fn(&Interval) -> DVec3,
) -> Composite {
    let mut radiance = DVec3::ZERO;
    let mut transmittance = 1.0;
    for iv in intervals {
        let tau = iv.sigma * iv.length();
        let a = opacity(tau);
        radiance += (transmittance * a) * source(iv);
        if tau.is_infinite() {
            transmittance = 0.0;
            break;
        }
        transmittance *= (-tau).exp();
    }
    Composite {
        radiance: radiance + transmittance * background,
        transmittance,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_exponential_gives_opacity_and_transmittance_to_a_few_ulps() {
        // Against the two-call forms: expm1 for a, exp for e (each correct to an ulp in glibc).
        let mut worst = (0.0f64, 0.0f64);
        for k in 0..=4000 {
            let tau = 1e-12 * 10f64.powf(k as f64 * 15.0 / 4000.0); // 1e-12 … 1e3
            let (a, e) = opacity_and_transmittance(tau);
            let (a0, e0) = (-(-tau).exp_m1(), (-tau).exp());
            worst.0 = worst.0.max(((a - a0) / a0).abs() / f64::EPSILON);
            if e0 > 0.0 {
                worst.1 = worst.1.max(((e - e0) / e0).abs() / f64::EPSILON);
            }
        }
        assert!(worst.0 <= 20.0, "opacity off by {} ε", worst.0);
        assert!(worst.1 <= 2.0, "transmittance off by {} ε", worst.1);
        assert_eq!(opacity_and_transmittance(f64::INFINITY), (1.0, 0.0));
        assert_eq!(opacity_and_transmittance(0.0), (0.0, 1.0));
    }

    fn iv(t0: f64, t1: f64, sigma: f64, e: DVec3) -> Interval {
        Interval {
            t0,
            t1,
            sigma,
            emission: e,
            albedo: e,
        }
    }

    #[test]
    fn one_interval_is_the_closed_form() {
        let bg = DVec3::new(0.3, 0.1, 2.0);
        let c = DVec3::new(1.0, 0.5, 0.0);
        let r = composite(&[iv(1.0, 3.5, 0.7, c)], bg);
        let t = (-0.7f64 * 2.5).exp();
        assert!((r.transmittance - t).abs() < 1e-16);
        assert!((r.radiance - (bg * t + c * (1.0 - t))).abs().max_element() < 1e-15);
    }

    #[test]
    fn back_to_front_equals_front_to_back() {
        let ivs = [
            iv(0.0, 1.0, 0.5, DVec3::X),
            iv(1.0, 1.5, 2.0, DVec3::Y),
            iv(2.0, 4.0, 0.1, DVec3::Z),
        ];
        let bg = DVec3::ONE;
        let mut l = bg;
        for v in ivs.iter().rev() {
            let t = (-v.sigma * v.length()).exp();
            l = l * t + v.emission * (1.0 - t);
        }
        assert!((composite(&ivs, bg).radiance - l).abs().max_element() < 1e-15);
    }

    #[test]
    fn infinite_sigma_hides_what_is_behind() {
        let ivs = [
            iv(0.0, 1.0, 0.5, DVec3::X),
            iv(1.0, 1.5, f64::INFINITY, DVec3::Y),
            iv(2.0, 4.0, 0.1, DVec3::Z),
        ];
        let r = composite(&ivs, DVec3::splat(100.0));
        let t = (-0.5f64).exp();
        assert_eq!(r.transmittance, 0.0);
        assert!(
            (r.radiance - (DVec3::X * (1.0 - t) + DVec3::Y * t))
                .abs()
                .max_element()
                < 1e-15
        );
        assert!(r.radiance.is_finite());
    }
}
