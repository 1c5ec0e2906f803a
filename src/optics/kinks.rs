//! Where a shadow ray grazes a sphere: the kinks of the lit and single-scatter integrands
//! (docs/design.md §3, "kinks ... computed in closed form and used as breakpoints").
//!
//! Along a camera ray x(t) = o + t·d the source Q(x(t)) is smooth except where the shadow ray
//! from x(t) towards a light becomes tangent to a sphere j: there the shadow chord through j
//! grows like √(t − t*) and Q has a square-root kink. (Where x(t) crosses a sphere's surface the
//! camera ray is cut into intervals anyway.) The tangencies have closed forms:
//!
//! * directional light, unit vector ω towards it: the shadow ray is tangent to sphere (c, r) iff
//!   x(t) lies on the cylinder of radius r about the line c + s·ω, with the tangent point ahead
//!   of x ((c − x)·ω > 0): a ray–cylinder intersection, a quadratic in t;
//! * point light at p outside the sphere (D = |c − p| > r): iff x(t) lies on the cone with apex p,
//!   axis towards c and half-angle asin(r/D), on the sphere's nappe, and at least as far from p
//!   as the tangent point (√(D² − r²)), so that the tangent point lies on the shadow segment:
//!   a ray–cone intersection, again a quadratic. A light inside a sphere has no tangencies.
//!
//! An ellipsoid is the unit sphere after an affine map (`geometry::ellipsoid`), which keeps lines,
//! tangency and the order of points on a line: its tangencies are the unit sphere's for the
//! mapped camera ray and the mapped light (a directional light's direction M·ω, normalised; a
//! point light's position M(p − c)), found by the same functions, the roots scaled back from the
//! mapped ray's parameter. The cylinder and the cone become an elliptic cylinder and an
//! elliptic cone in the scene, still quadrics, so there are still at most two kinks per light.
//!
//! The candidate spheres are those that a shadow ray from some point of the camera segment can
//! reach: the segment swept towards the light (a parallelogram for a directional light, a
//! triangle for a point light). The BVH is traversed with a separating-axis test of that
//! polygon against the node boxes ([`shadow_tangencies`]); the renderer, which gathers the
//! same spheres for its shadow rays anyway, takes the roots from that list instead
//! (`reference::shadow::Occluders::tangencies`, the same values). The roots are only
//! breakpoints for the quadrature: an inexact root costs refinement, never correctness.

// `!(a > b)` is deliberate throughout: unlike `a <= b` it is also true when a value is NaN, so
// degenerate input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::light::Light;
use super::particle::Particle;
use crate::geometry::{Bvh, Leaf, Ray, Shape};
use glam::DVec3;

/// Appends to `out` the ray parameters t in (t_lo, t_hi) where the shadow ray from `ray.at(t)`
/// towards `light` is tangent to a particle with σ > 0, then sorts `out` (which may hold the
/// kinks of other lights already). `bvh` indexes `particles`.
pub fn shadow_tangencies(
    ray: &Ray,
    (t_lo, t_hi): (f64, f64),
    light: &Light,
    bvh: &Bvh,
    particles: &[Particle],
    out: &mut Vec<f64>,
) {
    if bvh.is_empty() || !(t_hi > t_lo) || !t_lo.is_finite() || !t_hi.is_finite() {
        return;
    }
    let poly = swept_polygon(bvh, light, ray.at(t_lo), ray.at(t_hi));
    for_each_swept_leaf(bvh, &poly, |leaf| {
        for (i, shape) in leaf.shapes() {
            if particles[i as usize].sigma > 0.0 {
                push_tangencies(ray, (t_lo, t_hi), light, shape, out);
            }
        }
    });
    out.sort_unstable_by(f64::total_cmp);
    out.dedup();
}

/// Appends to `out` the t in (t_lo, t_hi) where the shadow ray from `ray.at(t)` towards `light`
/// is tangent to `shape`: one particle's part of [`shadow_tangencies`].
pub(crate) fn push_tangencies(
    ray: &Ray,
    (t_lo, t_hi): (f64, f64),
    light: &Light,
    shape: Shape,
    out: &mut Vec<f64>,
) {
    let (roots, _) = shape_roots(ray, light, shape);
    out.extend(
        roots
            .into_iter()
            .flatten()
            .filter(|&t| t > t_lo && t < t_hi),
    );
}

/// A side of a kink t_k: the shadow rays from x(t), t > t_k close to it, cross the sphere.
pub const CROSSES_ABOVE: u8 = 1;
/// Those from t < t_k do.
pub const CROSSES_BELOW: u8 = 2;

/// [`push_tangencies`] with the side of each kink on which the shadow rays cross the sphere
/// ([`CROSSES_ABOVE`], [`CROSSES_BELOW`]): there the chord, and with it the integrand, grows
/// like √|t − t_k|; on the other side the sphere is not crossed and the integrand is smooth
/// through t_k. For a directional light the camera ray is inside the sphere's tangency
/// cylinder between its two roots, so the first root is crossed above and the second below (a
/// double root, the ray touching the cylinder, comes twice and gets both). For a point light
/// the crossing side is the inside of the tangent cone, where the ray enters or leaves it
/// ([`cone_roots`]); a root too close to double for that to be certain gets both.
#[inline]
pub(crate) fn push_sided_tangencies(
    ray: &Ray,
    (t_lo, t_hi): (f64, f64),
    light: &Light,
    shape: Shape,
    out: &mut Vec<(f64, u8)>,
) {
    let (roots, sides) = shape_roots(ray, light, shape);
    for (t, side) in roots.into_iter().zip(sides) {
        if let Some(t) = t.filter(|&t| t > t_lo && t < t_hi) {
            out.push((t, side));
        }
    }
}

/// The two tangency roots of `shape` for `light` along `ray`, each with its side
/// ([`push_sided_tangencies`]): a sphere's from [`sided_roots`], an ellipsoid's from the unit
/// sphere's for the mapped ray and light (see the module documentation).
#[inline(always)]
fn shape_roots(ray: &Ray, light: &Light, shape: Shape) -> ([Option<f64>; 2], [u8; 2]) {
    match shape {
        Shape::Sphere { center, radius } => sided_roots(ray, light, (center, radius)),
        Shape::Ellipsoid { center, ellipsoid } => ellipsoid_roots(ray, light, center, ellipsoid),
    }
}

/// `light` in the unit-sphere coordinates x ↦ M(x − c) of the ellipsoid `e` about `center`: a
/// directional light's direction mapped and normalised, a point light's position mapped (the
/// map takes shadow rays to the mapped light's shadow rays).
pub(crate) fn light_in_unit_coordinates(
    light: &Light,
    center: DVec3,
    e: &crate::geometry::Ellipsoid,
) -> Light {
    match *light {
        Light::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            direction: e.to_unit(DVec3::ZERO, direction).normalize(),
            irradiance,
        },
        Light::Point {
            position,
            intensity,
            falloff,
        } => Light::Point {
            position: e.to_unit(center, position),
            intensity,
            falloff,
        },
    }
}

/// [`shape_roots`] of an ellipsoid: the unit sphere's for the mapped ray and light.
#[inline(never)]
fn ellipsoid_roots(
    ray: &Ray,
    light: &Light,
    center: DVec3,
    ellipsoid: &crate::geometry::Ellipsoid,
) -> ([Option<f64>; 2], [u8; 2]) {
    let (unit, k) = ellipsoid.unit_ray(ray, center);
    let mapped = light_in_unit_coordinates(light, center, ellipsoid);
    let (roots, sides) = sided_roots(&unit, &mapped, (DVec3::ZERO, 1.0));
    (roots.map(|s| s.map(|s| s / k)), sides)
}

/// The two tangency roots of the sphere (c, r) for `light` along `ray`, each with its side
/// ([`push_sided_tangencies`]).
fn sided_roots(ray: &Ray, light: &Light, (c, r): (DVec3, f64)) -> ([Option<f64>; 2], [u8; 2]) {
    match *light {
        Light::Directional { direction, .. } => (
            cylinder_roots(ray, -direction, c, r),
            [CROSSES_ABOVE, CROSSES_BELOW],
        ),
        Light::Point { position, .. } => cone_roots(ray, position, c, r),
    }
}

/// The planar convex polygon that holds every shadow ray from a point of the segment [y0, y1]
/// towards `light`: a parallelogram reaching past the root box of `bvh` for a directional light,
/// the triangle (y0, y1, p) for a point light at p.
pub(crate) fn swept_polygon(bvh: &Bvh, light: &Light, y0: DVec3, y1: DVec3) -> SweptPolygon {
    match *light {
        Light::Directional { direction, .. } => {
            let root = &bvh.nodes[0];
            let centre = 0.5 * (root.min + root.max);
            // Far enough along the light's direction to leave the root box from any point of
            // the segment.
            let reach =
                (root.max - root.min).length() + (y0 - centre).length() + (y1 - centre).length();
            SweptPolygon::new(&[y0, y1, y1 - direction * reach, y0 - direction * reach])
        }
        Light::Point { position, .. } => SweptPolygon::new(&[y0, y1, position]),
    }
}

/// Calls `visit` with the sphere indices of every BVH leaf whose box the polygon `poly` (from
/// [`swept_polygon`]) may overlap (a conservative separating-axis test).
pub(crate) fn for_each_swept_leaf(bvh: &Bvh, poly: &SweptPolygon, mut visit: impl FnMut(Leaf)) {
    if bvh.is_empty() {
        return;
    }
    let mut stack = vec![0u32];
    while let Some(n) = stack.pop() {
        let node = &bvh.nodes[n as usize];
        if !poly.overlaps_box(node.min, node.max) {
            continue;
        }
        if node.count == 0 {
            stack.push(node.first);
            stack.push(node.first + 1);
            continue;
        }
        visit(bvh.leaf(node));
    }
}

/// Roots of the ray against the cylinder of radius r about c + s·ω (ω unit, towards the light),
/// kept where the tangent point lies ahead of x(t) towards the light.
fn cylinder_roots(ray: &Ray, omega: DVec3, c: DVec3, r: f64) -> [Option<f64>; 2] {
    let Some(AxisApproach { t_c, dist, a }) = axis_approach(ray, omega, c, 1e-24) else {
        // The camera ray runs along the light: its distance to the axis never changes.
        return [None, None];
    };
    if dist >= r {
        return [None, None];
    }
    let half = ((r - dist) * (r + dist) / a).sqrt();
    let ahead = |t: f64| (c - ray.at(t)).dot(omega) > 0.0;
    [t_c - half, t_c + half].map(|t| ahead(t).then_some(t))
}

/// Where a ray comes closest to the line c + s·ω (ω unit): at t_c, at distance `dist`, with
/// a = |d⊥|² the squared part of the ray's direction normal to ω. The inside of the cylinder of
/// radius r about that line is t_c ± √((r² − dist²)/a).
#[derive(Debug, Clone, Copy)]
pub(crate) struct AxisApproach {
    pub t_c: f64,
    pub dist: f64,
    pub a: f64,
}

/// The ray's closest approach to the line c + s·ω, in the same stable form as the sphere
/// intersection (closest approach first, then the half-chord); `None` where a ≤ `min_a`, i.e.
/// the ray runs (nearly) along the line and the approach is undefined or far off.
pub(crate) fn axis_approach(ray: &Ray, omega: DVec3, c: DVec3, min_a: f64) -> Option<AxisApproach> {
    let q0 = ray.origin - c;
    let d_perp = ray.direction - ray.direction.dot(omega) * omega;
    let q_perp = q0 - q0.dot(omega) * omega;
    let a = d_perp.length_squared();
    if !(a > min_a) {
        return None;
    }
    let t_c = -q_perp.dot(d_perp) / a;
    let dist = (q_perp + t_c * d_perp).length();
    Some(AxisApproach { t_c, dist, a })
}

/// Roots of the ray against the cone with apex p (the point light) tangent to sphere (c, r),
/// kept on the sphere's nappe and beyond the tangent point as seen from the light, each with
/// the side on which the shadow segments cross the sphere ([`push_sided_tangencies`]).
///
/// With v = x(t) − p, w the unit axis and k = cos² of the half-angle, F(t) = (v·w)² − k·|v|²
/// is positive exactly inside the double cone, and near a kept root (v·w > 0) inside means on
/// the sphere's nappe. There a shadow segment from x to p passes the tangent point's
/// neighbourhood through the sphere: it crosses it (the chord grows like the square root of
/// the distance from the cone), while outside the cone it misses it. So a root where F rises
/// (F′ > 0) is crossed above and one where it falls below. F is the quadratic
/// a·t² + b·t + c of [`solve_quadratic`], whose first root is (−b − s·√D)/(2a) with s the sign
/// of b, and so F′ = 2a·t + b is −s·√D there and +s·√D at the second: the signs come from the
/// formula, not from evaluating F′ at rounded roots. Where √D is below [`NEAR_DOUBLE`] of |b|
/// (the ray nearly touches the cone, and the computed roots may be out of order), both roots
/// get both sides. A linear F (a = 0) has one root, with F′ = b.
fn cone_roots(ray: &Ray, p: DVec3, c: DVec3, r: f64) -> ([Option<f64>; 2], [u8; 2]) {
    const BOTH: u8 = CROSSES_ABOVE | CROSSES_BELOW;
    let axis = c - p;
    let dd = axis.length();
    if !(dd > r) {
        return ([None, None], [BOTH, BOTH]);
    }
    let w = axis / dd;
    let k = (1.0 - r / dd) * (1.0 + r / dd); // cos² of the half-angle
    let tangent_distance = dd * k.sqrt();
    let v0 = ray.origin - p;
    let dw = ray.direction.dot(w);
    let v0w = v0.dot(w);
    let qa = dw * dw - k;
    let qb = 2.0 * (v0w * dw - k * v0.dot(ray.direction));
    let qc = v0w * v0w - k * v0.length_squared();
    let roots = solve_quadratic(qa, qb, qc);
    let valid = |t: f64| {
        let v = v0 + t * ray.direction;
        v.dot(w) > 0.0 && v.length() >= tangent_distance
    };
    let side = |slope: f64| {
        if slope > 0.0 {
            CROSSES_ABOVE
        } else if slope < 0.0 {
            CROSSES_BELOW
        } else {
            BOTH
        }
    };
    let sides = if qa == 0.0 {
        [side(qb), BOTH]
    } else {
        let root_disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
        if root_disc > NEAR_DOUBLE * qb.abs() {
            let s = qb.signum();
            [side(-s), side(s)]
        } else {
            [BOTH, BOTH]
        }
    };
    (roots.map(|t| t.filter(|&t| valid(t))), sides)
}

/// Relative size of √D (D the discriminant) against |b| below which a point light's two
/// tangency roots count as nearly double ([`cone_roots`]). Their separation is √D/|a| against
/// their size |b|/(2|a|), and the rounding of the coefficients moves nearly double roots by up
/// to about √ε ≈ 1.5e-8 of that size: below 1e-6 their order is not certain enough.
const NEAR_DOUBLE: f64 = 1e-6;

/// Real roots of a·t² + b·t + c = 0 without cancellation (the q = −(b + sign(b)·√disc)/2 form).
pub(crate) fn solve_quadratic(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    if a == 0.0 {
        return [(b != 0.0).then(|| -c / b), None];
    }
    let disc = b * b - 4.0 * a * c;
    if !(disc >= 0.0) {
        return [None, None];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let t1 = q / a;
    let t2 = if q != 0.0 { c / q } else { t1 };
    [
        Some(t1).filter(|t| t.is_finite()),
        Some(t2).filter(|t| t.is_finite()),
    ]
}

/// A planar convex polygon (3 or 4 vertices) prepared for separating-axis tests against
/// axis-aligned boxes: the candidate axes (the polygon's normal, the box faces, the cross
/// products of its edges with the box axes) and the polygon's extent along each, computed once,
/// so that a box costs two dot products per axis.
#[derive(Debug, Clone)]
pub(crate) struct SweptPolygon {
    axes: [DVec3; 16],
    /// The polygon's projection [lo, hi] on each axis, and max |v·axis| over its vertices
    /// (for the round-off slack).
    lo: [f64; 16],
    hi: [f64; 16],
    magnitude: [f64; 16],
    count: usize,
}

impl SweptPolygon {
    fn new(poly: &[DVec3]) -> SweptPolygon {
        Self::with_axes(poly, true)
    }

    /// The polygon with the edge axes of every edge (`distinct_only` false: the plain
    /// separating-axis set, the test oracle) or once per edge direction, without zero axes.
    fn with_axes(poly: &[DVec3], distinct_only: bool) -> SweptPolygon {
        let mut p = SweptPolygon {
            axes: [DVec3::ZERO; 16],
            lo: [0.0; 16],
            hi: [0.0; 16],
            magnitude: [0.0; 16],
            count: 0,
        };
        let e0 = poly[1] - poly[0];
        let e1 = poly[2] - poly[1];
        // The plane first: the sweep is thin across it, so it separates most boxes at once.
        p.push(poly, e0.cross(e1));
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            p.push(poly, axis);
        }
        // Edge × coordinate axes, once per edge direction: the far edge of a parallelogram
        // repeats the near one's axes, and an edge along a coordinate axis gives a zero axis.
        // Leaving out an axis can only make the test more conservative, never wrong.
        let mut seen: [DVec3; 4] = [DVec3::ZERO; 4];
        let mut distinct = 0;
        for i in 0..poly.len() {
            let edge = poly[(i + 1) % poly.len()] - poly[i];
            let e2 = edge.length_squared();
            if !distinct_only {
                for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                    p.push(poly, edge.cross(axis));
                }
                continue;
            }
            if !(e2 > 0.0)
                || seen[..distinct]
                    .iter()
                    .any(|s| s.cross(edge).length_squared() <= 1e-24 * s.length_squared() * e2)
            {
                continue;
            }
            if distinct < seen.len() {
                seen[distinct] = edge;
                distinct += 1;
            }
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                let a = edge.cross(axis);
                if a.length_squared() > 1e-24 * e2 {
                    p.push(poly, a);
                }
            }
        }
        p
    }

    fn push(&mut self, poly: &[DVec3], axis: DVec3) {
        let (mut lo, mut hi, mut magnitude) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for v in poly {
            let s = v.dot(axis);
            lo = lo.min(s);
            hi = hi.max(s);
            magnitude = magnitude.max(s.abs());
        }
        let k = self.count;
        self.axes[k] = axis;
        self.lo[k] = lo;
        self.hi[k] = hi;
        self.magnitude[k] = magnitude;
        self.count += 1;
    }

    /// Whether the polygon may overlap the box [min, max]. Conservative: a relative slack keeps
    /// round-off from separating what touches (also the round-off of projecting polygon and box
    /// separately, which grows with the distance from the origin).
    pub(crate) fn overlaps_box(&self, min: DVec3, max: DVec3) -> bool {
        let centre = 0.5 * (min + max);
        let half = 0.5 * (max - min);
        if !(half.min_element() >= 0.0) {
            return false;
        }
        for k in 0..self.count {
            let axis = self.axes[k];
            let c = centre.dot(axis);
            let (lo, hi) = (self.lo[k] - c, self.hi[k] - c);
            let extent = half.dot(axis.abs());
            if lo <= extent && hi >= -extent {
                // Overlapping on this axis without the slack, so also with it (slack ≥ 0): the
                // same decision without computing it, for most axes of the boxes that pass.
                continue;
            }
            let slack =
                1e-9 * (extent + lo.abs().max(hi.abs())) + 1e-12 * (self.magnitude[k] + c.abs());
            if lo > extent + slack || hi < -extent - slack {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::light::Falloff;

    fn sphere(c: DVec3, r: f64) -> Particle {
        Particle {
            ellipsoid: None,
            profile: crate::optics::Profile::Constant,
            center: c,
            radius: r,
            color: DVec3::ONE,
            sigma: 1.0,
            albedo: DVec3::ONE,
            ks: 0.0,
            shininess: 0.0,
        }
    }

    /// Checks each reported root against the definition: the shadow ray from x(t*) is tangent
    /// to the sphere (its distance to the centre equals r, to 1e-9 relative).
    /// An ellipsoid's is the unit sphere's in its map.
    fn is_tangent(ray: &Ray, t: f64, light: &Light, p: &Particle) -> bool {
        let x = ray.at(t);
        let inc = light.incident_at(x).unwrap();
        let shadow = Ray {
            origin: x,
            direction: inc.toward,
        };
        let (shadow, k, radius) = match &p.ellipsoid {
            None => (shadow, 1.0, p.radius),
            Some(e) => {
                let (unit, k) = e.unit_ray(&shadow, p.center);
                (unit, k, 1.0)
            }
        };
        let center = if p.ellipsoid.is_some() {
            DVec3::ZERO
        } else {
            p.center
        };
        let f = shadow.origin - center;
        let t_c = -f.dot(shadow.direction);
        let dist = (f + t_c * shadow.direction).length();
        t_c > 0.0
            && t_c <= k * inc.distance * (1.0 + 1e-9)
            && (dist - radius).abs() < 1e-9 * radius.max(1.0)
    }

    /// Leaving out the repeated and zero edge axes changes no decision of the separating-axis
    /// test: parallelograms for directional lights along a coordinate axis (the thesis's) and
    /// oblique ones, and triangles for point lights, against random boxes.
    #[test]
    fn distinct_edge_axes_decide_like_all_sixteen() {
        let mut rng = crate::formats::random::SplitMix64::new(5);
        let mut v = |s: f64| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * s - DVec3::splat(s)
        };
        let (mut overlapping, mut separated) = (0, 0);
        for trial in 0..400 {
            let (y0, y1) = (v(3.0), v(3.0));
            let poly: Vec<DVec3> = match trial % 3 {
                0 => vec![y0, y1, y1 + DVec3::Y * 20.0, y0 + DVec3::Y * 20.0],
                1 => {
                    let w = v(1.0).normalize() * 20.0;
                    vec![y0, y1, y1 + w, y0 + w]
                }
                _ => vec![y0, y1, v(5.0)],
            };
            let (fast, all) = (
                SweptPolygon::with_axes(&poly, true),
                SweptPolygon::with_axes(&poly, false),
            );
            assert!(fast.count <= all.count);
            for _ in 0..50 {
                let c = v(4.0);
                let h = v(1.5).abs() + DVec3::splat(0.01);
                let got = fast.overlaps_box(c - h, c + h);
                assert_eq!(
                    got,
                    all.overlaps_box(c - h, c + h),
                    "trial {trial}: {poly:?}"
                );
                if got {
                    overlapping += 1;
                } else {
                    separated += 1;
                }
            }
        }
        assert!(
            overlapping > 1000 && separated > 1000,
            "{overlapping} {separated}"
        );
    }

    /// Kinks carry the side on which the shadow rays cross their sphere: just past a kink on
    /// that side the shadow ray (or, for a point light, the shadow segment to the light) crosses
    /// it, just past it on the other side it does not (random spheres and camera rays, every
    /// root of each; a directional light and a point light, also one among the spheres).
    #[test]
    fn a_kink_is_crossed_on_its_side_only() {
        kinks_are_crossed_on_their_side(false);
    }

    /// The same for ellipsoids of axis ratios up to 1:20, randomly turned: the roots of the
    /// mapped sphere are kinks of the ellipsoid, with the sides the scene's shadow rays show.
    #[test]
    fn an_ellipsoids_kink_is_crossed_on_its_side_only() {
        kinks_are_crossed_on_their_side(true);
    }

    fn random_ellipsoid(mut unit: impl FnMut(f64) -> DVec3) -> crate::geometry::Ellipsoid {
        let long = 0.3 + unit(0.5).x.abs();
        let ratio = |u: f64| 1.0 / (1.0 + 19.0 * u.abs());
        let w = unit(1.0);
        let axes = DVec3::new(long, long * ratio(w.x), long * ratio(w.y));
        let q = glam::DQuat::from_xyzw(w.z, unit(1.0).x, unit(1.0).y, unit(1.0).z + 0.1);
        crate::geometry::Ellipsoid::new(axes, q.normalize())
    }

    fn kinks_are_crossed_on_their_side(ellipsoids: bool) {
        let lights = [
            Light::Directional {
                direction: DVec3::new(0.2, -1.0, 0.1).normalize(),
                irradiance: DVec3::ONE,
            },
            Light::Point {
                position: DVec3::new(0.5, 4.0, -0.3),
                intensity: DVec3::ONE,
                falloff: Falloff::InverseSquare,
            },
            Light::Point {
                position: DVec3::new(-0.4, 0.3, 0.2),
                intensity: DVec3::ONE,
                falloff: Falloff::InverseSquare,
            },
        ];
        for light in &lights {
            let mut rng = crate::formats::random::SplitMix64::new(17);
            let mut unit = |s: f64| {
                DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * s
                    - DVec3::splat(s)
            };
            let (mut checked, mut sides) = (0, [0; 2]);
            for _ in 0..2000 {
                let c = unit(3.0);
                let r = 0.3 + unit(0.25).x.abs();
                let e = random_ellipsoid(&mut unit);
                let shape = if ellipsoids {
                    Shape::Ellipsoid {
                        center: c,
                        ellipsoid: &e,
                    }
                } else {
                    Shape::Sphere {
                        center: c,
                        radius: r,
                    }
                };
                let ray = Ray::new(DVec3::new(-6.0, 0.0, 0.0) + unit(2.0), DVec3::X + unit(0.4));
                let mut out = Vec::new();
                push_sided_tangencies(&ray, (0.0, 20.0), light, shape, &mut out);
                for &(t, side) in &out {
                    let crosses = |t: f64| {
                        let x = ray.at(t);
                        let inc = light.incident_at(x).unwrap();
                        let shadow = Ray {
                            origin: x,
                            direction: inc.toward,
                        };
                        shape
                            .intersect(&shadow)
                            .is_some_and(|h| h.t_exit > 0.0 && h.t_enter < inc.distance)
                    };
                    let d = 1e-7 * (1.0 + t.abs());
                    assert!(side == CROSSES_ABOVE || side == CROSSES_BELOW, "{side}");
                    assert_eq!(crosses(t + d), side == CROSSES_ABOVE, "t {t} side {side}");
                    assert_eq!(crosses(t - d), side == CROSSES_BELOW, "t {t} side {side}");
                    sides[usize::from(side == CROSSES_BELOW)] += 1;
                    checked += 1;
                }
            }
            assert!(
                checked > 100 && sides[0] > 40 && sides[1] > 40,
                "{light:?}: {checked} {sides:?}"
            );
        }
    }

    #[test]
    fn tangencies_are_tangent_and_every_change_of_hit_is_found() {
        let particles = vec![
            sphere(DVec3::new(0.3, 2.0, 0.1), 0.7),
            sphere(DVec3::new(-1.0, 3.0, 0.5), 0.4),
            sphere(DVec3::new(0.5, -2.5, -0.2), 0.9),
        ];
        every_change_of_hit_is_a_tangency(&particles);
    }

    /// The same with elongated (1:20) and flat ellipsoids among spheres.
    #[test]
    fn ellipsoid_tangencies_are_tangent_and_every_change_of_hit_is_found() {
        let ellipsoid = |c: DVec3, axes: DVec3, q: glam::DQuat| {
            let e = crate::geometry::Ellipsoid::new(axes, q.normalize());
            Particle {
                ellipsoid: Some(e),
                radius: e.bounding_radius(),
                ..sphere(c, 1.0)
            }
        };
        let particles = vec![
            ellipsoid(
                DVec3::new(0.3, 2.0, 0.1),
                DVec3::new(1.4, 0.07, 0.3),
                glam::DQuat::from_xyzw(0.3, 0.1, -0.4, 0.8),
            ),
            sphere(DVec3::new(-1.0, 3.0, 0.5), 0.4),
            ellipsoid(
                DVec3::new(0.5, -2.5, -0.2),
                DVec3::new(0.2, 1.2, 0.9),
                glam::DQuat::from_xyzw(-0.2, 0.5, 0.1, 0.6),
            ),
        ];
        every_change_of_hit_is_a_tangency(&particles);
    }

    fn every_change_of_hit_is_a_tangency(particles: &[Particle]) {
        let bvh = Bvh::build_shapes(
            particles.iter().map(|p| p.center).collect(),
            particles.iter().map(|p| p.radius).collect(),
            particles.iter().map(|p| p.ellipsoid).collect(),
            |_| true,
        );
        let lights = [
            Light::Directional {
                direction: DVec3::new(0.1, -1.0, 0.05).normalize(),
                irradiance: DVec3::ONE,
            },
            Light::Point {
                position: DVec3::new(0.2, 6.0, 0.3),
                intensity: DVec3::ONE,
                falloff: Falloff::InverseSquare,
            },
        ];
        let ray = Ray::new(DVec3::new(-4.0, 0.2, 0.0), DVec3::new(1.0, 0.05, 0.02));
        for light in &lights {
            let mut kinks = Vec::new();
            shadow_tangencies(&ray, (0.0, 8.0), light, &bvh, particles, &mut kinks);
            assert!(!kinks.is_empty());
            for &t in &kinks {
                let ok = particles.iter().any(|p| is_tangent(&ray, t, light, p));
                assert!(ok, "t = {t} is tangent to no sphere");
            }
            // Brute force: the set of spheres the shadow ray hits changes only at a kink.
            let hits_at = |t: f64| -> Vec<bool> {
                let x = ray.at(t);
                let inc = light.incident_at(x).unwrap();
                let sray = Ray {
                    origin: x,
                    direction: inc.toward,
                };
                particles
                    .iter()
                    .map(|p| p.shape().intersect(&sray).is_some_and(|c| c.t_exit > 0.0))
                    .collect()
            };
            let inside_at = |t: f64| -> Vec<bool> {
                let x = ray.at(t);
                particles.iter().map(|p| p.shape().contains(x)).collect()
            };
            let n = 4000;
            let mut changes = 0;
            for i in 0..n {
                let (a, b) = (8.0 * i as f64 / n as f64, 8.0 * (i + 1) as f64 / n as f64);
                // Crossing a sphere's surface also changes what the shadow ray hits; that is an
                // interval boundary of the renderer, not a tangency.
                if hits_at(a) != hits_at(b) && inside_at(a) == inside_at(b) {
                    changes += 1;
                    assert!(
                        kinks.iter().any(|&k| k >= a - 1e-9 && k <= b + 1e-9),
                        "no kink in [{a}, {b}]"
                    );
                }
            }
            assert!(changes > 0);
        }
    }
}
