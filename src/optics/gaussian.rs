//! The Gaussian density profile along a ray (docs/design.md §9 "Gaussian density"): the optical
//! depth in closed form, and the opacity mapping from a splatting file's peak opacity to σᵢ.
//!
//! A Gaussian particle has the density σ(x) = σᵢ·exp(−½·m(x)²), m the Mahalanobis distance whose
//! axes are the ellipsoid's semi-axes taken as standard deviations: m(x) = |M(x − c)|, M = S⁻¹Rᵀ
//! ([`Ellipsoid`]). Along a ray o + t·d the mapped point is u(t) = u₀ + t·v (u₀ = M(o − c),
//! v = Md), so m(t)² = m*² + ((t − t*)/s)² with
//!
//! * t* = −u₀·v/|v|², the ray's closest approach in the Mahalanobis metric,
//! * s = 1/|v|, the profile's standard deviation along the ray (in t),
//! * m* = |u₀ − (u₀·v̂)v̂|, the Mahalanobis distance at t*,
//!
//! and the density along the ray is the 1D Gaussian σᵢ·e^{−½m*²}·e^{−½((t − t*)/s)²}. Its optical
//! depth over [t₀, t₁] is
//!
//!   τ = σᵢ·e^{−½m*²}·s·√(π/2)·[erf(b) − erf(a)],   a = (t₀ − t*)/(√2·s), b = (t₁ − t*)/(√2·s).
//!
//! The difference of two erf is computed without cancellation: where both arguments lie on the
//! same side of 0 it is the difference of two erfc of the arguments' magnitudes, which are small
//! and exact to a few ulp far in the tails, where erf(b) − erf(a) would subtract two numbers that
//! both round to ±1 (`libm`'s erf and erfc, the rust-lang port of FreeBSD's, accurate to < 1 ulp).

use crate::geometry::{Ellipsoid, Ray};
use glam::DVec3;

/// √(π/2).
const SQRT_HALF_PI: f64 = 1.253_314_137_315_500_3;

/// erf(b) − erf(a) for a ≤ b, without cancellation in the tails.
pub fn erf_difference(a: f64, b: f64) -> f64 {
    if a >= 0.0 {
        // Both ≥ 0: 1 − erf is small and exact in erfc.
        libm::erfc(a) - libm::erfc(b)
    } else if b <= 0.0 {
        // Both ≤ 0: by symmetry erf(b) − erf(a) = erfc(−b) − erfc(−a).
        libm::erfc(-b) - libm::erfc(-a)
    } else {
        // Opposite signs: a sum of two positive terms.
        libm::erf(b) + libm::erf(-a)
    }
}

/// A Gaussian particle's density along one ray: σᵢ·e^{−½m*²}·e^{−½((t − t*)/s)²}.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianAlongRay {
    /// The closest approach t* (Mahalanobis metric).
    pub t_star: f64,
    /// The standard deviation along the ray, s = 1/|Md|.
    pub s: f64,
    /// The density at t*: σᵢ·e^{−½m*²}.
    pub peak: f64,
}

impl GaussianAlongRay {
    /// The profile of the Gaussian with centre `center`, standard deviations and orientation
    /// `shape` and peak density `sigma` along `ray` (unit direction).
    pub fn new(ray: &Ray, center: DVec3, shape: &Ellipsoid, sigma: f64) -> GaussianAlongRay {
        let (mapped, k) = shape.unit_ray(ray, center);
        let (u0, v_hat) = (mapped.origin, mapped.direction);
        let along = u0.dot(v_hat);
        // The part of u₀ across v̂: no cancellation in m*² when the ray passes near the centre.
        let across = u0 - along * v_hat;
        GaussianAlongRay {
            t_star: -along / k,
            s: 1.0 / k,
            peak: sigma * (-0.5 * across.length_squared()).exp(),
        }
    }

    /// The density at t.
    pub fn density(&self, t: f64) -> f64 {
        let z = (t - self.t_star) / self.s;
        self.peak * (-0.5 * z * z).exp()
    }

    /// The optical depth ∫ density dt over [t0, t1] (t0 ≤ t1), in closed form.
    pub fn optical_depth(&self, t0: f64, t1: f64) -> f64 {
        let scale = std::f64::consts::SQRT_2 * self.s;
        let d = erf_difference((t0 - self.t_star) / scale, (t1 - self.t_star) / scale);
        self.peak * self.s * SQRT_HALF_PI * d
    }

    /// The optical depth from `t0` to later points, with the work at `t0` done once
    /// ([`DepthFrom::to`]).
    pub fn depth_from(&self, t0: f64) -> DepthFrom {
        let z0 = (t0 - self.t_star) / (std::f64::consts::SQRT_2 * self.s);
        self.depth_from_tail(t0, libm::erfc(z0.abs()))
    }

    /// [`GaussianAlongRay::depth_from`] where erfc(|z₀|) at `t0` is known already (the `tail`
    /// that [`DepthFrom::to_with_tail`] returned for `t0`).
    pub fn depth_from_tail(&self, t0: f64, tail0: f64) -> DepthFrom {
        let scale = std::f64::consts::SQRT_2 * self.s;
        DepthFrom {
            t_star: self.t_star,
            inv_scale: 1.0 / scale,
            z0: (t0 - self.t_star) / scale,
            tail0,
            factor: self.peak * self.s * SQRT_HALF_PI,
        }
    }

    /// The optical depth over the whole line, σᵢ·e^{−½m*²}·s·√(2π).
    pub fn total_depth(&self) -> f64 {
        self.peak * self.s * 2.0 * SQRT_HALF_PI
    }
}

/// The optical depth of one Gaussian from a fixed t₀ ([`GaussianAlongRay::depth_from`]): one
/// erfc per later point, by the cases of [`erf_difference`] with erfc(|z₀|) kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthFrom {
    t_star: f64,
    inv_scale: f64,
    z0: f64,
    tail0: f64,
    factor: f64,
}

impl DepthFrom {
    /// The optical depth over [t₀, t], t ≥ t₀.
    #[inline]
    pub fn to(&self, t: f64) -> f64 {
        self.to_with_tail(t).0
    }

    /// The optical depth over [t₀, t], t ≥ t₀, and erfc(|z|) at t (for a later
    /// [`GaussianAlongRay::depth_from_tail`] from t).
    #[inline]
    pub fn to_with_tail(&self, t: f64) -> (f64, f64) {
        let z1 = (t - self.t_star) * self.inv_scale;
        let tail1 = libm::erfc(z1.abs());
        let d = if self.z0 >= 0.0 {
            self.tail0 - tail1
        } else if z1 <= 0.0 {
            tail1 - self.tail0
        } else {
            // erf(z₁) + erf(−z₀), each 1 − erfc: both terms in (0, 1], no cancellation that
            // matters for an absolute depth.
            (1.0 - tail1) + (1.0 - self.tail0)
        };
        (self.factor * d, tail1)
    }
}

/// The opacity mapping (docs/design.md §9): the peak density σᵢ of a Gaussian whose shortest
/// standard deviation is `shortest` such that a ray through its centre along that axis keeps
/// 1 − `opacity` of the light behind it: the whole line's optical depth σᵢ·s·√(2π) equals
/// −ln(1 − opacity). Opacity 1 gives +∞.
pub fn sigma_from_peak_opacity(opacity: f64, shortest: f64) -> f64 {
    -(-opacity).ln_1p() / (shortest * 2.0 * SQRT_HALF_PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// ∫ f over [a, b] by composite Gauss–Legendre (5 points) on `n` panels: an independent
    /// numerical integral of the density.
    fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        const X: [f64; 5] = [
            0.0,
            -0.538_469_310_105_683_1,
            0.538_469_310_105_683_1,
            -0.906_179_845_938_664,
            0.906_179_845_938_664,
        ];
        const W: [f64; 5] = [
            0.568_888_888_888_888_9,
            0.478_628_670_499_366_5,
            0.478_628_670_499_366_5,
            0.236_926_885_056_189_1,
            0.236_926_885_056_189_1,
        ];
        let h = (b - a) / n as f64;
        (0..n)
            .map(|i| {
                let mid = a + (i as f64 + 0.5) * h;
                X.iter()
                    .zip(W)
                    .map(|(x, w)| w * f(mid + 0.5 * h * x))
                    .sum::<f64>()
                    * 0.5
                    * h
            })
            .sum()
    }

    fn turned() -> (DVec3, Ellipsoid) {
        let shape = Ellipsoid::new(
            DVec3::new(0.7, 0.2, 1.5),
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9),
        );
        (DVec3::new(0.3, -0.2, 4.0), shape)
    }

    #[test]
    fn the_profile_is_the_mahalanobis_density_along_the_ray() {
        let (c, shape) = turned();
        let ray = Ray::new(
            DVec3::new(-0.4, 0.1, 0.0),
            DVec3::new(0.1, -0.05, 1.0).normalize(),
        );
        let g = GaussianAlongRay::new(&ray, c, &shape, 2.5);
        for t in [0.0, 2.0, 3.7, 4.1, 6.0] {
            let m2 = shape
                .to_unit(c, ray.origin + t * ray.direction)
                .length_squared();
            let direct = 2.5 * (-0.5 * m2).exp();
            assert!(
                (g.density(t) - direct).abs() <= 1e-14 * direct.max(1e-300),
                "t {t}: {} against {direct}",
                g.density(t)
            );
        }
    }

    #[test]
    fn the_optical_depth_equals_a_numerical_integral() {
        let (c, shape) = turned();
        let ray = Ray::new(
            DVec3::new(-0.4, 0.1, 0.0),
            DVec3::new(0.1, -0.05, 1.0).normalize(),
        );
        let g = GaussianAlongRay::new(&ray, c, &shape, 2.5);
        let spans = [
            (g.t_star - 0.3, g.t_star + 0.1),
            (0.0, 10.0),
            (g.t_star + 0.5 * g.s, g.t_star + 3.0 * g.s),
            (g.t_star - 4.0 * g.s, g.t_star - 1.0 * g.s),
        ];
        for (t0, t1) in spans {
            let closed = g.optical_depth(t0, t1);
            let numeric = gauss_legendre(|t| g.density(t), t0, t1, 4000);
            assert!(
                (closed - numeric).abs() <= 1e-12 * numeric,
                "[{t0}, {t1}]: {closed} against {numeric}"
            );
        }
        assert!((g.optical_depth(-1e3, 1e3) - g.total_depth()).abs() <= 1e-14 * g.total_depth());
    }

    #[test]
    fn the_tails_keep_their_relative_accuracy() {
        // 8 to 11 standard deviations out, erf(b) − erf(a) subtracts two numbers within 1e-15 of
        // 1 and keeps no digit; the erfc form is exact to 1e-12 relative.
        let g = GaussianAlongRay {
            t_star: 0.0,
            s: 0.5,
            peak: 3.0,
        };
        for sign in [1.0, -1.0] {
            let (t0, t1) = if sign > 0.0 { (4.0, 5.5) } else { (-5.5, -4.0) };
            let closed = g.optical_depth(t0, t1);
            let numeric = gauss_legendre(|t| g.density(t), t0, t1, 2000);
            assert!(numeric > 0.0 && numeric < 1e-13, "{numeric}");
            assert!(
                (closed - numeric).abs() <= 1e-12 * numeric,
                "{closed} against {numeric}"
            );
            let naive = libm::erf((t1 - g.t_star) / (std::f64::consts::SQRT_2 * g.s))
                - libm::erf((t0 - g.t_star) / (std::f64::consts::SQRT_2 * g.s));
            let naive = g.peak * g.s * SQRT_HALF_PI * naive.abs();
            assert!(
                (naive - numeric).abs() > 1e-3 * numeric,
                "the naive difference would be accurate here too ({naive} vs {numeric}): the test shows nothing"
            );
        }
    }

    #[test]
    fn the_opacity_mapping_gives_the_files_opacity_along_the_shortest_axis() {
        // Shortest standard deviation 0.2 along the body's y axis, turned.
        let rotation = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, 0.2).normalize(), 1.1);
        let shape = Ellipsoid::new(DVec3::new(0.9, 0.2, 0.5), rotation);
        let c = DVec3::new(1.0, 2.0, 3.0);
        for opacity in [0.01, 0.5, 0.9, 0.999] {
            let sigma = sigma_from_peak_opacity(opacity, 0.2);
            let axis = rotation * DVec3::Y;
            let ray = Ray::new(c - 5.0 * axis, axis);
            let g = GaussianAlongRay::new(&ray, c, &shape, sigma);
            let seen = 1.0 - (-g.optical_depth(0.0, 10.0)).exp();
            assert!(
                (seen - opacity).abs() <= 1e-12,
                "opacity {opacity}: seen {seen}"
            );
            // Along the longest axis the same Gaussian is more opaque.
            let long = rotation * DVec3::X;
            let g = GaussianAlongRay::new(&Ray::new(c - 5.0 * long, long), c, &shape, sigma);
            assert!(1.0 - (-g.total_depth()).exp() > opacity);
        }
        assert_eq!(sigma_from_peak_opacity(1.0, 0.2), f64::INFINITY);
    }

    #[test]
    fn the_depth_from_a_point_is_the_optical_depth() {
        let g = GaussianAlongRay {
            t_star: 2.0,
            s: 0.3,
            peak: 1.7,
        };
        for t0 in [0.0, 1.5, 2.0, 2.2, 4.5] {
            let from = g.depth_from(t0);
            for dt in [0.0, 0.01, 0.3, 0.9, 2.0, 5.0] {
                let (a, b) = (from.to(t0 + dt), g.optical_depth(t0, t0 + dt));
                assert!(
                    (a - b).abs() <= 4e-16 * g.total_depth(),
                    "{t0} {dt}: {a} {b}"
                );
            }
        }
    }

    #[test]
    fn two_coincident_gaussians_are_one_with_twice_sigma() {
        let (c, shape) = turned();
        let ray = Ray::new(DVec3::ZERO, DVec3::new(0.05, -0.04, 1.0).normalize());
        let one = GaussianAlongRay::new(&ray, c, &shape, 1.3);
        let double = GaussianAlongRay::new(&ray, c, &shape, 2.6);
        let (t0, t1) = (2.0, 5.0);
        let sum = 2.0 * one.optical_depth(t0, t1);
        assert!((double.optical_depth(t0, t1) - sum).abs() <= 1e-15 * sum);
    }
}
