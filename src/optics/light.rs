//! Light sources and what arrives from them (docs/design.md §1): directional lights with irradiance
//! E, point lights with intensity I and irradiance I/d² (or I with `falloff = "none"`).

use glam::DVec3;

/// `light_weight` of the lit model (docs/design.md §2): w = 1/m (`mean`, thesis eq. 4.17) or w = 1
/// (`sum`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LightWeight {
    Mean,
    Sum,
}

/// w of the lit model (docs/design.md §2): 1/m for `mean` (thesis eq. 4.17), 1 for `sum`; 0 without
/// lights (there is nothing to weigh).
pub fn light_weight(weight: LightWeight, lights: usize) -> f64 {
    match (weight, lights) {
        (_, 0) => 0.0,
        (LightWeight::Mean, m) => 1.0 / m as f64,
        (LightWeight::Sum, _) => 1.0,
    }
}

/// How a point light's irradiance falls off with distance d.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Falloff {
    /// E = I/d².
    InverseSquare,
    /// E = I.
    None,
}

/// A light source (docs/design.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// `direction` is unit length and is the way the light travels.
    Directional { direction: DVec3, irradiance: DVec3 },
    /// `intensity` in W/sr.
    Point {
        position: DVec3,
        intensity: DVec3,
        falloff: Falloff,
    },
}

/// What arrives at a point from one light, before any occlusion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incident {
    /// Unit vector from the point towards the light.
    pub toward: DVec3,
    /// Distance to the light (∞ for a directional light).
    pub distance: f64,
    /// Irradiance on a surface facing the light, unoccluded: E, or I/d² (I with `falloff = none`).
    pub irradiance: DVec3,
}

impl Light {
    /// The unoccluded light arriving at `x` (docs/design.md §1: E for directional lights, I/d² for
    /// point lights). A point exactly at a point light's position gets `None`.
    #[inline]
    pub fn incident_at(&self, x: DVec3) -> Option<Incident> {
        match *self {
            Light::Directional {
                direction,
                irradiance,
            } => Some(Incident {
                toward: -direction,
                distance: f64::INFINITY,
                irradiance,
            }),
            Light::Point {
                position,
                intensity,
                falloff,
            } => {
                let v = position - x;
                let d = v.length();
                if d <= 0.0 || !d.is_finite() {
                    return None;
                }
                let irradiance = match falloff {
                    Falloff::InverseSquare => intensity / (d * d),
                    Falloff::None => intensity,
                };
                Some(Incident {
                    toward: v / d,
                    distance: d,
                    irradiance,
                })
            }
        }
    }
}

impl Light {
    /// A per-channel upper bound of the unoccluded irradiance at every point o + s·d, s ≥ `t`,
    /// of the ray (o, d) (d unit length): E for a directional light; I/d_min² for a point light,
    /// d_min its distance from that half-line (∞ where the half-line passes through it, and I
    /// with `falloff = "none"`). Rounded up by a relative 1e-12, far above the round-off of d_min.
    pub fn max_irradiance_beyond(&self, origin: DVec3, direction: DVec3, t: f64) -> DVec3 {
        match *self {
            Light::Directional { irradiance, .. } => irradiance,
            Light::Point {
                falloff: Falloff::None,
                intensity,
                ..
            } => intensity,
            Light::Point {
                position,
                intensity,
                falloff: Falloff::InverseSquare,
            } => {
                let v = position - origin;
                let s = v.dot(direction).max(t);
                let d = (v - s * direction).length();
                intensity / (d * d) * (1.0 + 1e-12)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound holds at every sampled point of the half-line, and is reached (to its rounding
    /// margin) at the point nearest to a point light that lies beside the half-line.
    #[test]
    fn the_irradiance_bound_covers_the_half_line() {
        let mut rng = crate::formats::random::SplitMix64::new(3);
        let mut v = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
        for _ in 0..200 {
            let light = Light::Point {
                position: v() * 3.0,
                intensity: DVec3::new(1.0, 2.0, 0.5),
                falloff: Falloff::InverseSquare,
            };
            let (o, d) = (v() * 5.0, v().normalize());
            let t0 = 4.0 * v().x;
            let bound = light.max_irradiance_beyond(o, d, t0);
            let mut best = DVec3::ZERO;
            for k in 0..2000 {
                let x = o + (t0 + k as f64 * 0.005) * d;
                let e = light.incident_at(x).unwrap().irradiance;
                assert!(e.cmple(bound).all(), "{e} above {bound}");
                best = best.max(e);
            }
            // The nearest point lies within the sampled stretch when the light is near the ray.
            let Light::Point { position, .. } = light else {
                unreachable!()
            };
            let s = (position - o).dot(d).max(t0);
            if s < t0 + 9.0 {
                assert!(best.x > 0.99 * bound.x, "{best} far below {bound}");
            }
        }
        let sun = Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: DVec3::new(0.1, 0.2, 0.3),
        };
        assert_eq!(
            sun.max_irradiance_beyond(DVec3::ZERO, DVec3::X, 5.0),
            DVec3::new(0.1, 0.2, 0.3)
        );
        let through = Light::Point {
            position: DVec3::new(3.0, 0.0, 0.0),
            intensity: DVec3::ONE,
            falloff: Falloff::InverseSquare,
        };
        let on_it = through.max_irradiance_beyond(DVec3::ZERO, DVec3::X, 1.0);
        assert!(on_it.x.is_infinite(), "{on_it}");
        assert!(through
            .max_irradiance_beyond(DVec3::ZERO, DVec3::X, 4.0)
            .cmplt(DVec3::splat(1.0 + 1e-9))
            .all());
    }

    #[test]
    fn weights() {
        assert_eq!(light_weight(LightWeight::Mean, 4), 0.25);
        assert_eq!(light_weight(LightWeight::Sum, 4), 1.0);
        assert_eq!(light_weight(LightWeight::Mean, 0), 0.0);
        assert_eq!(light_weight(LightWeight::Sum, 0), 0.0);
    }

    #[test]
    fn point_light_irradiance_falls_off_with_the_square_of_the_distance() {
        let light = |falloff| Light::Point {
            position: DVec3::new(0.0, 3.0, 4.0),
            intensity: DVec3::splat(50.0),
            falloff,
        };
        let inc = light(Falloff::InverseSquare)
            .incident_at(DVec3::ZERO)
            .unwrap();
        assert_eq!(inc.distance, 5.0);
        assert_eq!(inc.irradiance, DVec3::splat(2.0));
        assert!((inc.toward - DVec3::new(0.0, 0.6, 0.8)).length() < 1e-15);
        let inc = light(Falloff::None).incident_at(DVec3::ZERO).unwrap();
        assert_eq!(inc.irradiance, DVec3::splat(50.0));
        assert!(light(Falloff::None)
            .incident_at(DVec3::new(0.0, 3.0, 4.0))
            .is_none());
        let sun = Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: DVec3::ONE,
        };
        let inc = sun.incident_at(DVec3::splat(7.0)).unwrap();
        assert_eq!((inc.toward, inc.distance), (DVec3::Y, f64::INFINITY));
    }
}
