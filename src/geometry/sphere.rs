//! The ray–sphere intersection in f64 (docs/design.md §3).
//!
//! The textbook form solves t² + 2(f·d)t + |f|² − r² = 0 with f = o − c; for |o| ≫ r the term
//! |f|² − r² loses every significant digit. Instead we project the centre on the ray
//! (t_c = −f·d), take the closest point's offset l = f + t_c·d from the centre, and get the
//! half-chord from h² = r² − |l|² = (r − |l|)(r + |l|), which has no cancellation beyond the
//! subtraction r − |l| itself (exact for close values by Sterbenz). The chord 2h goes to 0
//! continuously as the ray approaches the silhouette, and a ray that misses gives `None`.

use super::Ray;
use glam::DVec3;

/// Where a ray's line crosses a sphere: entry `t_enter` and exit `t_exit` (t_enter < t_exit).
/// Either may be negative: a ray starting inside the sphere has t_enter < 0 < t_exit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chord {
    pub t_enter: f64,
    pub t_exit: f64,
}

impl Chord {
    /// Length of the chord (twice the half-chord h).
    #[inline]
    pub fn length(&self) -> f64 {
        self.t_exit - self.t_enter
    }
}

/// Intersects the whole line of `ray` with the sphere (centre, radius); `None` when the line
/// misses or only touches it (a zero-length chord contributes nothing to any integral).
/// The ray direction must be unit length.
#[inline]
pub fn intersect_sphere(ray: &Ray, center: DVec3, radius: f64) -> Option<Chord> {
    let f = ray.origin - center;
    let t_c = -f.dot(ray.direction);
    let l = f + t_c * ray.direction;
    let dist = l.length();
    if dist >= radius {
        return None;
    }
    let half_sq = (radius - dist) * (radius + dist);
    let half = half_sq.sqrt();
    if half <= 0.0 {
        return None;
    }
    Some(Chord {
        t_enter: t_c - half,
        t_exit: t_c + half,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    #[test]
    fn through_the_centre_the_chord_is_the_diameter() {
        let ray = Ray::new(DVec3::new(0.0, 0.0, -10.0), DVec3::Z);
        let c = intersect_sphere(&ray, DVec3::ZERO, 2.0).unwrap();
        assert_eq!(c.t_enter, 8.0);
        assert_eq!(c.t_exit, 12.0);
    }

    #[test]
    fn origin_inside_gives_negative_entry() {
        let ray = Ray::new(DVec3::new(0.5, 0.0, 0.0), DVec3::X);
        let c = intersect_sphere(&ray, DVec3::ZERO, 1.0).unwrap();
        assert_relative_eq!(c.t_enter, -1.5, epsilon = 1e-15);
        assert_relative_eq!(c.t_exit, 0.5, epsilon = 1e-15);
    }

    #[test]
    fn far_origin_keeps_precision() {
        // |o| = 1e8 m, r = 1 m: the textbook discriminant |f|² − r² cancels completely here.
        let ray = Ray::new(DVec3::new(0.5, 0.0, -1e8), DVec3::Z);
        let c = intersect_sphere(&ray, DVec3::ZERO, 1.0).unwrap();
        let expected_half = (1.0f64 - 0.25).sqrt();
        assert_relative_eq!(c.length(), 2.0 * expected_half, epsilon = 1e-8);
    }

    #[test]
    fn tangent_and_outside_rays_miss() {
        let tangent = Ray::new(DVec3::new(1.0, 0.0, -5.0), DVec3::Z);
        assert!(intersect_sphere(&tangent, DVec3::ZERO, 1.0).is_none());
        let outside = Ray::new(DVec3::new(1.0 + 1e-12, 0.0, -5.0), DVec3::Z);
        assert!(intersect_sphere(&outside, DVec3::ZERO, 1.0).is_none());
        let grazing = Ray::new(DVec3::new(1.0 - 1e-12, 0.0, -5.0), DVec3::Z);
        let c = intersect_sphere(&grazing, DVec3::ZERO, 1.0).unwrap();
        // h = sqrt(r² − (r−ε)²) ≈ sqrt(2ε)
        assert_relative_eq!(c.length(), 2.0 * (2e-12f64).sqrt(), max_relative = 1e-3);
    }

    proptest! {
        /// The chord length is continuous in the ray's offset b from the centre and equals the
        /// closed form 2·sqrt(r² − b²), from the centre to past the silhouette.
        #[test]
        fn chord_is_continuous_in_the_offset(
            r in 0.01f64..100.0,
            frac in 0.0f64..1.2,
            dir in prop::array::uniform3(-1.0f64..1.0),
            dist in 1.0f64..1e4,
        ) {
            let d = DVec3::from(dir);
            prop_assume!(d.length() > 0.1);
            let d = d.normalize();
            let perp = d.any_orthonormal_vector();
            let b = frac * r;
            let center = DVec3::new(3.0, -2.0, 7.0);
            let origin = center + perp * b - d * (dist * r);
            let ray = Ray { origin, direction: d };
            let expected = if b < r { 2.0 * ((r - b) * (r + b)).sqrt() } else { 0.0 };
            let got = intersect_sphere(&ray, center, r).map_or(0.0, |c| c.length());
            // Absolute error budget: the offset itself carries ~|origin|·1e-16 of round-off,
            // which sqrt amplifies near the silhouette to about sqrt(2·r·|origin|·1e-16).
            let slack = (2.0 * r * (origin.length() + r) * 4e-16).sqrt() + 1e-12 * r;
            prop_assert!((got - expected).abs() <= slack,
                "b/r={frac} got {got} expected {expected} slack {slack}");
        }
    }
}
