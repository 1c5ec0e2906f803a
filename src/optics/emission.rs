//! The emission model in closed form (docs/design.md §2, thesis eq. 4.11), composited exactly over
//! the intervals of a ray: [`composite`] over intervals known in advance (a camera ray), and
//! [`FrontToBack`] while they are being found (a shadow ray, which may stop early).

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

/// The emission model composited front to back while the intervals are still being found (a
/// shadow ray's, `optics::cutter` and `reference::shadow`): the same closed form as
/// [`composite`], with two differences that let it stop early and save exponentials. It may
/// stop where the transmittance has fallen to a given ε (then [`FrontToBack::finish`] bounds
/// what lies behind), and consecutive pieces of the same colour are composited as one. Its
/// opacity comes from [`opacity_and_transmittance`], so its last bits may differ from
/// [`composite`]'s.
#[derive(Debug, Clone, Copy)]
pub struct FrontToBack {
    radiance: DVec3,
    transmittance: f64,
    /// Transmittance at or below which nothing more is added (0: only an opaque stop).
    stop_at: f64,
    /// The run of intervals added since the last flush, all of this emission E, and their
    /// summed optical depth Σσ·Δ (0 and NaN emission: none).
    run_emission: DVec3,
    run_depth: f64,
}

impl FrontToBack {
    /// Nothing composited yet; stopping where T falls to the cut's ε, if any (`cut` is (ε, M):
    /// see [`FrontToBack::finish`]).
    pub fn new(cut: Option<(f64, DVec3)>) -> Self {
        FrontToBack {
            radiance: DVec3::ZERO,
            transmittance: 1.0,
            stop_at: cut.map_or(0.0, |(epsilon, _)| epsilon),
            run_emission: DVec3::NAN,
            run_depth: 0.0,
        }
    }

    /// Adds a homogeneous piece of finite extinction σ, σ-weighted colour S = Σσᵢ·Cᵢ and the
    /// given length; false once nothing more is to be added (T ≤ `stop_at`). E = S·(1/σ) is
    /// formed before the exponential, which it does not depend on: dividing after it (T·a/σ)
    /// put the division's latency on the path from each exponential to the running sums.
    #[inline]
    pub fn add(&mut self, sigma: f64, weighted: DVec3, length: f64) -> bool {
        self.add_emission(sigma, weighted * (1.0 / sigma), length)
    }

    /// [`FrontToBack::add`] with E = S·(1/σ) formed by the caller. Consecutive pieces of the
    /// same E (bit for bit) are one homogeneous source behind each other: their composite is
    /// T·(1 − e^{−Σσ·Δ})·E, so their depths are summed and composited as one, with one
    /// exponential (on a shadow ray, one particle is often followed by
    /// another of the same colour). T is checked against `stop_at` where a run ends.
    #[inline]
    pub fn add_emission(&mut self, sigma: f64, emission: DVec3, length: f64) -> bool {
        if emission == self.run_emission {
            self.run_depth += sigma * length;
            return true;
        }
        if !self.flush() {
            return false;
        }
        self.run_emission = emission;
        self.run_depth = sigma * length;
        true
    }

    /// Composites the pending run; false once nothing more is to be added.
    #[inline]
    pub fn flush(&mut self) -> bool {
        if self.run_depth != 0.0 {
            let (a, e) = opacity_and_transmittance(self.run_depth);
            self.radiance += (self.transmittance * a) * self.run_emission;
            self.transmittance *= e;
        }
        self.run_emission = DVec3::NAN;
        self.run_depth = 0.0;
        self.transmittance > self.stop_at
    }

    /// Adds an interval as [`composite`] does (σ may be ∞).
    pub fn add_interval(&mut self, iv: Interval) -> bool {
        if !self.flush() {
            return false;
        }
        if iv.sigma.is_infinite() {
            self.radiance += self.transmittance * iv.emission;
            self.transmittance = 0.0;
        } else {
            let (a, e) = opacity_and_transmittance(iv.sigma * iv.length());
            self.radiance += (self.transmittance * a) * iv.emission;
            self.transmittance *= e;
        }
        self.transmittance > self.stop_at
    }

    /// The end of the composite: the background behind what was composited, or, where the
    /// composite stopped with something still visible behind, the middle of what the rest
    /// could add (also where the stop came at the last interval: conservative, and within the
    /// same bound); whether it stopped so.
    ///
    /// With `cut = Some((ε, M))` the composite stops once T has fallen to ε or below (after the
    /// piece that took it there); what lies behind contributes T·L_rest with 0 ≤ L_rest ≤ M per
    /// channel (M ≥ `background` and every colour behind, a caller's bound), so the radiance
    /// becomes F + T·M/2 and the transmittance T/2, each off by at most half its range (T·M/2
    /// and T/2, both ≤ ε·(M, 1)/2). An exactly opaque stop (T = 0) is exact and is not a cut.
    pub fn finish(mut self, background: DVec3, cut: Option<(f64, DVec3)>) -> (Composite, bool) {
        self.flush();
        let t = self.transmittance;
        match cut {
            Some((epsilon, bound)) if t > 0.0 && t <= epsilon => (
                Composite {
                    radiance: self.radiance + t * (0.5 * bound),
                    transmittance: 0.5 * t,
                },
                true,
            ),
            _ => (
                Composite {
                    radiance: self.radiance + t * background,
                    transmittance: t,
                },
                false,
            ),
        }
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
