//! A bounding volume hierarchy over spheres and ellipsoids, built with binned SAH
//! (docs/design.md §3, §9).
//!
//! Nodes live in one flat `Vec` (the GPU side flattens the same array into a storage buffer);
//! memory is O(n): at most 2n − 1 nodes of 56 bytes and one u32 index per sphere.
//! Two queries: every sphere a ray crosses, sorted by entry (the volume renderer cuts rays into
//! intervals with them) and whether any sphere blocks a segment (shadow rays).

use super::{intersect_sphere, Chord, Ellipsoid, Ray, Shape};
use glam::DVec3;
use rayon::prelude::*;

/// Spheres per leaf at most (fewer when the SAH says a split does not pay).
const MAX_LEAF: usize = 4;
/// Centroid bins per axis for the SAH sweep.
const BINS: usize = 16;
/// Relative cost of one ray–box test against one ray–sphere test.
const TRAVERSAL_COST: f64 = 1.0;

/// One node. `count > 0`: a leaf holding `indices[first .. first + count]`; `count == 0`: an
/// inner node whose children are `first` and `first + 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhNode {
    pub min: DVec3,
    pub max: DVec3,
    pub first: u32,
    pub count: u32,
}

/// A sphere crossed by a ray: its index in the input order and the chord's ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub index: u32,
    pub chord: Chord,
}

/// The hierarchy over a fixed set of spheres (centres, radii, in the caller's order).
#[derive(Debug, Clone)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Sphere indices in leaf order.
    pub indices: Vec<u32>,
    /// Centres and radii in leaf order (`centers[k]` is sphere `indices[k]`'s): a leaf's
    /// spheres lie together in memory (in the caller's order, each would be a cache miss in a
    /// large scene).
    centers: Vec<DVec3>,
    radii: Vec<f64>,
    /// In leaf order, the ellipsoid about each centre (`None`: the sphere of its radius, which
    /// for an ellipsoid is its bounding radius); empty where every particle is a sphere, so
    /// that sphere scenes take the sphere-only loop.
    ellipsoids: Vec<Option<Ellipsoid>>,
}

/// The spheres of one BVH leaf: their indices in the caller's order, centres and radii.
#[derive(Debug, Clone, Copy)]
pub struct Leaf<'a> {
    pub indices: &'a [u32],
    pub centers: &'a [DVec3],
    /// Radii of the spheres, bounding radii of the ellipsoids.
    pub radii: &'a [f64],
    /// The ellipsoids by leaf position; empty where the tree holds spheres only.
    pub ellipsoids: &'a [Option<Ellipsoid>],
}

impl<'a> Leaf<'a> {
    /// (index, centre, radius) of each sphere.
    pub fn spheres(&self) -> impl Iterator<Item = (u32, DVec3, f64)> + 'a {
        let (indices, centers, radii) = (self.indices, self.centers, self.radii);
        indices
            .iter()
            .zip(centers)
            .zip(radii)
            .map(|((&i, &c), &r)| (i, c, r))
    }

    /// The ellipsoid of the leaf's `k`-th particle, `None` for a sphere.
    #[inline]
    pub fn ellipsoid(&self, k: usize) -> Option<&'a Ellipsoid> {
        self.ellipsoids.get(k).and_then(|e| e.as_ref())
    }

    /// (index, shape) of each particle.
    pub fn shapes(&self) -> impl Iterator<Item = (u32, Shape<'a>)> + '_ {
        self.spheres().enumerate().map(|(k, (i, center, radius))| {
            let shape = match self.ellipsoid(k) {
                None => Shape::Sphere { center, radius },
                Some(ellipsoid) => Shape::Ellipsoid { center, ellipsoid },
            };
            (i, shape)
        })
    }
}

#[derive(Clone, Copy)]
struct Aabb {
    min: DVec3,
    max: DVec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };
    fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }
    fn grow_point(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    fn half_area(&self) -> f64 {
        let e = self.max - self.min;
        if e.x < 0.0 {
            return 0.0;
        }
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// The box of a sphere, padded by a relative margin so that round-off in the slab test can never
/// cull a ray that grazes the sphere (the box only has to be conservative).
fn sphere_box(c: DVec3, r: f64) -> Aabb {
    let pad = r * (1.0 + 1e-9) + 1e-12 * c.abs().max_element();
    Aabb {
        min: c - DVec3::splat(pad),
        max: c + DVec3::splat(pad),
    }
}

/// The box about `c` of half extent `half` (an ellipsoid's tight box), padded as
/// [`sphere_box`] pads, relative to the largest extent.
fn padded_box(c: DVec3, half: DVec3) -> Aabb {
    let pad = half * (1.0 + 1e-9)
        + DVec3::splat(1e-9 * half.max_element() + 1e-12 * c.abs().max_element());
    Aabb {
        min: c - pad,
        max: c + pad,
    }
}

impl Bvh {
    /// Builds the hierarchy. Centres and radii must be finite (the scene validates them).
    ///
    /// Subtrees over more than `PARALLEL_MIN` (16k) spheres are built on rayon's pool, their two
    /// halves at once. The node layout is that of a sequential depth-first build (a node's
    /// children are allocated as a pair when it is split, the left subtree is finished before
    /// the right one starts), so the tree is the same for any number of threads.
    pub fn build(centers: Vec<DVec3>, radii: Vec<f64>) -> Bvh {
        Self::build_over(centers, radii, |_| true)
    }

    /// [`Bvh::build`] over the spheres i with `keep(i)` only; indices stay positions in
    /// `centers` and `radii`.
    pub fn build_over(centers: Vec<DVec3>, radii: Vec<f64>, keep: impl Fn(usize) -> bool) -> Bvh {
        Self::build_shapes(centers, radii, Vec::new(), keep)
    }

    /// [`Bvh::build_over`] where particle i is the ellipsoid `ellipsoids[i]` about `centers[i]`
    /// where that is `Some` (its radius then the bounding radius), a sphere where `None`.
    /// `ellipsoids` is empty or as long as `centers`; empty (or all `None`) is a sphere tree.
    pub fn build_shapes(
        centers: Vec<DVec3>,
        radii: Vec<f64>,
        ellipsoids: Vec<Option<Ellipsoid>>,
        keep: impl Fn(usize) -> bool,
    ) -> Bvh {
        assert_eq!(centers.len(), radii.len());
        assert!(ellipsoids.is_empty() || ellipsoids.len() == centers.len());
        let ellipsoids = if ellipsoids.iter().any(Option::is_some) {
            ellipsoids
        } else {
            Vec::new()
        };
        let n = centers.len();
        let boxes: Vec<Aabb> = centers
            .par_iter()
            .zip(&radii)
            .enumerate()
            .map(|(i, (&c, &r))| match ellipsoids.get(i) {
                Some(Some(e)) => padded_box(c, e.half_extent()),
                _ => sphere_box(c, r),
            })
            .collect();
        let mut indices: Vec<u32> = (0..n as u32).filter(|&i| keep(i as usize)).collect();
        let nodes = if indices.is_empty() {
            // An empty box that no ray enters.
            vec![BvhNode {
                min: DVec3::splat(f64::INFINITY),
                max: DVec3::splat(f64::NEG_INFINITY),
                first: 0,
                count: 0,
            }]
        } else {
            build_subtree(&mut indices, 0, &boxes, &centers)
        };
        let (centers, radii) = indices
            .iter()
            .map(|&i| (centers[i as usize], radii[i as usize]))
            .unzip();
        let ellipsoids = if ellipsoids.is_empty() {
            ellipsoids
        } else {
            indices.iter().map(|&i| ellipsoids[i as usize]).collect()
        };
        Bvh {
            nodes,
            indices,
            centers,
            radii,
            ellipsoids,
        }
    }

    /// The spheres of leaf `node` (whose `count` is > 0).
    pub fn leaf(&self, node: &BvhNode) -> Leaf<'_> {
        let range = node.first as usize..(node.first + node.count) as usize;
        Leaf {
            indices: &self.indices[range.clone()],
            centers: &self.centers[range.clone()],
            radii: &self.radii[range.clone()],
            ellipsoids: self.ellipsoids.get(range).unwrap_or(&[]),
        }
    }

    /// Number of spheres in the hierarchy.
    pub fn len(&self) -> usize {
        self.centers.len()
    }

    pub fn is_empty(&self) -> bool {
        self.centers.is_empty()
    }

    /// Every sphere whose chord overlaps (t_min, t_max), sorted by entry then index (a total
    /// order, so the result does not depend on the tree's shape). `out` is cleared first.
    pub fn all_hits(&self, ray: &Ray, t_min: f64, t_max: f64, out: &mut Vec<Hit>) {
        out.clear();
        self.traverse(ray, t_min, t_max, |index, chord, _| {
            out.push(Hit { index, chord });
            false
        });
        out.sort_unstable_by(|a, b| {
            a.chord
                .t_enter
                .total_cmp(&b.chord.t_enter)
                .then(a.index.cmp(&b.index))
        });
    }

    /// Whether any sphere's chord overlaps (t_min, t_max), ignoring spheres for which `skip`
    /// returns true.
    pub fn any_hit(&self, ray: &Ray, t_min: f64, t_max: f64, skip: impl Fn(u32) -> bool) -> bool {
        let mut found = false;
        self.traverse(ray, t_min, t_max, |index, _, _| {
            if skip(index) {
                false
            } else {
                found = true;
                true
            }
        });
        found
    }

    /// The nearest surface crossing with t in (t_min, t_max): the sphere, t, and whether the ray
    /// enters the sphere there (false: it leaves it, the origin being inside). Ties go to the
    /// lower index, so the answer does not depend on the tree's shape.
    pub fn first_hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(u32, f64, bool)> {
        let mut best: Option<(u32, f64, bool)> = None;
        self.traverse(ray, t_min, t_max, |index, chord, limit| {
            let (t, entering) = if chord.t_enter > t_min {
                (chord.t_enter, true)
            } else {
                (chord.t_exit, false)
            };
            if t < *limit || (t == *limit && best.is_some_and(|b| index < b.0)) {
                best = Some((index, t, entering));
                *limit = t;
            }
            false
        });
        best
    }

    /// Visits every sphere whose chord overlaps (t_min, t_max), nearer boxes first (not sorted:
    /// the tree's order, the same on every run), until `visit` returns true.
    pub fn visit_hits(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        mut visit: impl FnMut(u32, Chord) -> bool,
    ) {
        self.traverse(ray, t_min, t_max, |index, chord, _| visit(index, chord));
    }

    /// [`Bvh::visit_hits`], where `visit` may lower the far end `limit` (a front-to-back
    /// search that learns where it can stop): the boxes wholly beyond it are skipped from then on.
    pub fn visit_hits_narrowing(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        visit: impl FnMut(u32, Chord, &mut f64) -> bool,
    ) {
        self.traverse(ray, t_min, t_max, visit);
    }

    /// Visits every sphere whose chord overlaps (t_min, limit), nearer boxes first; `visit` may
    /// lower `limit` (nearest-hit search) and returns true to stop.
    fn traverse(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        mut visit: impl FnMut(u32, Chord, &mut f64) -> bool,
    ) {
        if self.centers.is_empty() {
            return;
        }
        let inv = ray.direction.recip();
        let mut limit = t_max;
        let root = &self.nodes[0];
        if slab_test(ray.origin, inv, root.min, root.max, t_min, limit).is_none() {
            return;
        }
        let mut stack = NodeStack::new();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let leaf = self.leaf(node);
                if leaf.ellipsoids.is_empty() {
                    for (i, center, radius) in leaf.spheres() {
                        if let Some(chord) = intersect_sphere(ray, center, radius) {
                            if chord.t_exit > t_min
                                && chord.t_enter < limit
                                && visit(i, chord, &mut limit)
                            {
                                return;
                            }
                        }
                    }
                } else {
                    for (i, shape) in leaf.shapes() {
                        if let Some(chord) = shape.intersect(ray) {
                            if chord.t_exit > t_min
                                && chord.t_enter < limit
                                && visit(i, chord, &mut limit)
                            {
                                return;
                            }
                        }
                    }
                }
                continue;
            }
            let (a, b) = (node.first, node.first + 1);
            let na = &self.nodes[a as usize];
            let nb = &self.nodes[b as usize];
            let ta = slab_test(ray.origin, inv, na.min, na.max, t_min, limit);
            let tb = slab_test(ray.origin, inv, nb.min, nb.max, t_min, limit);
            match (ta, tb) {
                (Some(ta), Some(tb)) => {
                    // Far child first on the stack, so the near one is visited first.
                    if ta <= tb {
                        stack.push(b);
                        stack.push(a);
                    } else {
                        stack.push(a);
                        stack.push(b);
                    }
                }
                (Some(_), None) => stack.push(a),
                (None, Some(_)) => stack.push(b),
                (None, None) => {}
            }
        }
    }
}

/// A traversal stack that lives on the machine stack for the usual depths and spills to the
/// heap only for pathological trees.
struct NodeStack {
    fixed: [u32; 64],
    len: usize,
    spill: Vec<u32>,
}

impl NodeStack {
    fn new() -> Self {
        NodeStack {
            fixed: [0; 64],
            len: 0,
            spill: Vec::new(),
        }
    }
    #[inline]
    fn push(&mut self, n: u32) {
        if self.len < self.fixed.len() {
            self.fixed[self.len] = n;
            self.len += 1;
        } else {
            self.spill.push(n);
        }
    }
    #[inline]
    fn pop(&mut self) -> Option<u32> {
        if let Some(n) = self.spill.pop() {
            return Some(n);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.fixed[self.len])
    }
}

/// Subtrees over more spheres than this are built in parallel (smaller ones are not worth a
/// task, and each parallel level copies its subtrees once to relocate them).
const PARALLEL_MIN: usize = 16 * 1024;

/// A node's box and where its range of `indices` was split (`None`: a leaf).
fn split_node(indices: &mut [u32], boxes: &[Aabb], centers: &[DVec3]) -> (Aabb, Option<usize>) {
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for &i in indices.iter() {
        bounds.grow(&boxes[i as usize]);
        cbounds.grow_point(centers[i as usize]);
    }
    let count = indices.len();
    let split = if count <= MAX_LEAF {
        None
    } else {
        choose_split(indices, boxes, centers, &bounds, &cbounds)
    };
    let mid = match split {
        Some((axis, pos)) => {
            let mut left = 0;
            for k in 0..indices.len() {
                if centers[indices[k] as usize][axis] < pos {
                    indices.swap(k, left);
                    left += 1;
                }
            }
            if left == 0 || left == count {
                // Round-off put every centroid on one side: split by count instead.
                median_split(indices, centers, &cbounds);
                count / 2
            } else {
                left
            }
        }
        None if count > 4 * MAX_LEAF * BINS => {
            // SAH sees no gain (e.g. all centroids equal) but the node is huge: split by count
            // so depth stays logarithmic.
            median_split(indices, centers, &cbounds);
            count / 2
        }
        None => 0,
    };
    (bounds, (mid != 0 && mid != count).then_some(mid))
}

/// The subtree over `indices` (which start at position `base` of the tree's index array): its
/// root first, then the rest in the order of a sequential depth-first build. Child links are
/// positions in the returned vector; leaf ranges are positions in the whole index array.
fn build_subtree(
    indices: &mut [u32],
    base: usize,
    boxes: &[Aabb],
    centers: &[DVec3],
) -> Vec<BvhNode> {
    if indices.len() > PARALLEL_MIN {
        let (bounds, mid) = split_node(indices, boxes, centers);
        if let Some(mid) = mid {
            let (left, right) = indices.split_at_mut(mid);
            let (l, r) = if mid.min(right.len()) > PARALLEL_MIN {
                rayon::join(
                    || build_subtree(left, base, boxes, centers),
                    || build_subtree(right, base + mid, boxes, centers),
                )
            } else {
                // A lopsided split: recursing on would nest as deep as the tree (a few spheres
                // peeled off per level); the big side is built sequentially instead.
                (
                    build_sequential(left, base, boxes, centers),
                    build_sequential(right, base + mid, boxes, centers),
                )
            };
            // [root, l[0], r[0], l[1..], r[1..]]: position q ≥ 1 of l moves to q + 2, of r to
            // q + |l| + 1; roots (q = 0) move to 1 and 2 and are never linked to from inside.
            let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
            nodes.push(BvhNode {
                min: bounds.min,
                max: bounds.max,
                first: 1,
                count: 0,
            });
            let moved = |node: &BvhNode, by: usize| BvhNode {
                first: if node.count == 0 {
                    node.first + by as u32
                } else {
                    node.first
                },
                ..*node
            };
            let (by_l, by_r) = (2, l.len() + 1);
            nodes.push(moved(&l[0], by_l));
            nodes.push(moved(&r[0], by_r));
            nodes.extend(l[1..].iter().map(|node| moved(node, by_l)));
            nodes.extend(r[1..].iter().map(|node| moved(node, by_r)));
            return nodes;
        }
    }
    build_sequential(indices, base, boxes, centers)
}

/// [`build_subtree`] on one thread, with an explicit work stack of (node, range start, range
/// end): depth is bounded by the fall-back median split, so no recursion limit is hit.
fn build_sequential(
    indices: &mut [u32],
    base: usize,
    boxes: &[Aabb],
    centers: &[DVec3],
) -> Vec<BvhNode> {
    let empty = BvhNode {
        min: DVec3::ZERO,
        max: DVec3::ZERO,
        first: 0,
        count: 0,
    };
    let mut nodes = Vec::with_capacity(2 * indices.len().max(1));
    nodes.push(empty);
    let mut stack = vec![(0usize, 0usize, indices.len())];
    while let Some((node, start, end)) = stack.pop() {
        let (bounds, mid) = split_node(&mut indices[start..end], boxes, centers);
        nodes[node].min = bounds.min;
        nodes[node].max = bounds.max;
        let Some(mid) = mid else {
            nodes[node].first = (base + start) as u32;
            nodes[node].count = (end - start) as u32;
            continue;
        };
        let left = nodes.len();
        nodes.extend([empty, empty]);
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        stack.push((left + 1, start + mid, end));
        stack.push((left, start, start + mid));
    }
    nodes.shrink_to_fit();
    nodes
}

/// Reorders `slice` so that its first half holds the centroids below the median along the widest
/// centroid axis.
fn median_split(slice: &mut [u32], centers: &[DVec3], cbounds: &Aabb) {
    let axis = (cbounds.max - cbounds.min).max_position();
    let half = slice.len() / 2;
    slice.select_nth_unstable_by(half, |&a, &b| {
        centers[a as usize][axis].total_cmp(&centers[b as usize][axis])
    });
}

/// Slab test of the segment (t_min, t_max) against a box. `f64::min`/`max` drop the NaN that
/// 0·∞ gives when the origin lies on a slab plane of an axis the ray is parallel to.
/// Returns the entry distance when the segment meets the box.
#[inline]
fn slab_test(o: DVec3, inv: DVec3, min: DVec3, max: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
    let t0 = (min - o) * inv;
    let t1 = (max - o) * inv;
    let near =
        t0.x.min(t1.x)
            .max(t0.y.min(t1.y))
            .max(t0.z.min(t1.z))
            .max(t_min);
    let far =
        t0.x.max(t1.x)
            .min(t0.y.max(t1.y))
            .min(t0.z.max(t1.z))
            .min(t_max);
    (near <= far).then_some(near)
}

/// Binned SAH over centroids: the (axis, position) with the lowest cost, or `None` when no split
/// beats a leaf.
fn choose_split(
    indices: &[u32],
    boxes: &[Aabb],
    centers: &[DVec3],
    bounds: &Aabb,
    cbounds: &Aabb,
) -> Option<(usize, f64)> {
    let mut best: Option<(f64, usize, f64)> = None;
    #[allow(clippy::needless_range_loop)] // `axis` indexes DVec3 components, not a slice
    for axis in 0..3 {
        let lo = cbounds.min[axis];
        let hi = cbounds.max[axis];
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let scale = BINS as f64 / (hi - lo);
        let mut bin_box = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for &i in indices {
            let b = (((centers[i as usize][axis] - lo) * scale) as usize).min(BINS - 1);
            bin_count[b] += 1;
            bin_box[b].grow(&boxes[i as usize]);
        }
        // Sweep from the right to get the right-hand areas, then from the left.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in (1..BINS).rev() {
            acc.grow(&bin_box[b]);
            cnt += bin_count[b];
            right_area[b] = acc.half_area();
            right_count[b] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for b in 0..BINS - 1 {
            acc.grow(&bin_box[b]);
            cnt += bin_count[b];
            if cnt == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f64 + right_area[b + 1] * right_count[b + 1] as f64;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, lo + (b + 1) as f64 / scale));
            }
        }
    }
    let (cost, axis, pos) = best?;
    let leaf_cost = indices.len() as f64;
    let split_cost = TRAVERSAL_COST + cost / bounds.half_area().max(f64::MIN_POSITIVE);
    if split_cost < leaf_cost || indices.len() > 4 * MAX_LEAF * BINS {
        Some((axis, pos))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute_all(centers: &[DVec3], radii: &[f64], ray: &Ray, t_min: f64, t_max: f64) -> Vec<Hit> {
        let mut v: Vec<Hit> = centers
            .iter()
            .zip(radii)
            .enumerate()
            .filter_map(|(i, (&c, &r))| {
                intersect_sphere(ray, c, r).map(|chord| Hit {
                    index: i as u32,
                    chord,
                })
            })
            .filter(|h| h.chord.t_exit > t_min && h.chord.t_enter < t_max)
            .collect();
        v.sort_unstable_by(|a, b| {
            a.chord
                .t_enter
                .total_cmp(&b.chord.t_enter)
                .then(a.index.cmp(&b.index))
        });
        v
    }

    fn spheres() -> impl Strategy<Value = Vec<([f64; 3], f64)>> {
        prop::collection::vec(
            (prop::array::uniform3(-10.0f64..10.0), 0.05f64..2.0),
            0..200,
        )
    }

    #[derive(Debug, Clone)]
    enum RayKind {
        Random([f64; 3], [f64; 3]),
        /// Grazes sphere `k` at (1 − 1e-12·s)·r from its centre, s ∈ [-1, 1].
        Graze(usize, [f64; 3], f64),
        /// Starts inside sphere `k`.
        Inside(usize, [f64; 3], [f64; 3]),
    }

    fn ray_kind() -> impl Strategy<Value = RayKind> {
        prop_oneof![
            (
                prop::array::uniform3(-15.0f64..15.0),
                prop::array::uniform3(-1.0f64..1.0)
            )
                .prop_map(|(o, d)| RayKind::Random(o, d)),
            (
                0usize..1000,
                prop::array::uniform3(-1.0f64..1.0),
                -1.0f64..1.0
            )
                .prop_map(|(k, d, s)| RayKind::Graze(k, d, s)),
            (
                0usize..1000,
                prop::array::uniform3(-0.5f64..0.5),
                prop::array::uniform3(-1.0f64..1.0)
            )
                .prop_map(|(k, o, d)| RayKind::Inside(k, o, d)),
        ]
    }

    fn make_ray(kind: &RayKind, centers: &[DVec3], radii: &[f64]) -> Option<Ray> {
        match *kind {
            RayKind::Random(o, d) => {
                let d = DVec3::from(d);
                (d.length() > 1e-3).then(|| Ray::new(DVec3::from(o), d))
            }
            RayKind::Graze(k, d, s) => {
                let d = DVec3::from(d);
                if centers.is_empty() || d.length() < 1e-3 {
                    return None;
                }
                let k = k % centers.len();
                let d = d.normalize();
                let b = radii[k] * (1.0 - 1e-12 * s);
                let origin = centers[k] + d.any_orthonormal_vector() * b - 20.0 * d;
                Some(Ray {
                    origin,
                    direction: d,
                })
            }
            RayKind::Inside(k, o, d) => {
                let d = DVec3::from(d);
                if centers.is_empty() || d.length() < 1e-3 {
                    return None;
                }
                let k = k % centers.len();
                Some(Ray::new(centers[k] + DVec3::from(o) * radii[k], d))
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        #[test]
        fn bvh_queries_agree_with_brute_force(sph in spheres(), kind in ray_kind(), t_min in prop_oneof![Just(0.0), Just(f64::NEG_INFINITY)], t_max in prop_oneof![Just(f64::INFINITY), 0.1f64..30.0]) {
            let centers: Vec<DVec3> = sph.iter().map(|s| DVec3::from(s.0)).collect();
            let radii: Vec<f64> = sph.iter().map(|s| s.1).collect();
            let Some(ray) = make_ray(&kind, &centers, &radii) else { return Ok(()); };
            let bvh = Bvh::build(centers.clone(), radii.clone());
            let mut got = Vec::new();
            bvh.all_hits(&ray, t_min, t_max, &mut got);
            let expected = brute_all(&centers, &radii, &ray, t_min, t_max);
            prop_assert_eq!(&got, &expected);
            prop_assert_eq!(bvh.any_hit(&ray, t_min, t_max, |_| false), !expected.is_empty());
            let brute_first = expected
                .iter()
                .map(|h| if h.chord.t_enter > t_min { (h.index, h.chord.t_enter, true) } else { (h.index, h.chord.t_exit, false) })
                .filter(|h| h.1 < t_max)
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            prop_assert_eq!(bvh.first_hit(&ray, t_min, t_max), brute_first);
            if let Some(first) = expected.first() {
                let skip = first.index;
                let others = expected.iter().any(|h| h.index != skip);
                prop_assert_eq!(bvh.any_hit(&ray, t_min, t_max, |i| i == skip), others);
            }
            // Over every other sphere: the hits of those, with their original indices.
            let keep = |i: usize| i % 2 == 1;
            let subset = Bvh::build_over(centers.clone(), radii.clone(), keep);
            prop_assert_eq!(subset.len(), centers.len() / 2);
            subset.all_hits(&ray, t_min, t_max, &mut got);
            let kept: Vec<Hit> = expected.into_iter().filter(|h| keep(h.index as usize)).collect();
            prop_assert_eq!(got, kept);
        }
    }

    #[test]
    fn leaves_cover_every_sphere_once_and_memory_is_linear() {
        let n = 20_000;
        let mut centers = Vec::with_capacity(n);
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..n {
            centers.push(DVec3::new(next(), next(), next()) * 100.0);
        }
        let bvh = Bvh::build(centers, vec![0.5; n]);
        assert!(bvh.nodes.len() < 2 * n);
        let mut seen = vec![0u8; n];
        for node in bvh.nodes.iter().filter(|nd| nd.count > 0) {
            for &i in &bvh.indices[node.first as usize..(node.first + node.count) as usize] {
                seen[i as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    /// The parallel build gives the sequential build's tree, node for node, on any number of
    /// threads: for uniform spheres (balanced splits, several parallel levels) and for a dense
    /// cluster with a sparse halo (lopsided splits).
    #[test]
    fn parallel_build_equals_the_sequential_tree_on_any_thread_count() {
        // SplitMix64 from seed 5 (formats::random's generator, written out: geometry does not
        // reach into formats, which reads cameras into geometry's types).
        let mut state = 5u64;
        let mut next = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        };
        let mut v = || DVec3::new(next(), next(), next());
        let n = 6 * PARALLEL_MIN;
        let uniform: Vec<DVec3> = (0..n).map(|_| v() * 100.0).collect();
        let clustered: Vec<DVec3> = (0..n)
            .map(|i| if i % 50 == 0 { v() * 1e4 } else { v() })
            .collect();
        for centers in [uniform, clustered] {
            let radii: Vec<f64> = (0..n).map(|i| 0.2 + (i % 7) as f64 * 0.1).collect();
            let boxes: Vec<Aabb> = centers
                .iter()
                .zip(&radii)
                .map(|(&c, &r)| sphere_box(c, r))
                .collect();
            let mut indices: Vec<u32> = (0..n as u32).collect();
            let nodes = build_sequential(&mut indices, 0, &boxes, &centers);
            for threads in [1, 2, 5] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let bvh = pool.install(|| Bvh::build(centers.clone(), radii.clone()));
                assert!(bvh.nodes == nodes, "{threads} threads: the nodes differ");
                assert!(
                    bvh.indices == indices,
                    "{threads} threads: the indices differ"
                );
            }
        }
    }

    #[test]
    fn identical_centres_still_build_a_shallow_tree() {
        let n = 5000;
        let bvh = Bvh::build(vec![DVec3::ONE; n], vec![1.0; n]);
        let ray = Ray::new(DVec3::new(1.0, 1.0, -5.0), DVec3::Z);
        let mut hits = Vec::new();
        bvh.all_hits(&ray, 0.0, f64::INFINITY, &mut hits);
        assert_eq!(hits.len(), n);
    }
}
