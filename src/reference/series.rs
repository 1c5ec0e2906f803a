//! The Gaussians whose windows are wide on a piece of a ray, summed once as one polynomial
//! (docs/design.md §9 "Gaussian density"): their density and colour-weighted density as Taylor
//! polynomials about the piece's middle, and their optical depth from the piece's start as the
//! polynomial's integral, with a bound on what the polynomials leave out.
//!
//! A Gaussian along the ray, g(t) = p·e^{−½((t − t*)/s)²}, has about c, with z = (c − t*)/s,
//! x = t − c and r = h/(2s) on a piece [c − h/2, c + h/2],
//!
//!   g(c + x) = p·e^{−½z²}·Σₙ (−1)ⁿ·Heₙ(z)/n!·(x/s)ⁿ,
//!
//! Heₙ the probabilists' Hermite polynomials. Cut after degree N, the Lagrange remainder is
//! p·|He_{N+1}(u)|·e^{−½u²}·(|x|/s)^{N+1}/(N+1)! for some u between z and z + x/s, and Cramér's
//! inequality |Heₙ(u)|·e^{−¼u²} ≤ K·√(n!) (K = 1.086435) bounds it by
//!
//!   p·K·e^{−¼u_min²}·r^{N+1}/√((N+1)!),   u_min = max(0, |z| − r).
//!
//! A Gaussian costs one exp and N steps of the Hermite recurrence a piece, instead of an erfc
//! and an exp at every node of the quadrature; each node costs two polynomials whatever the
//! number of Gaussians in them. The rounding of the recurrence and of the sums is bounded by a
//! generous multiple of ε times the sum of the recurrence's terms in absolute value, and is
//! added to the remainder.

use glam::DVec3;

/// The degree of the polynomials.
pub const DEGREE: usize = 16;

/// The largest r = h/(2s) of a Gaussian summed into a polynomial: beyond it the remainder
/// shrinks too slowly with the degree.
pub const MAX_HALF_WIDTH: f64 = 1.0;

/// Cramér's constant: |Heₙ(u)|·e^{−¼u²} ≤ K·√(n!) for every real u and n ≥ 0.
const CRAMER: f64 = 1.086_435;

/// A factor on ε·Σ|terms| that covers the rounding of the recurrence (a few operations a
/// step, each of relative error ≤ ε on terms bounded by the absolute recurrence), of exp (one
/// ulp), of the sums over Gaussians and of Horner's rule at |x̂| ≤ 1.
const ROUNDING: f64 = 16.0 * (DEGREE as f64 + 2.0) * f64::EPSILON;

/// 1/k for k = 1..=N+1: the recurrence multiplies instead of dividing.
const RECIPROCAL: [f64; DEGREE + 1] = [
    1.0,
    0.5,
    0.3333333333333333,
    0.25,
    0.2,
    0.16666666666666666,
    0.14285714285714285,
    0.125,
    0.1111111111111111,
    0.1,
    0.09090909090909091,
    0.08333333333333333,
    0.07692307692307693,
    0.07142857142857142,
    0.06666666666666667,
    0.0625,
    0.058823529411764705,
];

/// 1/√k for k = 1..=N+1: r^{n+1}/√((n+1)!) grows from r^n/√(n!) by r/√(n+1).
const INV_SQRT: [f64; DEGREE + 1] = [
    1.0,
    0.7071067811865475,
    0.5773502691896258,
    0.5,
    0.4472135954999579,
    0.4082482904638631,
    0.3779644730092272,
    0.35355339059327373,
    0.3333333333333333,
    0.31622776601683794,
    0.30151134457776363,
    0.2886751345948129,
    0.2773500981126146,
    0.2672612419124244,
    0.2581988897471611,
    0.25,
    0.24253562503633297,
];

/// A Gaussian takes the lowest degree whose remainder is at most this fraction of its peak
/// density (or [`DEGREE`]).
const REMAINDER_TARGET: f64 = 1e-13;

/// The degree n ≤ [`DEGREE`] a Gaussian with r = h/(2s) takes, and r^{n+1}/√((n+1)!), the
/// remainder's factor (rounded up: the tables' rounding is ≤ 1e-16 relative a factor).
fn degree_for(r: f64) -> (usize, f64) {
    let mut n = 0;
    let mut factor = r;
    while n < DEGREE && factor > REMAINDER_TARGET / CRAMER {
        n += 1;
        factor *= r * INV_SQRT[n];
    }
    (n, factor * (1.0 + 1e-14))
}

/// The wide Gaussians of one piece [lo, hi]: in x̂ = (t − c)/(h/2) ∈ [−1, 1], the density
/// Σ Aₙ·x̂ⁿ and the colour-weighted density Σ Bₙ·x̂ⁿ, and a bound on how far each is from the
/// true sums on the piece.
#[derive(Debug, Clone)]
pub struct WideSum {
    center: f64,
    half: f64,
    density: [f64; DEGREE + 1],
    weighted: [DVec3; DEGREE + 1],
    /// The depth polynomial Σ Pₖ·x̂ᵏ = ∫_lo^t density, filled by [`WideSum::finish`].
    depth: [f64; DEGREE + 2],
    /// A bound on |true density − Σ Aₙx̂ⁿ| on the piece.
    density_error: f64,
    /// Per channel, a bound on |true colour-weighted density − Σ Bₙx̂ⁿ|.
    weighted_error: DVec3,
    /// The highest degree any Gaussian of the sum took.
    degree: usize,
    count: usize,
}

impl WideSum {
    /// An empty sum over the piece [lo, hi] (lo < hi).
    pub fn new(lo: f64, hi: f64) -> WideSum {
        WideSum {
            center: 0.5 * (lo + hi),
            half: 0.5 * (hi - lo),
            density: [0.0; DEGREE + 1],
            weighted: [DVec3::ZERO; DEGREE + 1],
            depth: [0.0; DEGREE + 2],
            density_error: 0.0,
            weighted_error: DVec3::ZERO,
            degree: 0,
            count: 0,
        }
    }

    /// Adds a Gaussian of peak density `peak`, centre `t_star` and standard deviation `s` along
    /// the ray, whose colour deviates from the piece's reference by `deviation`; r must be at
    /// most [`MAX_HALF_WIDTH`]. Returns the bound on its density's error on the piece (its
    /// remainder and rounding).
    pub fn add(&mut self, peak: f64, t_star: f64, s: f64, deviation: DVec3) -> f64 {
        let r = self.half / s;
        debug_assert!(r <= MAX_HALF_WIDTH);
        let (degree, factor) = degree_for(r);
        let z = (self.center - t_star) / s;
        let scale = peak * (-0.5 * z * z).exp();
        // eₙ = (−1)ⁿ·Heₙ(z)/n!·rⁿ·scale: e_{n+1} = (−z·r·eₙ − r²·e_{n−1})/(n + 1); mₙ the same
        // recurrence in absolute values, a bound of every term it adds.
        let (a, b) = (-z * r, -r * r);
        let (mut e_prev, mut e) = (0.0, scale);
        let (mut m_prev, mut m) = (0.0, 1.0);
        let mut magnitude = 0.0;
        let terms = self.density[..=degree]
            .iter_mut()
            .zip(&mut self.weighted[..=degree])
            .zip(&RECIPROCAL);
        for ((density, weighted), reciprocal) in terms {
            *density += e;
            *weighted += e * deviation;
            magnitude += m;
            let next = (a * e + b * e_prev) * reciprocal;
            (e_prev, e) = (e, next);
            let m_next = (z.abs() * r * m + r * r * m_prev) * reciprocal;
            (m_prev, m) = (m, m_next);
        }
        self.degree = self.degree.max(degree);
        // Cramér's bound, with e^{−¼u_min²} where it can matter.
        let mut remainder = peak * CRAMER * factor;
        if factor > REMAINDER_TARGET {
            let u_min = (z.abs() - r).max(0.0);
            remainder *= (-0.25 * u_min * u_min).exp();
        }
        let error = remainder + ROUNDING * scale * magnitude;
        self.density_error += error;
        self.weighted_error += error * deviation.abs();
        self.count += 1;
        error
    }

    /// How many Gaussians the sum holds.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether the sum holds none.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Integrates the density polynomial into the depth from `lo`: ∫_lo^t = (h/2)·∫_{−1}^{x̂}.
    pub fn finish(&mut self) {
        let mut at_lo = 0.0;
        let mut sign = -1.0;
        let terms = self.density[..=self.degree].iter().zip(&RECIPROCAL);
        for (n, (density, reciprocal)) in terms.enumerate() {
            let p = self.half * density * reciprocal;
            self.depth[n + 1] = p;
            at_lo += p * sign;
            sign = -sign;
        }
        self.depth[0] = -at_lo;
    }

    /// The depth from the piece's start to t and the colour-weighted density at t, for t in
    /// the piece ([`WideSum::finish`] first).
    #[inline]
    pub fn at(&self, t: f64) -> (f64, DVec3) {
        let x = (t - self.center) / self.half;
        let top = self.degree;
        let mut depth = self.depth[top + 1];
        for k in (0..=top).rev() {
            depth = depth * x + self.depth[k];
        }
        let mut weighted = self.weighted[top];
        for k in (0..top).rev() {
            weighted = weighted * x + self.weighted[k];
        }
        (depth, weighted)
    }

    /// A bound, per channel, on how far ∫ over the piece of e^{−τ}·(deviation density) moves
    /// when the wide Gaussians' exact depth and density are replaced by the polynomials: with
    /// ε_τ = h·(density error) a bound of the depth's error at any t (the remainder's part grows
    /// as (t − lo)·remainder, the rounding's is at most h times its part), the integrand's error
    /// is at most
    /// e^{ε_τ}·(ε_τ·|D(t)| + e_D) at every t (|e^{−τ} − e^{−τ'}| ≤ e^{−min(τ, τ')}·|τ − τ'|,
    /// and τ' ≥ −ε_τ as τ ≥ 0), so its integral is at most e^{ε_τ}·(ε_τ·Σⱼ dⱼ·|ΔCⱼ| + h·e_D),
    /// where `deviation_depth` is Σⱼ dⱼ·|ΔCⱼ| over every Gaussian of the piece (dⱼ its depth
    /// on the piece: the integral of |D|).
    pub fn integral_error(&self, deviation_depth: DVec3) -> DVec3 {
        let h = 2.0 * self.half;
        let eps_tau = h * self.density_error;
        eps_tau.exp() * (eps_tau * deviation_depth + h * self.weighted_error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::gaussian::GaussianAlongRay;

    fn profile(t_star: f64, s: f64, peak: f64) -> GaussianAlongRay {
        GaussianAlongRay { t_star, s, peak }
    }

    /// The polynomials against the closed forms (erfc depths, exp densities) at points across
    /// the piece, for Gaussians centred inside, at the edge of and far from the piece, at
    /// r from 0.01 to 1: the difference is within the bound, and the bound is small where r is.
    #[test]
    fn the_polynomials_match_the_closed_forms_within_their_bound() {
        let (lo, hi) = (2.0, 2.5);
        for &(t_star, s, peak, colour) in &[
            (2.2, 0.25, 3.0, DVec3::new(0.5, -0.2, 0.0)),
            (2.0, 0.3, 1.0, DVec3::new(-1.0, 0.3, 0.2)),
            (-1.0, 0.5, 50.0, DVec3::new(0.1, 0.1, 0.1)),
            (6.0, 0.9, 2.0, DVec3::new(0.0, 1.0, -1.0)),
            (2.3, 25.0, 0.4, DVec3::new(0.7, 0.7, 0.1)),
        ] {
            let mut sum = WideSum::new(lo, hi);
            let error = sum.add(peak, t_star, s, colour);
            sum.finish();
            let g = profile(t_star, s, peak);
            let from = g.depth_from(lo);
            for i in 0..=40 {
                let t = lo + (hi - lo) * i as f64 / 40.0;
                let (depth, weighted) = sum.at(t);
                let exact_depth = from.to(t);
                let exact_density = g.density(t);
                assert!(
                    (depth - exact_depth).abs() <= error * (hi - lo) + 1e-15 * exact_depth,
                    "t* {t_star} s {s}: depth {depth} vs {exact_depth} at {t}, bound {error}"
                );
                let dev = (weighted - exact_density * colour).abs();
                assert!(
                    dev.cmple(error * colour.abs() + DVec3::splat(1e-300)).all(),
                    "t* {t_star} s {s}: weighted density off by {dev} at {t}, bound {error}"
                );
            }
            let r = 0.25 / s;
            if r <= 0.5 {
                assert!(error <= 1e-8 * peak, "r {r}: the bound {error} is loose");
            }
        }
    }

    #[test]
    fn the_tables_hold_what_they_name() {
        for k in 1..=DEGREE + 1 {
            assert_eq!(RECIPROCAL[k - 1], 1.0 / k as f64);
            assert_eq!(INV_SQRT[k - 1], 1.0 / (k as f64).sqrt());
        }
        // The remainder's factor against r^{n+1}/√((n+1)!) computed directly.
        for r in [0.01, 0.1, 0.5, 1.0] {
            let (n, factor) = degree_for(r);
            let direct =
                r.powi(n as i32 + 1) / (1..=n + 1).map(|k| k as f64).product::<f64>().sqrt();
            assert!(
                factor >= direct && factor <= direct * (1.0 + 1e-13),
                "r {r}"
            );
            assert!(n == DEGREE || factor <= REMAINDER_TARGET);
        }
    }

    /// Many Gaussians summed: the depth at the end is the sum of their closed-form depths
    /// within the summed bound, and the bound on the integral is ≥ the integral's true change.
    #[test]
    fn a_sum_of_many_matches_the_sum_of_the_closed_forms() {
        let (lo, hi) = (10.0, 10.3);
        let mut sum = WideSum::new(lo, hi);
        let mut exact = 0.0;
        let mut bound = 0.0;
        for i in 0..200 {
            let x = i as f64;
            let (t_star, s, peak) = (9.0 + 0.013 * x, 0.16 + 0.01 * (x % 7.0), 0.5 + (x % 5.0));
            bound += sum.add(peak, t_star, s, DVec3::ZERO);
            exact += profile(t_star, s, peak).optical_depth(lo, hi);
        }
        sum.finish();
        let (depth, _) = sum.at(hi);
        assert!((depth - exact).abs() <= bound * (hi - lo) + 1e-13 * exact);
        assert!(sum.len() == 200 && !sum.is_empty());
    }
}
