//! The ellipsoid: a unit sphere after an affine map (docs/design.md §9).
//!
//! An ellipsoid with centre c, semi-axes s = (a, b, c) along its own axes and orientation R (a
//! unit quaternion, body to world) is the set of points x with |M(x − c)| ≤ 1, M = S⁻¹Rᵀ. The
//! map x ↦ M(x − c) takes it to the unit sphere at the origin and takes lines to lines, keeping
//! the order of points along them and their tangencies. So every exact piece of the sphere code
//! carries over: a ray o + t·d becomes the ray M(o − c) + t·Md, written with a unit direction
//! and the parameter s = k·t (k = |Md|), and the sphere's own stable intersection
//! ([`intersect_sphere`]) and its shadow tangencies (`optics::kinks`) run on it unchanged; the
//! answers come back as t = s/k.
//!
//! The shape of a particle is chosen here too ([`Shape`]): the renderers ask it for chords,
//! boxes, normals and insideness, and the sphere's answers are the sphere code's own, so sphere
//! scenes keep their bits.

use super::{intersect_sphere, Chord, Ray};
use glam::{DMat3, DQuat, DVec3};

/// The semi-axes and orientation of an ellipsoid about its centre, with the map to the unit
/// sphere prepared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid {
    /// Semi-axes along the body's x, y and z axes (m), each finite and > 0.
    semi_axes: DVec3,
    /// Orientation, body to world: a unit quaternion.
    rotation: DQuat,
    /// M = S⁻¹Rᵀ: a world offset from the centre to unit-sphere coordinates (the inverse, R·S,
    /// is needed rarely and made when it is: [`Ellipsoid::unit_to_world`]).
    to_unit: DMat3,
}

impl Ellipsoid {
    /// The ellipsoid with `semi_axes` (finite, > 0) turned by `rotation` (unit length; the
    /// scene normalises what files give).
    pub fn new(semi_axes: DVec3, rotation: DQuat) -> Ellipsoid {
        let r = DMat3::from_quat(rotation);
        Ellipsoid {
            semi_axes,
            rotation,
            to_unit: DMat3::from_diagonal(semi_axes.recip()) * r.transpose(),
        }
    }

    /// M⁻¹ = R·S: unit-sphere coordinates to a world offset from the centre.
    fn unit_to_world(&self) -> DMat3 {
        DMat3::from_quat(self.rotation) * DMat3::from_diagonal(self.semi_axes)
    }

    pub fn semi_axes(&self) -> DVec3 {
        self.semi_axes
    }

    pub fn rotation(&self) -> DQuat {
        self.rotation
    }

    /// The longest semi-axis: the radius of the smallest sphere about the centre holding it.
    pub fn bounding_radius(&self) -> f64 {
        self.semi_axes.max_element()
    }

    /// M = S⁻¹Rᵀ, the map from a world offset about the centre to unit-sphere coordinates.
    pub fn to_unit_matrix(&self) -> DMat3 {
        self.to_unit
    }

    /// The shortest semi-axis: Θmax is the opacity along the diameter of this length.
    pub fn shortest_semi_axis(&self) -> f64 {
        self.semi_axes.min_element()
    }

    /// The point `x` in unit-sphere coordinates of the ellipsoid about `center`.
    #[inline]
    pub fn to_unit(&self, center: DVec3, x: DVec3) -> DVec3 {
        self.to_unit * (x - center)
    }

    /// `ray` in unit-sphere coordinates of the ellipsoid about `center`, with a unit direction,
    /// and k = |Md|: the mapped ray's parameter is s = k·t.
    #[inline]
    pub fn unit_ray(&self, ray: &Ray, center: DVec3) -> (Ray, f64) {
        let origin = self.to_unit * (ray.origin - center);
        let d = self.to_unit * ray.direction;
        let k = d.length();
        (
            Ray {
                origin,
                direction: d / k,
            },
            k,
        )
    }

    /// Where the line of `ray` crosses the ellipsoid about `center` ([`intersect_sphere`]'s
    /// contract: `None` for a miss or a touch).
    #[inline]
    pub fn intersect(&self, ray: &Ray, center: DVec3) -> Option<Chord> {
        let (unit, k) = self.unit_ray(ray, center);
        let c = intersect_sphere(&unit, DVec3::ZERO, 1.0)?;
        Some(Chord {
            t_enter: c.t_enter / k,
            t_exit: c.t_exit / k,
        })
    }

    /// Half the extent of the tightest axis-aligned box about the centre: along world axis i,
    /// √Σⱼ (R_ij·s_j)² (the support of the ellipsoid in direction eᵢ).
    pub fn half_extent(&self) -> DVec3 {
        let m = self.unit_to_world().transpose();
        DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
    }

    /// Whether `x` lies strictly inside the ellipsoid about `center`.
    pub fn contains(&self, center: DVec3, x: DVec3) -> bool {
        self.to_unit(center, x).length() < 1.0
    }

    /// The outward unit normal at the surface point nearest (in the unit-sphere map) to `x`:
    /// the gradient MᵀM(x − c) of |M(x − c)|², normalised.
    pub fn normal(&self, center: DVec3, x: DVec3) -> DVec3 {
        (self.to_unit.transpose() * self.to_unit(center, x)).normalize_or_zero()
    }

    /// `x` moved onto the surface along the line through the centre (the unit sphere's
    /// radial projection, mapped back).
    pub fn snap_to_surface(&self, center: DVec3, x: DVec3) -> DVec3 {
        center + self.unit_to_world() * self.to_unit(center, x).normalize_or_zero()
    }
}

/// The shape of one particle, as the renderers ask for it: a sphere (centre, radius) or an
/// ellipsoid about a centre. Every geometric question has its answer for each shape here.
#[derive(Debug, Clone, Copy)]
pub enum Shape<'a> {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    Ellipsoid {
        center: DVec3,
        ellipsoid: &'a Ellipsoid,
    },
}

impl Shape<'_> {
    /// The chord of the line of `ray` through the shape.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Chord> {
        match *self {
            Shape::Sphere { center, radius } => intersect_sphere(ray, center, radius),
            Shape::Ellipsoid { center, ellipsoid } => ellipsoid.intersect(ray, center),
        }
    }

    /// The centre.
    pub fn center(&self) -> DVec3 {
        match *self {
            Shape::Sphere { center, .. } | Shape::Ellipsoid { center, .. } => center,
        }
    }

    /// The radius of a sphere about the centre that holds the shape (the sphere's own radius).
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Shape::Sphere { radius, .. } => radius,
            Shape::Ellipsoid { ellipsoid, .. } => ellipsoid.bounding_radius(),
        }
    }

    /// Half the extent of the tightest axis-aligned box about the centre.
    pub fn half_extent(&self) -> DVec3 {
        match *self {
            Shape::Sphere { radius, .. } => DVec3::splat(radius),
            Shape::Ellipsoid { ellipsoid, .. } => ellipsoid.half_extent(),
        }
    }

    /// Whether `x` lies strictly inside.
    pub fn contains(&self, x: DVec3) -> bool {
        match *self {
            Shape::Sphere { center, radius } => (x - center).length() < radius,
            Shape::Ellipsoid { center, ellipsoid } => ellipsoid.contains(center, x),
        }
    }

    /// The outward unit normal at the surface point of `x` (a point on or near the surface).
    pub fn normal(&self, x: DVec3) -> DVec3 {
        match *self {
            Shape::Sphere { center, .. } => (x - center).normalize_or_zero(),
            Shape::Ellipsoid { center, ellipsoid } => ellipsoid.normal(center, x),
        }
    }

    /// `x` moved onto the surface along the line through the centre.
    pub fn snap_to_surface(&self, x: DVec3) -> DVec3 {
        match *self {
            Shape::Sphere { center, radius } => center + (x - center).normalize() * radius,
            Shape::Ellipsoid { center, ellipsoid } => ellipsoid.snap_to_surface(center, x),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn quat(q: [f64; 4]) -> DQuat {
        DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize()
    }

    #[test]
    fn equal_axes_give_the_spheres_chord() {
        let e = Ellipsoid::new(DVec3::splat(2.0), quat([0.3, -0.5, 0.2, 0.7]));
        let c = DVec3::new(1.0, -2.0, 3.0);
        for (o, d) in [
            (DVec3::new(0.0, 0.0, -10.0), DVec3::new(0.1, -0.2, 1.0)),
            (DVec3::new(1.5, -2.0, 3.0), DVec3::new(1.0, 1.0, 0.0)),
            (DVec3::new(-50.0, 7.0, 1.0), DVec3::new(1.0, -0.17, 0.03)),
        ] {
            let ray = Ray::new(o, d);
            let a = e.intersect(&ray, c).unwrap();
            let b = intersect_sphere(&ray, c, 2.0).unwrap();
            assert_relative_eq!(
                a.t_enter,
                b.t_enter,
                epsilon = 1e-12 * b.t_enter.abs().max(1.0)
            );
            assert_relative_eq!(
                a.t_exit,
                b.t_exit,
                epsilon = 1e-12 * b.t_exit.abs().max(1.0)
            );
        }
    }

    #[test]
    fn axis_aligned_chords_are_the_semi_axes() {
        // Turned 90° about z: the body's x axis (a = 3) lies along world y.
        let e = Ellipsoid::new(
            DVec3::new(3.0, 1.0, 0.5),
            DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
        );
        let along_y = Ray::new(DVec3::new(0.0, -10.0, 0.0), DVec3::Y);
        let c = e.intersect(&along_y, DVec3::ZERO).unwrap();
        assert_relative_eq!(c.length(), 6.0, epsilon = 1e-12);
        let along_x = Ray::new(DVec3::new(-10.0, 0.0, 0.0), DVec3::X);
        assert_relative_eq!(
            e.intersect(&along_x, DVec3::ZERO).unwrap().length(),
            2.0,
            epsilon = 1e-12
        );
        let along_z = Ray::new(DVec3::new(0.0, 0.0, 10.0), -DVec3::Z);
        let c = e.intersect(&along_z, DVec3::ZERO).unwrap();
        assert_relative_eq!(c.t_enter, 9.5, epsilon = 1e-12);
        assert_relative_eq!(e.half_extent(), DVec3::new(1.0, 3.0, 0.5), epsilon = 1e-12);
        // Misses just outside the long axis.
        let outside = Ray::new(DVec3::new(0.0, 3.0 + 1e-9, -5.0), DVec3::Z);
        assert!(e.intersect(&outside, DVec3::ZERO).is_none());
    }

    proptest! {
        /// Chord ends lie on the surface, the normal is the gradient's direction, the box holds
        /// points sampled on the surface and touches it.
        #[test]
        fn chords_normals_and_boxes_agree_with_the_implicit_surface(
            axes in prop::array::uniform3(0.01f64..10.0),
            q in prop::array::uniform4(-1.0f64..1.0),
            o in prop::array::uniform3(-20.0f64..20.0),
            aim in prop::array::uniform3(-1.0f64..1.0),
        ) {
            prop_assume!(norm4(q) > 0.1);
            let e = Ellipsoid::new(DVec3::from(axes), quat(q));
            let c = DVec3::new(0.5, -1.0, 2.0);
            let ray = Ray::new(DVec3::from(o), c + DVec3::from(aim) * e.bounding_radius() - DVec3::from(o));
            prop_assume!(ray.direction.is_finite());
            if let Some(ch) = e.intersect(&ray, c) {
                for t in [ch.t_enter, ch.t_exit] {
                    let u = e.to_unit(c, ray.at(t)).length();
                    prop_assert!((u - 1.0).abs() < 1e-9, "|M(x−c)| = {u}");
                    let x = ray.at(t);
                    let n = e.normal(c, x);
                    // Moving along the normal leaves the ellipsoid, against it enters.
                    let h = 1e-6 * e.shortest_semi_axis();
                    prop_assert!(!e.contains(c, x + h * n) && e.contains(c, x - h * n));
                }
                let mid = ray.at(0.5 * (ch.t_enter + ch.t_exit));
                prop_assert!(e.contains(c, mid));
            }
            let half = e.half_extent();
            let mut reached = DVec3::ZERO;
            for i in 0..64 {
                for j in 0..32 {
                    let (th, ph) = (std::f64::consts::TAU * i as f64 / 64.0, std::f64::consts::PI * j as f64 / 31.0);
                    let u = DVec3::new(ph.sin() * th.cos(), ph.sin() * th.sin(), ph.cos());
                    let x = e.unit_to_world() * u;
                    prop_assert!(x.abs().cmple(half * (1.0 + 1e-12)).all());
                    reached = reached.max(x.abs());
                }
            }
            // A coarse grid of the surface reaches most of the box.
            prop_assert!(reached.cmpge(half * 0.9).all(), "{reached} of {half}");
        }
    }

    fn norm4(q: [f64; 4]) -> f64 {
        q.iter().map(|x| x * x).sum::<f64>().sqrt()
    }
}
