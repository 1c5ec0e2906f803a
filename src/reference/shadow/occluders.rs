//! Occluder lists: the spheres a shadow ray can cross, gathered once per piece of a camera ray
//! instead of once per shadow ray (docs/design.md §3).
//!
//! The lit and single-scatter integrands fire one shadow ray per quadrature node and light. All
//! nodes of one camera-ray interval lie on the segment [x(ta), x(tb)], so every shadow ray from
//! them lies in the planar polygon that segment sweeps towards the light (a parallelogram for a
//! directional light, a triangle for a point light; `optics::kinks::swept_polygon`). One BVH
//! query with that polygon gives a short candidate list, and each node then tests only those
//! spheres, exactly, with the same ray–sphere intersection and the same filter and order as
//! [`Bvh::all_hits`]. The list is a superset of the spheres any of those shadow rays crosses
//! (the polygon test is conservative, with slack for round-off), so the hits, and with them every
//! pixel, are bit-identical to a traversal of the whole BVH per shadow ray.
//!
//! The lists are gathered once per (camera-ray interval, light). Between two kinks of a light
//! (where a shadow ray grazes a sphere, `optics::kinks`) the set of spheres crossed does not
//! change, so a list per kink-free stretch would be shorter still, but it would cost a BVH
//! query per quadrature segment (segments end at kinks), more than the longer lists cost.
//! Instead, for a directional light each candidate keeps the range of camera-ray parameters t
//! from which a shadow ray can reach it at all (the inside of its tangency cylinder, padded for
//! round-off: `reach_range`), and a node outside that range skips the sphere test: the effect of
//! a list per kink-free stretch without the extra queries.
//!
//! For a point light the reach range is the inside of the cone from the light tangent to the
//! sphere (`cone_reach_range`), convex, so again one interval of t.
//!
//! Even the query per interval is more than needed: the renderer gathers one list for the whole
//! finite stretch of the camera ray ([`Occluders::gather`] over it, one BVH query per light and
//! camera ray), and each interval's list is *narrowed* from it ([`Occluders::narrow`]: the same
//! reach-range and half-space tests, no BVH). The narrowed list keeps the wide one's order and
//! is a superset of the spheres crossed, so the hits are the same, in the same order (tested).
//!
//! **Ellipsoids** (docs/design.md §9) are culled as their bounding spheres (a superset of what
//! their own test would keep), their reach range is their own (the unit sphere's in their
//! unit-sphere coordinates: `ellipsoid_reach_range`), and they are kept in a list of their own,
//! after the spheres, and their kinks are the ellipsoid's own. Towards a directional light every
//! shadow ray of the list has the light's direction and starts on the list's camera ray, so each
//! ellipsoid's chord is a closed form in the camera-ray parameter t, prepared once per gather
//! (`ShadowLine`: one square root per shadow ray, no matrix); its chords are
//! [`Ellipsoid::intersect`]'s up to round-off (tested), so those hits are not bit for bit the
//! BVH's. Towards a point light each shadow ray tests them with the ellipsoid's intersection,
//! the one [`Bvh::all_hits`] uses (in lanes of shadow rays as the spheres, with the same
//! arithmetic). The spheres' lanes stay as they are, and so do their hits.

// `!(a > b)` is deliberate: unlike `a <= b` it is also true when a value is NaN, so degenerate
// input takes the safe branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::geometry::{Bvh, Chord, Ellipsoid, Hit, Ray, Shape};
use crate::optics::kinks::{
    axis_approach, for_each_swept_leaf, push_sided_tangencies, solve_quadratic, swept_polygon,
    AxisApproach,
};
use crate::optics::light::Light;
use glam::DVec3;

/// Relative padding of a candidate sphere's box in the polygon test: far above the round-off of
/// the node positions (≈ 1e-16 relative), far below any geometry that matters for speed.
const BOX_PADDING: f64 = 1e-7;

/// Padding of a candidate's radius, relative to the size of the coordinates involved, when its
/// range of camera-ray parameters is computed (`Candidate::t_lo`): far above the round-off of
/// the roots (≈ √ε relative where a root is double), far below any geometry.
const RANGE_PADDING: f64 = 1e-6;

/// One candidate: its index in the scene and its geometry (copied, so the per-node tests run
/// over a short contiguous array), and the camera-ray parameters [t_lo, t_hi] outside which no
/// shadow ray can reach it.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    center: DVec3,
    radius: f64,
    index: u32,
    t_lo: f64,
    t_hi: f64,
}

/// A shadow ray of [`Occluders::hits_batch`]: from the camera ray's point x(`t`), along
/// `ray`, up to `t_max` (the light's distance).
#[derive(Debug, Clone, Copy)]
pub struct ShadowRay {
    pub t: f64,
    pub ray: Ray,
    pub t_max: f64,
}

/// The candidate occluders of the shadow rays towards one light from the points x(t),
/// t ∈ [ta, tb], of one camera ray, with the key they were gathered for.
#[derive(Debug, Default)]
pub struct Occluders {
    /// (interval tag, light) of the current list; `None` before the first gather.
    key: Option<(usize, usize)>,
    /// The stretch of the camera ray the list holds for.
    ta: f64,
    tb: f64,
    candidates: Vec<Candidate>,
    /// The candidates that are ellipsoids (their `radius` the bounding radius), with their
    /// ellipsoids, position for position.
    ellipsoid_candidates: Vec<Candidate>,
    ellipsoids: Vec<Ellipsoid>,
    /// Each ellipsoid candidate's shadow rays in closed form along the camera ray, position for
    /// position (`None` for a point light, or where the form is not worth its round-off).
    shadow_lines: Vec<Option<ShadowLine>>,
    /// The direction of the shadow rays that `shadow_lines` hold for: a directional light's
    /// unit vector towards it.
    line_toward: Option<DVec3>,
}

impl Occluders {
    /// Forgets the list's key, so that it covers nothing until the next gather or narrowing:
    /// for a buffer reused on another camera ray, whose intervals have the same tags.
    pub fn invalidate(&mut self) {
        self.key = None;
    }

    /// Whether the list holds for the shadow rays towards light `light` from x(t) in interval
    /// `tag`.
    #[inline]
    pub fn covers(&self, tag: usize, light: usize, t: f64) -> bool {
        self.key == Some((tag, light)) && t >= self.ta && t <= self.tb
    }

    /// Empties the list and keys it to (interval `tag`, light `l`) over [ta, tb].
    fn start(&mut self, (tag, l): (usize, usize), (ta, tb): (f64, f64)) {
        self.key = Some((tag, l));
        self.ta = ta;
        self.tb = tb;
        self.candidates.clear();
        self.ellipsoid_candidates.clear();
        self.ellipsoids.clear();
        self.shadow_lines.clear();
        self.line_toward = None;
    }

    /// Gathers the spheres of `bvh` whose padded box the polygon swept from [x(ta), x(tb)]
    /// towards `light` may touch, for interval `tag` and light index `l`. The renderer's BVH
    /// holds the spheres with σ > 0 only (`Scene::build_gas_bvh`), the only ones that
    /// contribute to a shadow ray: no particle is read here (in a large scene each read would
    /// be a cache miss).
    pub fn gather(
        &mut self,
        bvh: &Bvh,
        camera_ray: &Ray,
        (tag, l): (usize, usize),
        light: &Light,
        (ta, tb): (f64, f64),
    ) {
        self.start((tag, l), (ta, tb));
        let (ya, yb) = (camera_ray.at(ta), camera_ray.at(tb));
        let poly = swept_polygon(bvh, light, ya, yb);
        let ahead = AheadOfSegment::new(light, ya, yb);
        let candidates = &mut self.candidates;
        let (ellipsoid_candidates, ellipsoids, shadow_lines) = (
            &mut self.ellipsoid_candidates,
            &mut self.ellipsoids,
            &mut self.shadow_lines,
        );
        for_each_swept_leaf(bvh, &poly, |leaf| {
            // The leaf's centres and radii (the particles', in leaf order) lie together.
            for (k, (i, center, radius)) in leaf.spheres().enumerate() {
                let (t_lo, t_hi) = match leaf.ellipsoid(k) {
                    None => reach_range(camera_ray, light, center, radius, tb),
                    Some(e) => ellipsoid_reach_range(camera_ray, light, center, e, tb),
                };
                if !(t_lo <= tb && t_hi >= ta) {
                    continue;
                }
                let pad = padded_radius(center, radius);
                // A finite reach range is the cylinder test of a directional light; with the
                // half-space test below it is as tight as the polygon's (which is the
                // cylinder's inside, cut at the segment) and far cheaper than its axes.
                let near = match &ahead {
                    Some(ahead) if t_lo.is_finite() && t_hi.is_finite() => ahead.keeps(center, pad),
                    _ => poly.overlaps_box(center - DVec3::splat(pad), center + DVec3::splat(pad)),
                };
                if near {
                    let candidate = Candidate {
                        center,
                        radius,
                        index: i,
                        t_lo,
                        t_hi,
                    };
                    match leaf.ellipsoid(k) {
                        None => candidates.push(candidate),
                        Some(e) => {
                            ellipsoid_candidates.push(candidate);
                            ellipsoids.push(*e);
                            shadow_lines.push(ShadowLine::new(camera_ray, light, center, e));
                        }
                    }
                }
            }
        });
        if let Light::Directional { direction, .. } = *light {
            self.line_toward = Some(-direction);
        }
        // In the order of their centres along a directional light's shadow rays (which all
        // share its direction), so that each node's hits arrive nearly sorted by entry and the
        // interval cutter's sort has little to do. The order does not change any result.
        if let Light::Directional { direction, .. } = *light {
            let toward = -direction;
            candidates.sort_unstable_by(|a, b| {
                a.center
                    .dot(toward)
                    .total_cmp(&b.center.dot(toward))
                    .then(a.index.cmp(&b.index))
            });
        }
    }

    /// The kinks of `light` along `camera_ray` in (t_lo, t_hi), as
    /// [`shadow_tangencies`](crate::optics::kinks::shadow_tangencies) finds them with a query of
    /// the BVH, from this list instead (gathered for a stretch of the same ray that contains
    /// (t_lo, t_hi), towards the same light), into `out`, sorted: saves the renderer a second
    /// traversal with the same polygon. The same values: a sphere with a tangency in the
    /// stretch is in the list (its padded reach range holds the tangency, and it is not wholly
    /// behind the stretch, where the tangent point lies ahead), and each sphere's roots come
    /// from the same function; a test compares the two, bit for bit. (The renderer takes
    /// [`Occluders::sided_tangencies`]; this is its values, for that test.)
    #[cfg(test)]
    pub fn tangencies(
        &self,
        camera_ray: &Ray,
        (t_lo, t_hi): (f64, f64),
        light: &Light,
        out: &mut Vec<f64>,
    ) {
        let mut sided = Vec::new();
        self.sided_tangencies(camera_ray, (t_lo, t_hi), light, &mut sided);
        out.extend(sided.into_iter().map(|(t, _)| t));
    }

    /// [`Occluders::tangencies`] with the side of each on which the shadow rays cross the
    /// sphere (`kinks::push_sided_tangencies`), sorted by value, equal values merged into one
    /// with both their sides. `out` is not cleared.
    pub fn sided_tangencies(
        &self,
        camera_ray: &Ray,
        (t_lo, t_hi): (f64, f64),
        light: &Light,
        out: &mut Vec<(f64, u8)>,
    ) {
        debug_assert!(
            self.ta <= t_lo && t_hi <= self.tb,
            "a list for another stretch"
        );
        if !(t_hi > t_lo) || !t_lo.is_finite() || !t_hi.is_finite() {
            return;
        }
        for c in &self.candidates {
            let shape = Shape::Sphere {
                center: c.center,
                radius: c.radius,
            };
            push_sided_tangencies(camera_ray, (t_lo, t_hi), light, shape, out);
        }
        for (c, ellipsoid) in self.ellipsoid_candidates.iter().zip(&self.ellipsoids) {
            let shape = Shape::Ellipsoid {
                center: c.center,
                ellipsoid,
            };
            push_sided_tangencies(camera_ray, (t_lo, t_hi), light, shape, out);
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        out.dedup_by(|b, a| {
            if a.0 == b.0 {
                a.1 |= b.1;
                true
            } else {
                false
            }
        });
    }

    /// The candidates of `wide` (gathered for a stretch of the same camera ray that contains
    /// [ta, tb], towards the same light) that shadow rays from x(t), t ∈ [ta, tb], can reach:
    /// those whose reach range meets [ta, tb] and, for a directional light, that are not wholly
    /// behind the segment (the tests of [`Occluders::gather`], without its BVH query). A
    /// superset of the spheres those shadow rays cross, in `wide`'s order, so
    /// [`Occluders::hits`] gives exactly what it gives after a gather of its own. Candidates of
    /// `wide` with an unbounded reach range are all kept.
    pub fn narrow(
        &mut self,
        wide: &Occluders,
        camera_ray: &Ray,
        (tag, l): (usize, usize),
        light: &Light,
        (ta, tb): (f64, f64),
    ) {
        self.start((tag, l), (ta, tb));
        let ahead = AheadOfSegment::new(light, camera_ray.at(ta), camera_ray.at(tb));
        let keep = |c: &Candidate| {
            if !(c.t_lo <= tb && c.t_hi >= ta) {
                return false;
            }
            match &ahead {
                Some(ahead) if c.t_lo.is_finite() && c.t_hi.is_finite() => {
                    ahead.keeps(c.center, padded_radius(c.center, c.radius))
                }
                _ => true,
            }
        };
        for c in &wide.candidates {
            if keep(c) {
                self.candidates.push(*c);
            }
        }
        let ellipsoids = wide.ellipsoid_candidates.iter().zip(&wide.ellipsoids);
        for ((c, e), line) in ellipsoids.zip(&wide.shadow_lines) {
            if keep(c) {
                self.ellipsoid_candidates.push(*c);
                self.ellipsoids.push(*e);
                self.shadow_lines.push(*line);
            }
        }
        self.line_toward = wide.line_toward;
    }

    /// Every candidate whose chord overlaps (0, t_max) along `ray`, the shadow ray from the
    /// camera ray's point x(`t`) (of the camera ray the list was gathered for): the set that
    /// [`Bvh::all_hits`]`(ray, 0, t_max)` returns for the spheres with σ > 0 (the others
    /// contribute nothing to a shadow ray), in list order, the spheres' list before the
    /// ellipsoids' (the interval cutter takes hits in any order and gives the same intervals);
    /// an ellipsoid's chord towards a directional light up to round-off (`ShadowLine`: a
    /// shadow ray within round-off of a graze may find a hit of that size that `all_hits` does
    /// not, or miss one). Candidates whose reach range excludes `t` are not tested. `out` is
    /// cleared first.
    #[cfg(test)]
    pub fn hits(&self, t: f64, ray: &Ray, t_max: f64, out: &mut Vec<Hit>) {
        self.hits_batch(
            &[ShadowRay {
                t,
                ray: *ray,
                t_max,
            }],
            std::slice::from_mut(out),
        );
    }

    /// [`Occluders::hits`] of several shadow rays at once, `out[i]` for `shadow[i]`: the list
    /// is read once, each candidate tested against every shadow ray in turn (the nodes of one
    /// quadrature segment, whose shadow rays mostly cross the same candidates). Each `out[i]`
    /// is cleared first and gets the same hits in the same order as `hits` would give it.
    pub fn hits_batch(&self, shadow: &[ShadowRay], out: &mut [Vec<Hit>]) {
        for o in out.iter_mut() {
            o.clear();
        }
        for (shadow, out) in shadow.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let lanes = Lanes::new(shadow);
            hits_in_lanes(&self.candidates, &lanes, shadow, out);
            if !self.ellipsoids.is_empty() {
                ellipsoid_hits_in_lanes(self, &lanes, shadow, out);
            }
        }
    }

    /// Number of candidates in the current list.
    pub fn len(&self) -> usize {
        self.candidates.len() + self.ellipsoid_candidates.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Shadow rays per pass of [`hits_in_lanes`]: one level of a quadrature segment (G7's seven
/// nodes, or the eight K15 adds).
const LANES: usize = 8;

/// Up to [`LANES`] shadow rays laid out for the lane loops: origins and directions by
/// coordinate, and the span [t_first, t_last] of their camera-ray parameters (a candidate whose
/// reach range misses all of it is skipped whole; any NaN t makes it (−∞, ∞), so that every
/// candidate is tested).
struct Lanes {
    n: usize,
    o: [[f64; LANES]; 3],
    d: [[f64; LANES]; 3],
    t_first: f64,
    t_last: f64,
}

impl Lanes {
    fn new(shadow: &[ShadowRay]) -> Lanes {
        let n = shadow.len().min(LANES);
        let (mut o, mut d) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
        let (mut t_first, mut t_last) = (f64::INFINITY, f64::NEG_INFINITY);
        for (i, s) in shadow[..n].iter().enumerate() {
            (o[0][i], o[1][i], o[2][i]) = s.ray.origin.into();
            (d[0][i], d[1][i], d[2][i]) = s.ray.direction.into();
            if s.t.is_nan() {
                (t_first, t_last) = (f64::NEG_INFINITY, f64::INFINITY);
            } else {
                (t_first, t_last) = (t_first.min(s.t), t_last.max(s.t));
            }
        }
        Lanes {
            n,
            o,
            d,
            t_first,
            t_last,
        }
    }
}

/// [`Occluders::hits_batch`] for up to [`LANES`] shadow rays (`lanes`, made from `shadow`),
/// `out` cleared: each candidate in list order, against every shadow ray whose reach range
/// holds it. The chords are `intersect_sphere`'s, with its arithmetic in the same order,
/// computed for all lanes at once with no branch (so that the compiler puts them in SIMD
/// lanes, two square roots per instruction, where the loop over one ray at a time waited for
/// each), and kept where its checks pass. (Compiled for AVX2's four lanes it was no faster: 1UUN lit 128², one thread,
/// 15 interleaved runs, fastest 1.27 s against 1.26 s.)
fn hits_in_lanes(
    candidates: &[Candidate],
    lanes: &Lanes,
    shadow: &[ShadowRay],
    out: &mut [Vec<Hit>],
) {
    let (n, t_first, t_last) = (lanes.n, lanes.t_first, lanes.t_last);
    let ([ox, oy, oz], [dx, dy, dz]) = (&lanes.o, &lanes.d);
    for c in candidates {
        if c.t_hi < t_first || c.t_lo > t_last {
            continue;
        }
        let (cx, cy, cz, r) = (c.center.x, c.center.y, c.center.z, c.radius);
        let (mut t_c, mut dist, mut half) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for i in 0..LANES {
            // f = o − c, t_c = −f·d, l = f + t_c·d, |l|, √((r − |l|)(r + |l|)), as
            // `intersect_sphere` (and glam's dot product) compute them.
            let (fx, fy, fz) = (ox[i] - cx, oy[i] - cy, oz[i] - cz);
            let tc = -(fx * dx[i] + fy * dy[i] + fz * dz[i]);
            let (lx, ly, lz) = (fx + tc * dx[i], fy + tc * dy[i], fz + tc * dz[i]);
            let d = (lx * lx + ly * ly + lz * lz).sqrt();
            t_c[i] = tc;
            dist[i] = d;
            half[i] = ((r - d) * (r + d)).sqrt();
        }
        for (i, (s, o)) in shadow[..n].iter().zip(out.iter_mut()).enumerate() {
            // Written so that a NaN t tests every candidate; `intersect_sphere`'s misses are
            // dist ≥ r and a half-chord ≤ 0.
            if s.t < c.t_lo || s.t > c.t_hi || dist[i] >= r || half[i] <= 0.0 {
                continue;
            }
            let chord = Chord {
                t_enter: t_c[i] - half[i],
                t_exit: t_c[i] + half[i],
            };
            if chord.t_exit > 0.0 && chord.t_enter < s.t_max {
                o.push(Hit {
                    index: c.index,
                    chord,
                });
            }
        }
    }
}

/// The ellipsoids' part of [`Occluders::hits_batch`], for up to [`LANES`] shadow rays
/// (`lanes`, made from `shadow`): each ellipsoid candidate of `list` against every shadow ray
/// whose reach range holds it, appended to `out`. Where the pass is one of shadow rays towards
/// the directional light the list was gathered for, from points of its camera ray (every ray
/// with the light's direction, every t finite), a candidate with a [`ShadowLine`] gives its
/// chords in closed form ([`ShadowLine::hits`]); the others take [`Ellipsoid::intersect`]'s
/// arithmetic ([`exact_ellipsoid_hits`]). Not inlined: the spheres' pass in
/// [`Occluders::hits_batch`] keeps its own code.
#[inline(never)]
fn ellipsoid_hits_in_lanes(
    list: &Occluders,
    lanes: &Lanes,
    shadow: &[ShadowRay],
    out: &mut [Vec<Hit>],
) {
    let (n, t_first, t_last) = (lanes.n, lanes.t_first, lanes.t_last);
    // The direction every ray has, where they all have the same bits (a directional light's).
    let bits = |d: DVec3| d.to_array().map(f64::to_bits);
    let shared_direction = shadow
        .first()
        .map(|first| first.ray.direction)
        .filter(|&d| shadow[..n].iter().all(|s| bits(s.ray.direction) == bits(d)));
    let on_lines = t_first.is_finite()
        && t_last.is_finite()
        && shared_direction
            .zip(list.line_toward)
            .is_some_and(|(d, toward)| bits(d) == bits(toward));
    // The camera-ray parameters by lane (0 past n), for the closed forms.
    let mut t = [0.0; LANES];
    for (t, s) in t.iter_mut().zip(&shadow[..n]) {
        *t = s.t;
    }
    let ellipsoids = list.ellipsoid_candidates.iter().zip(&list.ellipsoids);
    for ((c, ellipsoid), line) in ellipsoids.zip(&list.shadow_lines) {
        if c.t_hi < t_first || c.t_lo > t_last {
            continue;
        }
        match line {
            Some(line) if on_lines => line.hits(c.index, &t, shadow, out),
            _ => exact_ellipsoid_hits(c, ellipsoid, shared_direction, lanes, shadow, out),
        }
    }
}

/// One ellipsoid candidate `c` against up to [`LANES`] shadow rays, with
/// [`Ellipsoid::intersect`]'s arithmetic in the same order (glam's matrix–vector product and
/// length, the unit sphere's `intersect_sphere`, the division by k), computed for all lanes at
/// once with no branch as in [`hits_in_lanes`], so the hits are bit for bit those of the
/// ray-at-a-time test. The mapped direction is computed once where all rays share it
/// (`shared_direction`).
fn exact_ellipsoid_hits(
    c: &Candidate,
    ellipsoid: &Ellipsoid,
    shared_direction: Option<DVec3>,
    lanes: &Lanes,
    shadow: &[ShadowRay],
    out: &mut [Vec<Hit>],
) {
    let n = lanes.n;
    let ([ox, oy, oz], [dx, dy, dz]) = (&lanes.o, &lanes.d);
    let (cx, cy, cz) = (c.center.x, c.center.y, c.center.z);
    let m = ellipsoid.to_unit_matrix();
    let (mx, my, mz) = (m.x_axis, m.y_axis, m.z_axis);
    // e = M·d as glam's product sums it (x, then y, then z column), k = |e|, v = e/k:
    // once for a direction all rays share (the same bits as per ray), else per ray.
    let unit_direction = |(dx, dy, dz): (f64, f64, f64)| {
        let ex = mx.x * dx + my.x * dy + mz.x * dz;
        let ey = mx.y * dx + my.y * dy + mz.y * dz;
        let ez = mx.z * dx + my.z * dy + mz.z * dz;
        let k = (ex * ex + ey * ey + ez * ez).sqrt();
        [ex / k, ey / k, ez / k, k]
    };
    let (mut vx, mut vy, mut vz, mut k) = ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
    match shared_direction {
        Some(d) => {
            let [x, y, z, w] = unit_direction(d.into());
            (vx, vy, vz, k) = ([x; LANES], [y; LANES], [z; LANES], [w; LANES]);
        }
        None => {
            for i in 0..LANES {
                [vx[i], vy[i], vz[i], k[i]] = unit_direction((dx[i], dy[i], dz[i]));
            }
        }
    }
    let (mut dist, mut half) = ([0.0; LANES], [0.0; LANES]);
    let (mut enter, mut exit) = ([0.0; LANES], [0.0; LANES]);
    for i in 0..LANES {
        // u = M(o − c) as glam's product sums it; then the unit sphere's t_c, |l| and
        // half-chord along v, and the chord's ends divided by k.
        let (fx, fy, fz) = (ox[i] - cx, oy[i] - cy, oz[i] - cz);
        let ux = mx.x * fx + my.x * fy + mz.x * fz;
        let uy = mx.y * fx + my.y * fy + mz.y * fz;
        let uz = mx.z * fx + my.z * fy + mz.z * fz;
        let tc = -(ux * vx[i] + uy * vy[i] + uz * vz[i]);
        let (lx, ly, lz) = (ux + tc * vx[i], uy + tc * vy[i], uz + tc * vz[i]);
        let d = (lx * lx + ly * ly + lz * lz).sqrt();
        let h = ((1.0 - d) * (1.0 + d)).sqrt();
        dist[i] = d;
        half[i] = h;
        enter[i] = (tc - h) / k[i];
        exit[i] = (tc + h) / k[i];
    }
    for (i, (s, o)) in shadow[..n].iter().zip(out.iter_mut()).enumerate() {
        // As in `hits_in_lanes`: a NaN t tests every candidate, and the unit sphere's
        // misses are |l| ≥ 1 and a half-chord ≤ 0.
        if s.t < c.t_lo || s.t > c.t_hi || dist[i] >= 1.0 || half[i] <= 0.0 {
            continue;
        }
        let chord = Chord {
            t_enter: enter[i],
            t_exit: exit[i],
        };
        if chord.t_exit > 0.0 && chord.t_enter < s.t_max {
            o.push(Hit {
                index: c.index,
                chord,
            });
        }
    }
}

/// An ellipsoid's chords along the shadow rays towards a directional light from the points
/// x(t) = o + t·d of one camera ray, as functions of t, prepared once per gather.
///
/// In the ellipsoid's unit-sphere coordinates (x ↦ M(x − c), `geometry::ellipsoid`) the camera
/// ray is u(s) = u₀ + s·δ (|δ| = 1, s = k_c·t, k_c = |Md|) and every shadow ray runs along the
/// unit vector v = Mω/k_l (ω towards the light, k_l = |Mω|), a shadow parameter σ of the mapped
/// ray being k_l·τ of the world's. The shadow ray from u(s) crosses the unit sphere where
/// σ = σ_c(s) ± √(1 − |u⊥(s)|²), σ_c(s) = −u(s)·v and u⊥ the part of u normal to v. Both are
/// closed forms in t about the camera ray's closest approach to the light's axis through the
/// centre (`kinks::axis_approach`: at s_c, at distance ρ, a = |δ⊥|²):
///
/// |u⊥|² = ρ² + a·k_c²·(t − t_c)²,   σ_c = σ_c(s_c) − k_c·(δ·v)·(t − t_c),   t_c = s_c/k_c,
///
/// so a shadow ray's chord is τ = [σ_c ∓ √((1 − ρ)(1 + ρ) − a·k_c²·(t − t_c)²)]/k_l: one square
/// root and no matrix per ray. The chords differ from [`Ellipsoid::intersect`]'s by round-off
/// (both compute the same quantities in stable forms; this one's origin is o + t·d exactly
/// rather than rounded), and the hit decision can differ only for shadow rays within round-off
/// of a graze, where the chord is of the size of that round-off.
#[derive(Debug, Clone, Copy)]
struct ShadowLine {
    /// t_c: the camera-ray parameter of the closest approach.
    t_c: f64,
    /// (1 − ρ)(1 + ρ): the squared half-chord (unit coordinates) at t_c.
    gap: f64,
    /// a·k_c²: how fast the squared half-chord shrinks away from t_c, per t².
    shrink: f64,
    /// σ_c(s_c)/k_l: the world shadow parameter of the chord's midpoint at t_c.
    mid: f64,
    /// −k_c·(δ·v)/k_l: its rate of change per unit of t.
    mid_slope: f64,
    /// 1/k_l.
    inv_k: f64,
}

impl ShadowLine {
    /// The closed form for ellipsoid `e` about `c`, the shadow rays towards `light` from
    /// `camera_ray`; `None` for a point light, and where the camera ray runs (nearly) along
    /// the light in unit coordinates (a tiny a) or the map gives non-finite values.
    fn new(camera_ray: &Ray, light: &Light, c: DVec3, e: &Ellipsoid) -> Option<ShadowLine> {
        let Light::Directional { direction, .. } = *light else {
            return None;
        };
        let (unit, k_c) = e.unit_ray(camera_ray, c);
        let toward = e.to_unit(DVec3::ZERO, -direction);
        let k_l = toward.length();
        let v = toward / k_l;
        let approach = axis_approach(&unit, v, DVec3::ZERO, 1e-12)?;
        let rho = approach.dist;
        let line = ShadowLine {
            t_c: approach.t_c / k_c,
            gap: (1.0 - rho) * (1.0 + rho),
            shrink: approach.a * k_c * k_c,
            mid: -unit.at(approach.t_c).dot(v) / k_l,
            mid_slope: -k_c * unit.direction.dot(v) / k_l,
            inv_k: 1.0 / k_l,
        };
        let values = [
            line.t_c,
            line.gap,
            line.shrink,
            line.mid,
            line.mid_slope,
            line.inv_k,
        ];
        values.iter().all(|x| x.is_finite()).then_some(line)
    }

    /// The chords of the shadow rays `shadow` (up to [`LANES`]) from x(t), t = `t[i]`,
    /// computed for all lanes with no branch, each kept (as `index`'s hit) where it is a
    /// crossing (a half-chord > 0) that overlaps (0, t_max), appended to `out`.
    #[inline(always)]
    fn hits(&self, index: u32, t: &[f64; LANES], shadow: &[ShadowRay], out: &mut [Vec<Hit>]) {
        let (mut mid, mut half) = ([0.0; LANES], [0.0; LANES]);
        for i in 0..LANES {
            let dt = t[i] - self.t_c;
            // NaN where the shadow ray misses: the test below is false for it.
            half[i] = (self.gap - self.shrink * dt * dt).sqrt() * self.inv_k;
            mid[i] = self.mid + self.mid_slope * dt;
        }
        for (i, (s, o)) in shadow.iter().zip(out.iter_mut()).enumerate() {
            if !(half[i] > 0.0) {
                continue;
            }
            let chord = Chord {
                t_enter: mid[i] - half[i],
                t_exit: mid[i] + half[i],
            };
            if chord.t_exit > 0.0 && chord.t_enter < s.t_max {
                o.push(Hit { index, chord });
            }
        }
    }
}

/// The radius of a sphere padded by [`BOX_PADDING`], relative to it and to its coordinates, for
/// the conservative box and half-space tests.
fn padded_radius(center: DVec3, radius: f64) -> f64 {
    radius * (1.0 + BOX_PADDING) + BOX_PADDING * center.abs().max_element()
}

/// The half-space test of [`Occluders::gather`] for one camera segment [y_a, y_b] and a
/// directional light: a shadow ray from x leaves a sphere (c, r) behind (t_exit ≤ 0) when
/// (c − x)·ω < −r, and (c − x)·ω is linear along the segment, so a sphere behind both ends is
/// behind every point between. The slack (the box padding of the polygon test, `BOX_PADDING`,
/// of the ends' size) covers the round-off of both sides. Prepared once per gather.
struct AheadOfSegment {
    toward: DVec3,
    ya: DVec3,
    yb: DVec3,
    slack: f64,
}

impl AheadOfSegment {
    /// `None` for anything but a directional light.
    fn new(light: &Light, ya: DVec3, yb: DVec3) -> Option<Self> {
        let Light::Directional { direction, .. } = *light else {
            return None;
        };
        Some(AheadOfSegment {
            toward: -direction,
            ya,
            yb,
            slack: BOX_PADDING * (ya.abs().max_element() + yb.abs().max_element()),
        })
    }

    /// Whether the sphere about `c` with padded radius `r_pad` is not wholly behind the
    /// segment (also true for NaN, and so for non-finite ends).
    fn keeps(&self, c: DVec3, r_pad: f64) -> bool {
        let behind = |y: DVec3| (c - y).dot(self.toward) < -(r_pad + self.slack);
        !(behind(self.ya) && behind(self.yb))
    }
}

/// A superset [t_lo, t_hi] of the camera-ray parameters t ≤ `t_end` whose shadow ray towards
/// `light` can cross the sphere (c, r); (−∞, ∞) where it is not worth computing.
///
/// Directional light, unit ω towards it: the shadow ray from x(t) = o + t·d crosses the sphere
/// only if the distance of c from the line x(t) + s·ω is below r, i.e. |q⊥ + t·d⊥| < r with
/// q⊥, d⊥ the parts of o − c and d normal to ω: the inside of the cylinder of `optics::kinks`,
/// an interval of t around the closest approach t_c, of half-width √((r² − m)/|d⊥|²), m the
/// squared closest distance (computed in the same stable form as the sphere intersection). The
/// radius is padded by [`RANGE_PADDING`] of the coordinates' size, which widens each side by more
/// than the round-off of the roots and of the shadow ray's own intersection test, and the
/// result is widened once more by the same amount in t. (Whether the sphere lies ahead of x is
/// left to the exact test.) Point lights: [`cone_reach_range`].
fn reach_range(camera_ray: &Ray, light: &Light, c: DVec3, r: f64, t_end: f64) -> (f64, f64) {
    let size = camera_ray.origin.abs().max_element()
        + c.abs().max_element()
        + r
        + if t_end.is_finite() { t_end.abs() } else { 0.0 };
    range_of_padded(camera_ray, light, c, r, RANGE_PADDING * size)
}

/// [`reach_range`] of an ellipsoid `e` about `c`: the unit sphere's range for the camera ray
/// and the light in the ellipsoid's unit-sphere coordinates (the map x ↦ M(x − c) takes lines
/// to lines and shadow rays to the mapped light's shadow rays, as in `kinks::ellipsoid_roots`;
/// a parameter s of the mapped ray with unit direction is k·t, k = |Md|), tighter than its
/// bounding sphere's. The padding is the world one ([`RANGE_PADDING`] of the coordinates' size)
/// divided by the shortest semi-axis, which bounds what a world distance becomes in unit
/// coordinates, so it covers the round-off of the map and of the mapped roots and shadow ray
/// tests as the sphere's covers its own.
fn ellipsoid_reach_range(
    camera_ray: &Ray,
    light: &Light,
    c: DVec3,
    e: &Ellipsoid,
    t_end: f64,
) -> (f64, f64) {
    let size = camera_ray.origin.abs().max_element()
        + c.abs().max_element()
        + e.bounding_radius()
        + if t_end.is_finite() { t_end.abs() } else { 0.0 };
    let pad = RANGE_PADDING * size / e.shortest_semi_axis();
    let (unit, k) = e.unit_ray(camera_ray, c);
    let mapped = crate::optics::kinks::light_in_unit_coordinates(light, c, e);
    if !(k > 0.0 && k.is_finite()) {
        return ALL;
    }
    let (s_lo, s_hi) = range_of_padded(&unit, &mapped, DVec3::ZERO, 1.0, pad);
    (s_lo / k, s_hi / k)
}

/// [`reach_range`] with the radius padding `pad` given.
fn range_of_padded(camera_ray: &Ray, light: &Light, c: DVec3, r: f64, pad: f64) -> (f64, f64) {
    if !pad.is_finite() {
        return ALL;
    }
    let direction = match *light {
        Light::Directional { direction, .. } => direction,
        Light::Point { position, .. } => {
            return cone_reach_range(camera_ray, position, c, r, pad);
        }
    };
    let Some(AxisApproach { t_c, dist, a }) = axis_approach(camera_ray, -direction, c, 1e-12)
    else {
        // The camera ray runs (nearly) along the light: the range would be huge or undefined.
        return ALL;
    };
    let r_pad = r + pad;
    if !(dist < r_pad) {
        return if dist.is_nan() || t_c.is_nan() {
            ALL
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
    }
    let half = ((r_pad - dist) * (r_pad + dist) / a).sqrt() + pad / a.sqrt();
    (t_c - half, t_c + half)
}

/// Every camera-ray parameter: the reach range where none is worth computing.
const ALL: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

/// [`reach_range`] for a point light at `p`: the shadow segment from x to p can cross the sphere
/// (c, r) only if x lies in the solid cone with apex p around the axis towards c whose surface
/// touches the sphere (a point y of the sphere on the segment is in that cone, and x lies on the
/// ray from p through y). The cone is taken for the radius padded by `pad`, so that it holds
/// the true one with room for the round-off of the roots; its half-angle is below 90°, so it is
/// convex and the camera ray meets it in one interval of t, found between the roots of
/// (v·w)² − cos²α·|v|² = 0 (v = x(t) − p, w the unit axis) and the zero of v·w, each piece
/// tested at an inner point; the result is widened by `pad` (relative to its size) again.
/// Everything near-degenerate (the light within the padded sphere, roots closer than 1e-9 of
/// their size, where a piece test could err) keeps every t.
fn cone_reach_range(camera_ray: &Ray, p: DVec3, c: DVec3, r: f64, pad: f64) -> (f64, f64) {
    let axis = c - p;
    let dist = axis.length();
    let r_pad = r + pad;
    if !(dist > 2.0 * r_pad) {
        // Wide cones (near a half-angle of 90°) and a light in or near the sphere.
        return ALL;
    }
    let w = axis / dist;
    let k = (1.0 - r_pad / dist) * (1.0 + r_pad / dist);
    let (v0, d) = (camera_ray.origin - p, camera_ray.direction);
    let (v0w, dw) = (v0.dot(w), d.dot(w));
    let inside = |t: f64| {
        let v = v0 + t * d;
        let g = v.dot(w);
        g > 0.0 && g * g >= k * v.length_squared()
    };
    let qa = dw * dw - k;
    let qb = 2.0 * (v0w * dw - k * v0.dot(d));
    let qc = v0w * v0w - k * v0.length_squared();
    let mut cuts = [0.0; 3];
    let mut n = 0;
    for t in solve_quadratic(qa, qb, qc).into_iter().flatten() {
        cuts[n] = t;
        n += 1;
    }
    if dw != 0.0 {
        let t = -v0w / dw;
        if t.is_finite() {
            cuts[n] = t;
            n += 1;
        }
    }
    let cuts = &mut cuts[..n];
    if cuts.iter().any(|t| t.is_nan()) {
        return ALL;
    }
    cuts.sort_unstable_by(f64::total_cmp);
    let scale = cuts.iter().fold(1.0f64, |m, t| m.max(t.abs()));
    if cuts.windows(2).any(|w| w[1] - w[0] <= 1e-9 * scale) {
        return ALL;
    }
    // The pieces between the cuts (and beyond the outer ones), each tested at an inner point.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut piece = |a: f64, b: f64, at: f64| {
        if inside(at) {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    };
    match cuts.len() {
        0 => piece(f64::NEG_INFINITY, f64::INFINITY, 0.0),
        m => {
            piece(f64::NEG_INFINITY, cuts[0], cuts[0] - scale);
            for j in 1..m {
                piece(cuts[j - 1], cuts[j], 0.5 * (cuts[j - 1] + cuts[j]));
            }
            piece(cuts[m - 1], f64::INFINITY, cuts[m - 1] + scale);
        }
    }
    if !(lo <= hi) {
        // Nowhere inside: no shadow ray from this camera ray reaches the sphere.
        return (f64::INFINITY, f64::NEG_INFINITY);
    }
    let widen = pad + RANGE_PADDING * scale;
    (lo - widen, hi + widen)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::random::SplitMix64;
    use crate::geometry::intersect_sphere;
    use crate::optics::kinks::shadow_tangencies;
    use crate::optics::light::Falloff;
    use crate::optics::particle::Particle;

    /// The cone's reach range holds every camera-ray parameter whose shadow segment towards the
    /// point light crosses the sphere (sampled densely, and bisected onto the range's edges of
    /// the exact test), and is finite in most cases (so the test can fail).
    #[test]
    fn the_cone_reach_range_holds_every_shadow_segment_that_crosses_the_sphere() {
        let mut rng = SplitMix64::new(19);
        let mut v = |s: f64| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * s - DVec3::splat(s)
        };
        let crosses = |ray: &Ray, t: f64, p: DVec3, c: DVec3, r: f64| {
            let x = ray.at(t);
            let to = p - x;
            let d = to.length();
            let shadow = Ray {
                origin: x,
                direction: to / d,
            };
            intersect_sphere(&shadow, c, r).is_some_and(|h| h.t_exit > 0.0 && h.t_enter < d)
        };
        let (mut finite, mut crossing) = (0, 0);
        for trial in 0..600 {
            let p = v(4.0);
            let (c, r) = (v(3.0), 0.2 + 0.8 * v(1.0).x.abs());
            let ray = Ray::new(v(6.0), v(1.0).normalize());
            let (lo, hi) = cone_reach_range(&ray, p, c, r, 1e-6 * 20.0);
            finite += usize::from(lo.is_finite() || lo > hi);
            let ts: Vec<f64> = (0..800).map(|j| -20.0 + 0.05 * j as f64).collect();
            for w in ts.windows(2) {
                let (a, b) = (crosses(&ray, w[0], p, c, r), crosses(&ray, w[1], p, c, r));
                let mut check = |t: f64| {
                    if crosses(&ray, t, p, c, r) {
                        crossing += 1;
                        assert!(
                            t >= lo && t <= hi,
                            "trial {trial}: t {t} outside [{lo}, {hi}]"
                        );
                    }
                };
                check(w[0]);
                if a != b {
                    // Bisect onto the edge of the crossing set, and test the last crossing t.
                    let (mut x0, mut x1) = (w[0], w[1]);
                    for _ in 0..60 {
                        let m = 0.5 * (x0 + x1);
                        if crosses(&ray, m, p, c, r) == a {
                            x0 = m;
                        } else {
                            x1 = m;
                        }
                    }
                    check(x0);
                    check(x1);
                }
            }
        }
        assert!(finite > 400, "the range should mostly be finite: {finite}");
        assert!(
            crossing > 5000,
            "the samples should cross spheres: {crossing}"
        );
    }

    /// An ellipsoid's own reach range holds every camera-ray parameter whose shadow ray towards
    /// either kind of light crosses it (sampled densely, and bisected onto the edges of the
    /// exact test), and lies within its bounding sphere's range, narrower in most cases (so
    /// the test can fail and the cull gains).
    #[test]
    fn the_ellipsoid_reach_range_holds_every_shadow_ray_that_crosses_it() {
        let mut rng = SplitMix64::new(23);
        let mut v = |s: f64| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * s - DVec3::splat(s)
        };
        let (mut narrower, mut finite, mut crossing) = (0, 0, 0);
        for trial in 0..400 {
            let w = v(1.0);
            let axes = DVec3::new(1.0, 0.1 + w.x.abs(), 0.1 + w.y.abs()) * (0.3 + w.z.abs());
            let q = glam::DQuat::from_xyzw(v(1.0).x, v(1.0).y, v(1.0).z, 0.5).normalize();
            let (e, c) = (Ellipsoid::new(axes, q), v(3.0));
            let light = if trial % 2 == 0 {
                Light::Directional {
                    direction: v(1.0).normalize(),
                    irradiance: DVec3::ONE,
                }
            } else {
                Light::Point {
                    position: v(4.0),
                    intensity: DVec3::ONE,
                    falloff: Falloff::InverseSquare,
                }
            };
            // Aimed near the centre, so that most bounding spheres' ranges are finite.
            let origin = v(6.0);
            let ray = Ray::new(origin, (c + v(1.0) - origin).normalize());
            let (lo, hi) = ellipsoid_reach_range(&ray, &light, c, &e, 20.0);
            let (b_lo, b_hi) = reach_range(&ray, &light, c, e.bounding_radius(), 20.0);
            if lo <= hi {
                // Within the sphere's, up to the larger padding of the ellipsoid's.
                let inside = lo >= b_lo - 1e-3 && hi <= b_hi + 1e-3;
                assert!(
                    inside,
                    "trial {trial}: [{lo}, {hi}] not in [{b_lo}, {b_hi}]"
                );
            }
            if b_lo.is_finite() && b_hi.is_finite() && b_lo <= b_hi {
                finite += 1;
                narrower += usize::from(lo > b_lo || hi < b_hi);
            }
            let crosses = |t: f64| {
                let Some(inc) = light.incident_at(ray.at(t)) else {
                    return false;
                };
                let shadow = Ray {
                    origin: ray.at(t),
                    direction: inc.toward,
                };
                e.intersect(&shadow, c)
                    .is_some_and(|h| h.t_exit > 0.0 && h.t_enter < inc.distance)
            };
            let mut check = |t: f64| {
                if crosses(t) {
                    crossing += 1;
                    assert!(
                        t >= lo && t <= hi,
                        "trial {trial}: t {t} outside [{lo}, {hi}]"
                    );
                }
            };
            let ts: Vec<f64> = (0..800).map(|j| -20.0 + 0.05 * j as f64).collect();
            for pair in ts.windows(2) {
                check(pair[0]);
                let (a, b) = (crosses(pair[0]), crosses(pair[1]));
                if a != b {
                    let (mut x0, mut x1) = (pair[0], pair[1]);
                    for _ in 0..60 {
                        let m = 0.5 * (x0 + x1);
                        if crosses(m) == a {
                            x0 = m;
                        } else {
                            x1 = m;
                        }
                    }
                    check(x0);
                    check(x1);
                }
            }
        }
        assert!(
            finite > 100 && narrower * 2 > finite,
            "the range should mostly be narrower: {narrower} of {finite}"
        );
        assert!(crossing > 5000, "the samples should cross: {crossing}");
    }

    /// The list-based hits equal the BVH's for random shadow rays from random camera segments,
    /// for both kinds of light (the property the bit-identical images rest on), one ray at a
    /// time and in batches.
    #[test]
    fn list_hits_equal_bvh_hits() {
        lists_equal_the_bvh(false);
    }

    /// The same with every third particle an ellipsoid (axis ratios up to 1:10, turned).
    #[test]
    fn list_hits_equal_bvh_hits_among_ellipsoids() {
        lists_equal_the_bvh(true);
    }

    fn lists_equal_the_bvh(ellipsoids: bool) {
        let mut rng = SplitMix64::new(7);
        let mut v = |s: f64| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 * s - DVec3::splat(s)
        };
        let particles: Vec<Particle> = (0..400)
            .map(|i| {
                let mut p = Particle {
                    ellipsoid: None,
                    profile: crate::optics::Profile::Constant,
                    center: v(6.0),
                    radius: 0.3 + 0.5 * v(1.0).x.abs(),
                    color: DVec3::ONE,
                    sigma: 0.5,
                    albedo: DVec3::ONE,
                    ks: 0.0,
                    shininess: 0.0,
                };
                if ellipsoids && i % 3 == 0 {
                    let w = v(1.0);
                    let axes = p.radius * DVec3::new(1.0, 0.1 + w.x.abs(), 0.1 + w.y.abs());
                    let q = glam::DQuat::from_xyzw(w.z, v(1.0).x, v(1.0).y, 0.5).normalize();
                    let e = Ellipsoid::new(axes * 1.5, q);
                    p.radius = e.bounding_radius();
                    p.ellipsoid = Some(e);
                }
                p
            })
            .collect();
        let bvh = Bvh::build_shapes(
            particles.iter().map(|p| p.center).collect(),
            particles.iter().map(|p| p.radius).collect(),
            particles.iter().map(|p| p.ellipsoid).collect(),
            |_| true,
        );
        let lights = [
            Light::Directional {
                direction: DVec3::new(0.2, -1.0, 0.1).normalize(),
                irradiance: DVec3::ONE,
            },
            Light::Point {
                position: DVec3::new(1.0, 2.0, -0.5),
                intensity: DVec3::ONE,
                falloff: Falloff::InverseSquare,
            },
        ];
        let mut occ = Occluders::default();
        let (mut wide, mut narrowed) = (Occluders::default(), Occluders::default());
        let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
        let (mut compared, mut grazing, mut narrowed_compared) = (0, 0, [0, 0]);
        let bits = |ts: &[f64]| ts.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        let (mut tangencies_compared, mut ragged_batches) = (0, 0);
        let (mut on_lines, mut max_deviation) = (0, 0.0f64);
        for trial in 0..200 {
            let ray = Ray::new(v(8.0) - DVec3::Z * 10.0, (v(0.3) + DVec3::Z).normalize());
            let (ta, tb) = (5.0 + v(3.0).x, 12.0 + v(3.0).x);
            for (l, light) in lights.iter().enumerate() {
                occ.gather(&bvh, &ray, (trial, l), light, (ta, tb));
                // The list narrowed from one gathered for a longer stretch of the same ray.
                let stretch = (ta - 2.0 + v(1.0).x, tb + 2.0 + v(1.0).x);
                wide.gather(&bvh, &ray, (usize::MAX, l), light, stretch);
                narrowed.narrow(&wide, &ray, (trial, l), light, (ta, tb));
                assert!(narrowed.len() <= wide.len());
                // Evenly spaced nodes, and nodes on and a few ulps around every kink (where a
                // shadow ray grazes a sphere: the ends of the candidates' reach ranges).
                let mut ts: Vec<f64> = (0..=20)
                    .map(|j| (ta + (tb - ta) * j as f64 / 20.0).min(tb))
                    .collect();
                let mut kinks = Vec::new();
                shadow_tangencies(&ray, (ta, tb), light, &bvh, &particles, &mut kinks);
                // The lists give the kinks that the BVH query gives, bit for bit: for their
                // own stretch, and the wide one for its longer stretch.
                let mut listed = Vec::new();
                occ.tangencies(&ray, (ta, tb), light, &mut listed);
                assert_eq!(bits(&listed), bits(&kinks), "trial {trial}, light {l}");
                let (mut over_stretch, mut queried) = (Vec::new(), Vec::new());
                wide.tangencies(&ray, stretch, light, &mut over_stretch);
                shadow_tangencies(&ray, stretch, light, &bvh, &particles, &mut queried);
                assert_eq!(
                    bits(&over_stretch),
                    bits(&queried),
                    "trial {trial}, light {l}"
                );
                tangencies_compared += kinks.len() + queried.len();
                for k in kinks {
                    for ulps in -3i64..=3 {
                        ts.push(f64::from_bits((k.to_bits() as i64 + ulps) as u64));
                    }
                }
                // All of them as one batch too (more than one pass of lanes, and a last pass
                // with fewer rays than lanes).
                let shadow: Vec<ShadowRay> = ts
                    .iter()
                    .filter_map(|&t| {
                        let x = ray.at(t);
                        let inc = light.incident_at(x)?;
                        let ray = Ray {
                            origin: x,
                            direction: inc.toward,
                        };
                        Some(ShadowRay {
                            t,
                            ray,
                            t_max: inc.distance,
                        })
                    })
                    .collect();
                // Stale hits, which the batch must clear.
                let stale = Hit {
                    index: 0,
                    chord: Chord {
                        t_enter: 0.0,
                        t_exit: 1.0,
                    },
                };
                let mut batch = vec![vec![stale; 3]; shadow.len()];
                occ.hits_batch(&shadow, &mut batch);
                ragged_batches +=
                    usize::from(shadow.len() > 2 * LANES && shadow.len() % LANES != 0);
                let mut batched = batch.iter();
                for (j, t) in ts.into_iter().enumerate() {
                    assert!(occ.covers(trial, l, t));
                    let x = ray.at(t);
                    let Some(inc) = light.incident_at(x) else {
                        continue;
                    };
                    let sray = Ray {
                        origin: x,
                        direction: inc.toward,
                    };
                    bvh.all_hits(&sray, 0.0, inc.distance, &mut a);
                    occ.hits(t, &sray, inc.distance, &mut b);
                    // Each ray of the batch got its own hits, in the same order.
                    assert_eq!(
                        batched.next(),
                        Some(&b),
                        "batch: trial {trial} light {l} t {t}"
                    );
                    b.sort_unstable_by(|a, b| {
                        a.chord
                            .t_enter
                            .total_cmp(&b.chord.t_enter)
                            .then(a.index.cmp(&b.index))
                    });
                    // Spheres, and ellipsoids towards the point light (the exact test), bit
                    // for bit; ellipsoids towards the directional light (the closed form of
                    // `ShadowLine`) within round-off.
                    let is_ellipsoid = |h: &&Hit| particles[h.index as usize].ellipsoid.is_some();
                    let on_line = |h: &&Hit| l == 0 && is_ellipsoid(h);
                    let exact = |hits: &[Hit]| -> Vec<Hit> {
                        hits.iter().filter(|h| !on_line(h)).copied().collect()
                    };
                    assert_eq!(exact(&a), exact(&b), "trial {trial} light {l} t {t}");
                    let lined = |hits: &[Hit]| -> Vec<Hit> {
                        hits.iter().filter(on_line).copied().collect()
                    };
                    let (n, dev) = hits_agree(&lined(&a), &lined(&b), inc.distance);
                    (on_lines, max_deviation) = (on_lines + n, max_deviation.max(dev));
                    assert!(narrowed.covers(trial, l, t));
                    let mut unsorted = Vec::new();
                    narrowed.hits(t, &sray, inc.distance, &mut unsorted);
                    occ.hits(t, &sray, inc.distance, &mut c);
                    // The same hits in the same order as the list's own gather.
                    assert_eq!(unsorted, c, "narrowed: trial {trial} light {l} t {t}");
                    narrowed_compared[l] += unsorted.len();
                    compared += a.len();
                    grazing += usize::from(j >= 21);
                }
                assert!(occ.len() < particles.len() / 2, "the list should be short");
            }
        }
        assert!(compared > 1000, "the rays should hit something: {compared}");
        assert!(
            ragged_batches > 100,
            "batches of several passes: {ragged_batches}"
        );
        assert!(grazing > 100, "the kinks should be tested: {grazing}");
        assert!(
            tangencies_compared > 200,
            "kinks compared: {tangencies_compared}"
        );
        assert!(
            narrowed_compared.iter().all(|&n| n > 500),
            "narrowed lists: {narrowed_compared:?}"
        );
        assert!(
            !ellipsoids || on_lines > 300,
            "ellipsoid hits in closed form: {on_lines}"
        );
        assert!(max_deviation < 1e-12, "chords' deviation {max_deviation:e}");
    }

    /// Whether two hit lists of one shadow ray (`exact`, from the ellipsoid's intersection, and
    /// `closed`, from a [`ShadowLine`]) agree within round-off: the same particles, each chord's
    /// midpoint and squared half-length the same up to round-off of the coordinates' size
    /// (about 10 here) and its square, except hits found by one alone whose overlap with
    /// (0, t_max) is a graze (below 1e-6). The number of hits matched and the largest of those
    /// deviations, relative to the size and its square.
    fn hits_agree(exact: &[Hit], closed: &[Hit], t_max: f64) -> (usize, f64) {
        const SIZE: f64 = 10.0;
        let graze = |h: &Hit| h.chord.t_exit.min(t_max) - h.chord.t_enter.max(0.0) < 1e-6;
        let (mut matched, mut deviation) = (0, 0.0f64);
        for h in exact {
            match closed.iter().find(|g| g.index == h.index) {
                Some(g) => {
                    matched += 1;
                    let mid = |h: &Hit| 0.5 * (h.chord.t_enter + h.chord.t_exit);
                    let half = |h: &Hit| 0.5 * (h.chord.t_exit - h.chord.t_enter);
                    // The squared half-chords: near a graze the half-chord is the square root
                    // of a difference that round-off enters directly.
                    let dev = ((mid(g) - mid(h)).abs() / SIZE)
                        .max((half(g).powi(2) - half(h).powi(2)).abs() / (SIZE * SIZE));
                    deviation = deviation.max(dev);
                }
                None => assert!(graze(h), "only the exact test hits {h:?}"),
            }
        }
        for g in closed {
            if !exact.iter().any(|h| h.index == g.index) {
                assert!(graze(g), "only the closed form hits {g:?}");
            }
        }
        (matched, deviation)
    }
}
