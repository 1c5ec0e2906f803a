//! The shadow rays toward a directional light from the points of a camera ray through Gaussian
//! gas (docs/design.md §9 "Models and modes with Gaussians"): one candidate list per piece of
//! the ray instead of a BVH traversal per shadow ray.
//!
//! The shadow rays from the points x(t) = o + t·d, t ∈ [t₀, t₁], of a camera ray toward a
//! directional light are parallel (unit direction u) and sweep the half-strip
//! {x(t) + r·u : t ∈ [t₀, t₁], r ≥ 0}. In a Gaussian's unit coordinates (M = S⁻¹Rᵀ, standard
//! deviations as semi-axes, its k-σ ellipsoid the ball of radius k) the shadow ray from x(t) is
//! u₀(t) + r·v with u₀(t) = M(x(t) − c) linear in t and v = M·u; with v̂ = v/|v| and s = 1/|v|,
//!
//! * along(t) = u₀(t)·v̂ and across(t) = u₀(t) − along(t)·v̂, both linear in t (kept as their
//!   value at a reference t and their slope);
//! * the ray meets the k-ball over r > 0 iff m² = |across|² < k² and (along < 0 or
//!   along² + m² = |u₀|² < k², the origin inside);
//! * its depth over [0, ∞) is σ·e^{−m²/2}·s·√(π/2)·erfc(along/√2) (the profile's t* is
//!   −along·s, `optics::gaussian`).
//!
//! So the t where a shadow ray can meet a Gaussian's k-σ ellipsoid form one interval, the hull
//! of {m² ≤ k², along ≤ 0} ∪ {|u₀|² ≤ k²} (m² and |u₀|² are quadratics in t, along a line).
//! [`SunLists::gather`] traverses the BVH once per camera ray and light, keeping the boxes the
//! half-strip meets (an exact test: the r ≥ 0 that put x(t) + r·u in the box along each axis are
//! an interval whose ends are linear in t, so the t with a common r are one interval, cut by
//! linear inequalities), takes each Gaussian's interval, and gives each piece [a, b] of the ray
//! the Gaussians whose interval overlaps it. Each shadow ray from the piece
//! ([`SunLists::transmittance`]) takes the exact test above for each of them, with a margin
//! that keeps a Gaussian on the k-σ surface rather than drop it, and sums the depths of those it
//! keeps: no shadow ray leaves out a Gaussian whose k-σ ellipsoid it meets, which err's missed
//! depth Δ_far assumes, and one kept beyond k σ only adds true depth. The boxes, intervals and
//! constraints are widened by a relative margin against round-off.

use crate::geometry::{Bvh, Ray};
use glam::{DMat3, DVec3};

/// √(π/2).
const SQRT_HALF_PI: f64 = 1.253_314_137_315_500_3;

/// The relative margin on k² by which a Gaussian is kept rather than dropped: far above the
/// round-off of m², far below what would keep a Gaussian the ray misses by a visible amount.
const KEEP_MARGIN: f64 = 1e-9;

/// The relative widening of the boxes, the intervals and the box test's constraints against
/// round-off.
const PAD: f64 = 1e-9;

/// Below this, erfc(z) = 1 + erf(−z) rounds to 2 (erfc(6) < 2.2e-17, a tenth of 2's ulp).
const ERFC_IS_TWO: f64 = -6.0;

/// What the renderer tells of one Gaussian: its centre, M = S⁻¹Rᵀ of its standard deviations,
/// and its peak density σᵢ.
#[derive(Debug, Clone, Copy)]
pub struct SunGaussian {
    pub center: DVec3,
    pub to_unit: DMat3,
    pub sigma: f64,
}

/// One Gaussian met by some shadow ray of a camera ray, in its unit coordinates about
/// `t_ref`: across(t) = across + (t − t_ref)·across_slope, along(t) likewise; σᵢ·s·√(π/2);
/// and the interval [lo, hi] of t outside which no shadow ray meets its k-σ ellipsoid.
#[derive(Debug, Clone, Copy)]
struct Entry {
    across: DVec3,
    across_slope: DVec3,
    along: f64,
    along_slope: f64,
    t_ref: f64,
    factor: f64,
    lo: f64,
    hi: f64,
    index: u32,
}

/// The candidate lists of one camera ray's pieces, one per piece and directional light.
#[derive(Debug, Default)]
pub struct SunLists {
    /// The Gaussians of the ray, light by light, each light's sorted by `lo`.
    entries: Vec<Entry>,
    /// Per piece and light (`piece * suns + light`): its range in `members`.
    lists: Vec<(usize, usize)>,
    /// Indices into `entries`, piece by piece.
    members: Vec<u32>,
    suns: usize,
    /// k² with the keep margin.
    keep: f64,
    pieces: Vec<(f64, f64)>,
    stack: Vec<u32>,
    open: Vec<u32>,
}

impl SunLists {
    /// Gathers the list of every piece `[a, b]` of `ray` (`pieces`, sorted and not
    /// overlapping) for every light direction `toward` (unit, toward the light), over the
    /// Gaussians of `bvh` (whose leaves hold k-σ ellipsoids, `cutoff` = k) that `gaussian`
    /// describes by index.
    pub fn gather(
        &mut self,
        bvh: &Bvh,
        gaussian: impl Fn(u32) -> SunGaussian,
        cutoff: f64,
        ray: &Ray,
        pieces: impl Iterator<Item = (f64, f64)>,
        toward: &[DVec3],
    ) {
        self.entries.clear();
        self.members.clear();
        self.pieces.clear();
        self.pieces.extend(pieces);
        self.lists.clear();
        self.lists.resize(self.pieces.len() * toward.len(), (0, 0));
        self.suns = toward.len();
        self.keep = cutoff * cutoff * (1.0 + KEEP_MARGIN);
        let (Some(&(start, _)), Some(&(_, end))) = (self.pieces.first(), self.pieces.last()) else {
            return;
        };
        for (sun, &u) in toward.iter().enumerate() {
            let first = self.entries.len();
            self.gather_span(bvh, &gaussian, ray, (start, end), u);
            let entries = &mut self.entries[first..];
            entries.sort_unstable_by(|a, b| a.lo.total_cmp(&b.lo).then(a.index.cmp(&b.index)));
            self.share_out(first, sun);
        }
    }

    /// Appends the entries of the Gaussians some shadow ray toward `u` from `ray` over
    /// `span` may meet.
    fn gather_span(
        &mut self,
        bvh: &Bvh,
        gaussian: &impl Fn(u32) -> SunGaussian,
        ray: &Ray,
        span: (f64, f64),
        u: DVec3,
    ) {
        self.stack.clear();
        self.stack.push(0);
        while let Some(n) = self.stack.pop() {
            let node = &bvh.nodes[n as usize];
            if !strip_meets_box(ray, u, span, (node.min, node.max)) {
                continue;
            }
            if node.count == 0 {
                self.stack.push(node.first);
                self.stack.push(node.first + 1);
                continue;
            }
            for &index in bvh.leaf(node).indices {
                if let Some(entry) = self.entry(index, &gaussian(index), ray, span, u) {
                    self.entries.push(entry);
                }
            }
        }
    }

    /// Gives each piece (`self.pieces`, in order) the entries from `first` on (sorted by `lo`)
    /// whose interval overlaps it, as light `sun`'s list.
    fn share_out(&mut self, first: usize, sun: usize) {
        self.open.clear();
        let mut next = first;
        for (p, &(a, b)) in self.pieces.iter().enumerate() {
            while next < self.entries.len() && self.entries[next].lo <= b {
                self.open.push(next as u32);
                next += 1;
            }
            let entries = &self.entries;
            self.open.retain(|&k| entries[k as usize].hi >= a);
            let start = self.members.len();
            self.members.extend_from_slice(&self.open);
            self.lists[p * self.suns + sun] = (start, self.members.len());
        }
    }

    /// Gaussian `index` (`g`) as an entry of `ray` over `span` toward `u`, or `None` where no
    /// shadow ray from the span can meet its k-σ ellipsoid.
    fn entry(
        &self,
        index: u32,
        g: &SunGaussian,
        ray: &Ray,
        (start, end): (f64, f64),
        u: DVec3,
    ) -> Option<Entry> {
        let v = g.to_unit * u;
        let length = v.length();
        let v_hat = v / length;
        let mid = 0.5 * (start + end);
        let slope = g.to_unit * ray.direction;
        let origin = g.to_unit * (ray.at(mid) - g.center);
        let (along, along_slope) = (origin.dot(v_hat), slope.dot(v_hat));
        let across = origin - along * v_hat;
        let across_slope = slope - along_slope * v_hat;
        // The t of the span (about mid) where m² ≤ k² and the ellipsoid lies ahead, or the
        // origin is inside it.
        let (near, far) = within(across, across_slope, self.keep)?;
        let (mut lo, mut hi) = match along_slope {
            b if b > 0.0 => (near, far.min(-along / b)),
            b if b < 0.0 => (near.max(-along / b), far),
            _ if along <= 0.0 => (near, far),
            _ => (f64::INFINITY, f64::NEG_INFINITY),
        };
        if lo > hi {
            (lo, hi) = (f64::INFINITY, f64::NEG_INFINITY);
        }
        if let Some((a, b)) = within(origin, slope, self.keep) {
            (lo, hi) = (lo.min(a), hi.max(b));
        }
        let half = 0.5 * (end - start);
        let pad = PAD * (half + mid.abs());
        let (lo, hi) = ((lo - pad).max(-half - pad), (hi + pad).min(half + pad));
        if lo > hi {
            return None;
        }
        let shift = 0.5 * (lo + hi);
        let (along, across) = (along + shift * along_slope, across + shift * across_slope);
        Some(Entry {
            across,
            across_slope,
            along,
            along_slope,
            t_ref: mid + shift,
            factor: g.sigma * SQRT_HALF_PI / length,
            lo: mid + lo,
            hi: mid + hi,
            index,
        })
    }

    /// T_l of the shadow ray from the point `t` of piece `piece` toward directional light
    /// `sun` (its index among the directional lights): e^{−D} with D the sum of the depths over
    /// [0, ∞) of the list's Gaussians whose k-σ ellipsoid the ray meets, in the list's order;
    /// stopped once D reaches `stop_depth` (then true).
    pub fn transmittance(&self, piece: usize, sun: usize, t: f64, stop_depth: f64) -> (f64, bool) {
        let (first, end) = self.lists[piece * self.suns + sun];
        let mut depth = 0.0;
        for &k in &self.members[first..end] {
            let e = &self.entries[k as usize];
            let dt = t - e.t_ref;
            let across = e.across + dt * e.across_slope;
            let m2 = across.length_squared();
            if m2 >= self.keep {
                continue;
            }
            let along = e.along + dt * e.along_slope;
            if along > 0.0 && along * along + m2 >= self.keep {
                continue;
            }
            depth += e.factor * (-0.5 * m2).exp() * erfc(along * std::f64::consts::FRAC_1_SQRT_2);
            if depth >= stop_depth {
                return ((-depth).exp(), true);
            }
        }
        ((-depth).exp(), false)
    }
}

/// erfc(z), by the cases of `optics::gaussian::erf_difference` for [z, ∞): erfc(z) for z ≥ 0,
/// 1 + erf(−z) below (2 exactly where that rounds to 2).
#[inline]
fn erfc(z: f64) -> f64 {
    if z >= 0.0 {
        libm::erfc(z)
    } else if z > ERFC_IS_TWO {
        1.0 + libm::erf(-z)
    } else {
        2.0
    }
}

/// The τ with |p + τ·q|² ≤ `bound`, an interval (−∞..∞ where q = 0 and |p|² ≤ bound), or
/// `None`; computed from the nearest point, without cancellation.
fn within(p: DVec3, q: DVec3, bound: f64) -> Option<(f64, f64)> {
    let qq = q.length_squared();
    if qq == 0.0 {
        return (p.length_squared() <= bound).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let nearest = -p.dot(q) / qq;
    let least = (p + nearest * q).length_squared();
    if least > bound {
        return None;
    }
    let half = ((bound - least) / qq).sqrt();
    Some((nearest - half, nearest + half))
}

/// Whether some shadow ray from `ray`'s points over `span` along `u` meets the box
/// `(min, max)`: whether there are t in the span and r ≥ 0 with min ≤ o + t·d + r·u ≤ max.
/// Along an axis with uᵢ ≠ 0 the r that fit are [lᵢ(t), hᵢ(t)], both linear in t; with uᵢ = 0
/// the axis bounds t itself. A common r exists where every lower bound (and 0) is at most every
/// upper one: linear inequalities in t, each cutting the span. The box is widened first, each
/// inequality by its round-off's bound, so that the test never drops a box the strip meets. An
/// empty box (min > max) is missed.
fn strip_meets_box(
    ray: &Ray,
    u: DVec3,
    (start, end): (f64, f64),
    (min, max): (DVec3, DVec3),
) -> bool {
    if !min.cmple(max).all() {
        return false;
    }
    let (o, d) = (ray.origin, ray.direction);
    let scale = (max - min).max_element() + min.abs().max(max.abs()).max_element();
    let pad = DVec3::splat(PAD * (scale + o.abs().max_element()));
    let (min, max) = (min - pad, max + pad);
    let (mut lo, mut hi) = (start, end);
    let reach = start.abs().max(end.abs());
    // The lower and upper bounds of r, each A + B·t; r ≥ 0 is the first lower one.
    let mut lower = [(0.0, 0.0); 4];
    let mut upper = [(0.0, 0.0); 3];
    let (mut lows, mut ups) = (1, 0);
    for i in 0..3 {
        if u[i] == 0.0 {
            // min ≤ oᵢ + t·dᵢ ≤ max: two inequalities in t alone.
            for (a, b) in [(min[i] - o[i], -d[i]), (o[i] - max[i], d[i])] {
                // a + b·t ≤ 0.
                cut(
                    &mut lo,
                    &mut hi,
                    b,
                    -a,
                    PAD * (a.abs() + (min[i].abs() + max[i].abs()) + b.abs() * reach),
                );
            }
            continue;
        }
        let (near, far) = if u[i] > 0.0 {
            (min[i], max[i])
        } else {
            (max[i], min[i])
        };
        lower[lows] = ((near - o[i]) / u[i], -d[i] / u[i]);
        upper[ups] = ((far - o[i]) / u[i], -d[i] / u[i]);
        lows += 1;
        ups += 1;
    }
    for &(la, lb) in &lower[..lows] {
        for &(ua, ub) in &upper[..ups] {
            // la + lb·t ≤ ua + ub·t.
            let slack = PAD * (la.abs() + ua.abs() + (lb.abs() + ub.abs()) * reach);
            cut(&mut lo, &mut hi, lb - ub, ua - la, slack);
        }
    }
    lo <= hi
}

/// Narrows [lo, hi] to the t with c·t ≤ e + slack.
#[inline]
fn cut(lo: &mut f64, hi: &mut f64, c: f64, e: f64, slack: f64) {
    let e = e + slack;
    if c > 0.0 {
        *hi = hi.min(e / c);
    } else if c < 0.0 {
        *lo = lo.max(e / c);
    } else if e < 0.0 {
        *hi = f64::NEG_INFINITY;
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::random::SplitMix64;
    use crate::geometry::Ellipsoid;
    use crate::optics::gaussian::GaussianAlongRay;
    use glam::DQuat;

    struct Cloud {
        centers: Vec<DVec3>,
        shapes: Vec<Ellipsoid>,
        sigmas: Vec<f64>,
        bvh: Bvh,
    }

    /// Gaussians round, long and flat (one axis 10⁻⁴ of the others), turned at random, and the
    /// BVH of their k-σ ellipsoids as the renderer builds it.
    fn cloud(rng: &mut SplitMix64, n: usize, k: f64) -> Cloud {
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        let (mut centers, mut shapes, mut sigmas) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            let mut std = DVec3::new(r(0.05, 0.8), r(0.05, 0.8), r(0.05, 0.8));
            if i % 3 == 0 {
                std.z = 1e-4 * std.x;
            }
            let axis = DVec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)).normalize();
            shapes.push(Ellipsoid::new(
                std,
                DQuat::from_axis_angle(axis, r(0.0, 3.0)),
            ));
            centers.push(DVec3::new(r(-3.0, 3.0), r(-3.0, 3.0), r(-3.0, 3.0)));
            sigmas.push(r(0.5, 3.0));
        }
        let bvh = Bvh::build_shapes(
            centers.clone(),
            shapes.iter().map(|e| k * e.bounding_radius()).collect(),
            shapes
                .iter()
                .map(|e| Some(Ellipsoid::new(k * e.semi_axes(), e.rotation())))
                .collect(),
            |_| true,
        );
        Cloud {
            centers,
            shapes,
            sigmas,
            bvh,
        }
    }

    /// The depth over [0, ∞) of every Gaussian whose k-σ ellipsoid the ray meets there, each
    /// found by intersecting its ellipsoid, not through a list or the BVH.
    fn brute_force_depth(c: &Cloud, shadow: &Ray, k: f64) -> f64 {
        let mut depth = 0.0;
        for i in 0..c.centers.len() {
            let e = Ellipsoid::new(k * c.shapes[i].semi_axes(), c.shapes[i].rotation());
            if e.intersect(shadow, c.centers[i])
                .is_some_and(|ch| ch.t_exit > 0.0)
            {
                depth += GaussianAlongRay::new(shadow, c.centers[i], &c.shapes[i], c.sigmas[i])
                    .optical_depth(0.0, f64::INFINITY);
            }
        }
        depth
    }

    #[test]
    fn every_shadow_ray_of_a_piece_sums_every_gaussian_it_meets() {
        let mut rng = SplitMix64::new(47);
        let k = 2.5;
        let c = cloud(&mut rng, 300, k);
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        let mut lists = SunLists::default();
        let (mut met, mut compared) = (0, 0);
        for _ in 0..40 {
            let origin = DVec3::new(r(-6.0, 6.0), r(-6.0, 6.0), -9.0);
            let ray = Ray::new(origin, DVec3::new(r(-0.4, 0.4), r(-0.4, 0.4), 1.0));
            let toward = [
                DVec3::new(r(-1.0, 1.0), 1.0, r(-1.0, 1.0)).normalize(),
                DVec3::new(r(-1.0, 1.0), r(-1.0, 1.0), -1.0).normalize(),
            ];
            let mut pieces = Vec::new();
            let mut t = r(3.0, 6.0);
            while t < 15.0 {
                let length = if pieces.len() % 2 == 0 {
                    r(0.001, 0.1)
                } else {
                    r(0.1, 3.0)
                };
                pieces.push((t, t + length));
                t += length + r(0.0, 0.5);
            }
            let gaussian = |i: u32| SunGaussian {
                center: c.centers[i as usize],
                to_unit: c.shapes[i as usize].to_unit_matrix(),
                sigma: c.sigmas[i as usize],
            };
            lists.gather(&c.bvh, gaussian, k, &ray, pieces.iter().copied(), &toward);
            for (p, &(a, b)) in pieces.iter().enumerate() {
                for j in 0..=12 {
                    let t = a + (b - a) * j as f64 / 12.0;
                    for (sun, &u) in toward.iter().enumerate() {
                        let shadow = Ray {
                            origin: ray.at(t),
                            direction: u,
                        };
                        let want = brute_force_depth(&c, &shadow, k);
                        let (got, stopped) = lists.transmittance(p, sun, t, f64::INFINITY);
                        assert!(!stopped);
                        let depth = -got.ln();
                        assert!(
                            (depth - want).abs() <= 1e-9 * want + 1e-12,
                            "piece {p} [{a}, {b}] at {t}, sun {sun}: depth {depth} from the list, {want} from every Gaussian"
                        );
                        met += usize::from(want > 0.0);
                        compared += 1;
                    }
                }
            }
        }
        // Many shadow rays cross the gas and meet some Gaussian.
        assert!(
            met * 4 > compared,
            "{met} of {compared} shadow rays met a Gaussian"
        );
    }

    #[test]
    fn a_shadow_ray_stops_once_its_depth_reaches_the_stop() {
        let mut rng = SplitMix64::new(3);
        let k = 3.0;
        let c = cloud(&mut rng, 200, k);
        let gaussian = |i: u32| SunGaussian {
            center: c.centers[i as usize],
            to_unit: c.shapes[i as usize].to_unit_matrix(),
            sigma: c.sigmas[i as usize],
        };
        let ray = Ray::new(DVec3::new(0.1, -0.2, -9.0), DVec3::Z);
        let mut lists = SunLists::default();
        lists.gather(
            &c.bvh,
            gaussian,
            k,
            &ray,
            [(8.5, 9.5)].into_iter(),
            &[DVec3::Y],
        );
        let (whole, stopped) = lists.transmittance(0, 0, 9.0, f64::INFINITY);
        let depth = -whole.ln();
        assert!(!stopped && depth > 1.0, "{depth}");
        let (t, stopped) = lists.transmittance(0, 0, 9.0, 0.5 * depth);
        assert!(
            stopped && -t.ln() >= 0.5 * depth && t >= whole,
            "{t} against {whole}"
        );
    }
}
