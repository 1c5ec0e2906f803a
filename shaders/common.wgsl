// pgt prelude (docs/design.md §4): the scene buffers, the camera of docs/design.md §1, ray–particle
// intersection (spheres and ellipsoids), one BVH traversal (all hits, first hit, any hit) and per-particle emission
// compositing. Every method file, pgt's own and users' (docs/user-shaders.md), is appended to
// this prelude and defines
//     fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>
// Coordinates are camera-relative (world − camera position): the camera is at the origin.
// The shared declarations are generated from Rust (see below); tests/gpu/layout.rs checks
// their layout with naga.

// The constants (MAX_HITS, STACK_SIZE, T_FAR, SIGMA_INFINITE, NO_PARTICLE, NO_ELLIPSOID, PI, the
// light and falloff codes, LOOP_LIMIT, LOOP_LIMIT_REPORT, WORKGROUP_SIDE, PARAM_SLOTS, the profile
// codes, TILE_SIDE and the Gaussian methods' SPLAT_*, GAUSSIAN_TRACE_SIGMAS, GAUSS_RAY_BATCH),
// the structs Particle, Ellipsoid, BvhNode, Light, Frame, Stats, Splat and the bindings frame,
// particles, nodes, leaf_indices, lights, output, stats, ellipsoids, splats, tile_entries are
// generated from src/approx/contract.rs and src/approx/layout.rs and prepended to this file:
// their values and docs live there.

// A method's parameter by slot; the slots are named by generated constants PARAM_<NAME>
// (e.g. method_param(PARAM_SAMPLES)).
fn method_param(slot: u32) -> u32 {
    return frame.params[slot / 4u][slot % 4u];
}

// Set when any hit list of this invocation overflowed; the entry point counts the pixel.
var<private> pixel_overflowed: bool = false;

// lavapipe (llvmpipe) ends all loops of an invocation after LOOP_LIMIT iterations *in total*
// and carries on with wrong values. pgt's loops count their iterations here; the entry point
// reports pixels that reached LOOP_LIMIT_REPORT (see src/approx/contract.rs for the margin),
// and the thesis method splits its work into passes to stay below it.
var<private> loop_iterations: u32 = 0u;
// Set by a method when this pixel has work beyond the pass's [pair_begin, pair_end).
var<private> pixel_more_work: bool = false;

fn count_iteration() {
    loop_iterations = loop_iterations + 1u;
}

// Working memory of one invocation lives at module scope (`private`): one copy per invocation
// however often the functions run, and the prelude's functions and a method can share hit lists
// by name. One traversal stack is enough: traversals never nest.
var<private> traversal_stack: array<u32, STACK_SIZE>;

struct Ray {
    origin: vec3<f32>,
    // Unit length, so t is a distance.
    direction: vec3<f32>,
}

fn ray_at(ray: Ray, t: f32) -> vec3<f32> {
    return ray.origin + t * ray.direction;
}

// docs/design.md §1: pixel (px, py), py down, through its centre:
// a = (2(px+0.5)/W − 1)·(W/H)·tan(fov_y/2), b = (1 − 2(py+0.5)/H)·tan(fov_y/2); with intrinsics
// ("Intrinsics") a = (px + 0.5 − cx)/fx, b = (cy − (py + 0.5))/fy.
fn camera_ray(pixel: vec2<u32>) -> Ray {
    if (frame.pinhole != 0u) {
        let a = (f32(pixel.x) + 0.5 - frame.cx) / frame.fx;
        let b = (frame.cy - (f32(pixel.y) + 0.5)) / frame.fy;
        return Ray(vec3<f32>(0.0), normalize(frame.forward + a * frame.right + b * frame.up));
    }
    let w = f32(frame.width);
    let h = f32(frame.height);
    let a = (2.0 * (f32(pixel.x) + 0.5) / w - 1.0) * (w / h) * frame.tan_half_fov;
    let b = (1.0 - 2.0 * (f32(pixel.y) + 0.5) / h) * frame.tan_half_fov;
    return Ray(vec3<f32>(0.0), normalize(frame.forward + a * frame.right + b * frame.up));
}

// Where a ray's line crosses a sphere; `hit` is false when it misses or only touches it.
struct Chord {
    t_enter: f32,
    t_exit: f32,
    hit: bool,
}

// The stable intersection of src/geometry/sphere.rs: project the centre on the ray and take the
// half-chord from h² = (r − |l|)(r + |l|), never the textbook b² − 4ac (which cancels when the
// origin is far from the sphere). The chord goes to 0 continuously at the silhouette.
fn intersect_sphere(ray: Ray, center: vec3<f32>, radius: f32) -> Chord {
    let f = ray.origin - center;
    let t_c = -dot(f, ray.direction);
    let l = f + t_c * ray.direction;
    let dist = length(l);
    var chord = Chord(0.0, 0.0, false);
    if (dist >= radius) {
        return chord;
    }
    let half = sqrt((radius - dist) * (radius + dist));
    if (half <= 0.0) {
        return chord;
    }
    chord.t_enter = t_c - half;
    chord.t_exit = t_c + half;
    chord.hit = true;
    return chord;
}

// Particle shapes (docs/design.md §9): a sphere (p.ellipsoid == NO_ELLIPSOID) of p.radius, or
// the ellipsoid ellipsoids[p.ellipsoid], whose map M = S⁻¹Rᵀ (by rows) takes a world offset
// about the centre to the unit sphere. Methods ask intersect_particle and particle_surface,
// never intersect_sphere directly, and so draw both shapes; a sphere's answers are the sphere
// code's own.

// M·v: a world offset (or direction) in the ellipsoid's unit-sphere coordinates.
fn ellipsoid_to_unit(e: Ellipsoid, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(e.row_x, v), dot(e.row_y, v), dot(e.row_z, v));
}

// M⁻¹·u = R·S·u: unit-sphere coordinates back to a world offset (column i of R·S is s_i²·row_i).
fn ellipsoid_from_unit(e: Ellipsoid, u: vec3<f32>) -> vec3<f32> {
    return e.row_x * (u.x * e.semi_x * e.semi_x) + e.row_y * (u.y * e.semi_y * e.semi_y)
        + e.row_z * (u.z * e.semi_z * e.semi_z);
}

// The chord of a ray through an ellipsoid: the mapped ray M(o − c) + t·Md, written with the unit
// direction Md/k and the parameter s = k·t (k = |Md|), crosses the unit sphere where
// intersect_sphere says (its stable form carries over); t = s/k.
fn intersect_ellipsoid(ray: Ray, center: vec3<f32>, e: Ellipsoid) -> Chord {
    let d = ellipsoid_to_unit(e, ray.direction);
    let k = length(d);
    if (!(k > 0.0)) {
        return Chord(0.0, 0.0, false);
    }
    let c = intersect_sphere(Ray(ellipsoid_to_unit(e, ray.origin - center), d / k), vec3<f32>(0.0), 1.0);
    return Chord(c.t_enter / k, c.t_exit / k, c.hit);
}

// Where a ray's line crosses particle p, whatever its shape. (HAS_ELLIPSOIDS, an `override`, is
// false for a scene of spheres: the test then folds away.)
fn intersect_particle(ray: Ray, p: Particle) -> Chord {
    if (!HAS_ELLIPSOIDS || p.ellipsoid == NO_ELLIPSOID) {
        return intersect_sphere(ray, p.center, p.radius);
    }
    // Most candidates miss: the bounding sphere (radius = the longest semi-axis) rejects a ray
    // whose line passes farther from the centre before the ray is mapped.
    let f = ray.origin - p.center;
    let l = f - dot(f, ray.direction) * ray.direction;
    if (dot(l, l) >= p.radius * p.radius) {
        return Chord(0.0, 0.0, false);
    }
    return intersect_ellipsoid(ray, p.center, ellipsoids[p.ellipsoid]);
}

// A point of a particle's surface and the outward unit normal there.
struct SurfacePoint {
    position: vec3<f32>,
    outward: vec3<f32>,
}

// The surface point on the line from p's centre through x (x near the surface: this snaps a
// computed hit onto it) and the outward normal there. An ellipsoid's normal is the gradient of
// |M(x − c)|², Mᵀ·M(x − c), normalised.
fn particle_surface(p: Particle, x: vec3<f32>) -> SurfacePoint {
    if (!HAS_ELLIPSOIDS || p.ellipsoid == NO_ELLIPSOID) {
        let outward = normalize(x - p.center);
        return SurfacePoint(p.center + outward * p.radius, outward);
    }
    let e = ellipsoids[p.ellipsoid];
    let u = normalize(ellipsoid_to_unit(e, x - p.center));
    let gradient = e.row_x * u.x + e.row_y * u.y + e.row_z * u.z;
    return SurfacePoint(p.center + ellipsoid_from_unit(e, u), normalize(gradient));
}

// Transmittance through a length of one particle's gas, exp(−σ·length); σ = +∞ (Θmax = 1)
// gives 0 for any positive length.
fn particle_transmittance(sigma: f32, length: f32) -> f32 {
    if (sigma < 0.0) {
        return select(1.0, 0.0, length > 0.0);
    }
    return exp(-sigma * max(length, 0.0));
}

// docs/design.md §2, emission model for one particle alone: L = L_behind·T + C·(1 − T).
fn composite_emission(p: Particle, length: f32, behind: vec3<f32>) -> vec3<f32> {
    let t = particle_transmittance(p.sigma, length);
    return behind * t + p.color * (1.0 - t);
}

// 1/d with d's zero components replaced by a tiny value of the same sign: the slab test then
// needs no infinities (0·∞ would be NaN).
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let s = select(vec3<f32>(1.0), vec3<f32>(-1.0), d < vec3<f32>(0.0));
    let m = max(abs(d), tiny);
    return s / m;
}

// Whether the ray meets a BVH box within [t_min, t_max] (box_span, the slab test shared with
// shaders/nearest_events.wgsl, is generated: src/approx/wgsl_generic.rs).
fn ray_box(origin: vec3<f32>, inv_dir: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_min: f32, t_max: f32) -> bool {
    let span = box_span(origin, inv_dir, bmin, bmax, t_min, t_max);
    return span.x <= span.y;
}

// The particles a ray crosses, sorted by entry (ties by index, as the CPU BVH sorts them).
// Parallel arrays keep the struct free of padding.
// Hit lists are `private` (see traversal_stack): `camera_hits` for the camera ray,
// `shadow_hits` for emission_along (shadow rays); user code may declare its own
// `var<private> name: HitList;`.
struct HitList {
    count: u32,
    overflowed: bool,
    t_enter: array<f32, MAX_HITS>,
    t_exit: array<f32, MAX_HITS>,
    index: array<u32, MAX_HITS>,
}

var<private> camera_hits: HitList;
var<private> shadow_hits: HitList;

// Inserts a particle's chord, keyed by (entry, index); a full list keeps its nearest MAX_HITS
// entries and is flagged as overflowed (hit_list_sorted_insert and the order hit_before are
// generated from the sorted insert that shaders/nearest_events.wgsl's batch also uses:
// src/approx/wgsl_generic.rs).
fn hit_list_insert(list: ptr<private, HitList>, index: u32, chord: Chord) {
    hit_list_sorted_insert(list, chord.t_enter, index, chord.t_exit, MAX_HITS);
}

// The nearest surface crossing with t in (t_min, t_max): which particle, where, and whether the
// ray enters it there (false: it leaves it, the origin being inside). Ties: lower index.
struct SurfaceHit {
    index: u32,
    t: f32,
    entering: bool,
    hit: bool,
}

// What `traverse` does with each particle whose chord overlaps (t_min, t_max).
// Collect: insert it into the hit list. First: keep the nearest surface crossing (and prune
// boxes beyond it). Any: stop at the first one.
const TRAVERSE_COLLECT: u32 = 0u;
const TRAVERSE_FIRST: u32 = 1u;
const TRAVERSE_ANY: u32 = 2u;

// The one BVH traversal (explicit stack). Particle `skip` is left out (NO_PARTICLE: none).
// `list` is written only in TRAVERSE_COLLECT mode (WGSL has no optional pointers: the other
// modes pass any hit list, untouched). Returns the hit found in the First and Any modes.
fn traverse(ray: Ray, t_min: f32, t_max: f32, mode: u32, skip: u32, list: ptr<private, HitList>) -> SurfaceHit {
    var best = SurfaceHit(0u, t_max, false, false);
    if (mode == TRAVERSE_COLLECT) {
        (*list).count = 0u;
        (*list).overflowed = false;
    }
    if (frame.particle_count == 0u) {
        return best;
    }
    let inv = safe_inverse(ray.direction);
    traversal_stack[0] = 0u;
    var sp = 1u;
    while (sp > 0u) {
        count_iteration();
        sp = sp - 1u;
        let node = nodes[traversal_stack[sp]];
        // best.t stays t_max except in the First mode, where it prunes boxes beyond the hit.
        if (!ray_box(ray.origin, inv, node.min, node.max, t_min, best.t)) {
            continue;
        }
        if (node.count > 0u) {
            for (var k = 0u; k < node.count; k = k + 1u) {
                count_iteration();
                let i = leaf_indices[node.first + k];
                if (i == skip) {
                    continue;
                }
                let c = intersect_particle(ray, particles[i]);
                if (!c.hit || c.t_exit <= t_min) {
                    continue;
                }
                if (mode == TRAVERSE_FIRST) {
                    let entering = c.t_enter > t_min;
                    let t = select(c.t_exit, c.t_enter, entering);
                    if (t < best.t || (t == best.t && best.hit && i < best.index)) {
                        best = SurfaceHit(i, t, entering, true);
                    }
                } else if (c.t_enter < t_max) {
                    if (mode == TRAVERSE_ANY) {
                        return SurfaceHit(i, c.t_enter, true, true);
                    }
                    hit_list_insert(list, i, c);
                }
            }
        } else if (sp + 2u <= STACK_SIZE) {
            traversal_stack[sp] = node.first;
            traversal_stack[sp + 1u] = node.first + 1u;
            sp = sp + 2u;
        }
    }
    return best;
}

// Every particle whose chord overlaps (t_min, t_max), sorted by entry, into `list`. Chords are
// not clipped: callers clip to their interval.
fn collect_hits(ray: Ray, t_min: f32, t_max: f32, list: ptr<private, HitList>) {
    traverse(ray, t_min, t_max, TRAVERSE_COLLECT, NO_PARTICLE, list);
}

fn first_hit(ray: Ray, t_min: f32, t_max: f32) -> SurfaceHit {
    return traverse(ray, t_min, t_max, TRAVERSE_FIRST, NO_PARTICLE, &shadow_hits);
}

// Whether any particle other than `skip` has a chord overlapping (t_min, t_max) (hard shadows).
// Pass skip = NO_PARTICLE to skip none.
fn any_hit(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    return traverse(ray, t_min, t_max, TRAVERSE_ANY, skip, &shadow_hits).hit;
}

// The emission model along (t_min, t_max) of a ray with `background` behind t_max, one particle
// at a time, back to front (docs/design.md §4: overlaps ignored; exact where particles are disjoint).
fn emission_along(ray: Ray, t_min: f32, t_max: f32, background: vec3<f32>) -> vec3<f32> {
    return emission_along_skipping(ray, t_min, t_max, background, NO_PARTICLE);
}

// emission_along with particle `skip` left out (a ray leaving that particle's surface).
fn emission_along_skipping(ray: Ray, t_min: f32, t_max: f32, background: vec3<f32>, skip: u32) -> vec3<f32> {
    collect_hits(ray, t_min, t_max, &shadow_hits);
    var radiance = background;
    var k = shadow_hits.count;
    while (k > 0u) {
        count_iteration();
        k = k - 1u;
        if (shadow_hits.index[k] == skip) {
            continue;
        }
        let p = particles[shadow_hits.index[k]];
        let length = min(shadow_hits.t_exit[k], t_max) - max(shadow_hits.t_enter[k], t_min);
        radiance = composite_emission(p, length, radiance);
    }
    return radiance;
}

// What arrives at x from one light before any occlusion (docs/design.md §1): the unit vector towards
// the light, the distance to it (T_FAR for directional lights) and E, or I/d² (I with
// falloff = "none"). `valid` is false at a point light's own position.
struct Incident {
    toward: vec3<f32>,
    distance: f32,
    irradiance: vec3<f32>,
    valid: bool,
}

fn light_incident(light: Light, x: vec3<f32>) -> Incident {
    if (light.kind == LIGHT_DIRECTIONAL) {
        return Incident(-light.vector, T_FAR, light.power, true);
    }
    let v = light.vector - x;
    let d = length(v);
    if (!(d > 0.0)) {
        return Incident(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), false);
    }
    var e = light.power;
    if (light.falloff == FALLOFF_INVERSE_SQUARE) {
        e = light.power / (d * d);
    }
    return Incident(v / d, d, e, true);
}

// docs/design.md §2 "lit": Q(x) = w·Σ_l L_l(x), L_l the emission model along the shadow ray from x
// towards light l with the light's E (or I/d²) as background; it includes the particle that
// contains x. One shadow ray per light.
fn lit_source(x: vec3<f32>) -> vec3<f32> {
    var q = vec3<f32>(0.0);
    for (var l = 0u; l < frame.light_count; l = l + 1u) {
        count_iteration();
        let inc = light_incident(lights[l], x);
        if (!inc.valid) {
            continue;
        }
        q = q + emission_along(Ray(x, inc.toward), 0.0, inc.distance, inc.irradiance);
    }
    return frame.light_weight * q;
}

// What a particle with Θmax = 1 (σ = ∞) shows where the camera ray enters it at t0, under the
// lit model: the limit σ → ∞ of ∫ σe^{−σs}·Q(x_s) ds. Light seen at depth z below the surface
// has crossed z/μ_l of the particle's own gas, the view ray z/μ_v, so each light contributes
// (L_rest·μ_l + C·μ_v)/(μ_l + μ_v), L_rest the emission model along the rest of the shadow ray
// (other particles, the light behind), μ_v = cos(view, normal), μ_l = cos(light, normal);
// a light behind the surface (μ_l ≤ 0), or an eye inside the particle, gives C.
fn lit_opaque_surface(ray: Ray, index: u32, t0: f32, entering: bool) -> vec3<f32> {
    let p = particles[index];
    let x = ray_at(ray, t0);
    let n = particle_surface(p, x).outward;
    let mu_v = max(dot(-ray.direction, n), 0.0);
    var q = vec3<f32>(0.0);
    for (var l = 0u; l < frame.light_count; l = l + 1u) {
        count_iteration();
        let inc = light_incident(lights[l], x);
        if (!inc.valid) {
            continue;
        }
        let mu_l = dot(n, inc.toward);
        if (!entering || mu_l <= 0.0 || mu_l + mu_v <= 0.0) {
            q = q + p.color;
            continue;
        }
        let rest = emission_along_skipping(Ray(x, inc.toward), 0.0, inc.distance, inc.irradiance, index);
        q = q + (rest * mu_l + p.color * mu_v) / (mu_l + mu_v);
    }
    return frame.light_weight * q;
}

// Gaussian particles (docs/design.md §9, §4 "splat", "gauss-ray"). The splatting methods read
// `splats` and `tile_entries`, made on the CPU by src/approx/splat_tiles.rs: tile k's splats,
// front to back by the centres' view depth, are tile_entries[tile_entries[2k] ..
// tile_entries[2k + 1]].

// The tile (row-major, TILE_SIDE pixels square) that holds a pixel.
fn pixel_tile(pixel: vec2<u32>) -> u32 {
    let columns = (frame.width + TILE_SIDE - 1u) / TILE_SIDE;
    return (pixel.y / TILE_SIDE) * columns + pixel.x / TILE_SIDE;
}

// Whether a pixel whose transmittance would become `next` stops before this splat: below the
// frame's splat_stop_below (3DGS: test_T < 0.0001), or also equal to it where
// splat_stop_inclusive is 1 (gsplat: next_T <= 1e-4).
fn splat_stops(next: f32) -> bool {
    return next < frame.splat_stop_below
        || (frame.splat_stop_inclusive != 0u && next == frame.splat_stop_below);
}

// 3D Gaussian splatting's opacity of a splat at a pixel centre (its forward.cu renderCUDA):
// α = min(cap, o·exp(−½ dᵀΣ₂D⁻¹d)), d the offset from the projected centre, cap the frame's
// splat_alpha_cap (3DGS 0.99, gsplat 0.999); 0 where the quadratic form is negative
// (rounding), as 3DGS and gsplat skip it.
fn splat_alpha(s: Splat, pixel: vec2<u32>) -> f32 {
    let d = vec2<f32>(s.mean_x, s.mean_y) - (vec2<f32>(pixel) + vec2<f32>(0.5));
    let power = -0.5 * (s.conic_a * d.x * d.x + s.conic_c * d.y * d.y) - s.conic_b * d.x * d.y;
    if (power > 0.0) {
        return 0.0;
    }
    return min(frame.splat_alpha_cap, s.opacity * exp(power));
}

// Front-to-back α compositing as 3D Gaussian splatting does it (forward.cu renderCUDA):
// L = Σ αᵢ·Tᵢ·Cᵢ + T·L_bg, Tᵢ the transmittance in front of splat i, the pixel stopping at the
// first splat that would take it to the stop (splat_stops; that splat not added). The splat
// methods and gauss-ray blend with it.
struct AlphaBlend {
    radiance: vec3<f32>,
    transmittance: f32,
}

fn alpha_blend_start() -> AlphaBlend {
    return AlphaBlend(vec3<f32>(0.0), 1.0);
}

// Adds a splat of colour `color` and opacity `alpha` behind what `b` holds; false where the
// pixel stops before it (`b` unchanged).
fn alpha_blend_over(b: ptr<function, AlphaBlend>, color: vec3<f32>, alpha: f32) -> bool {
    let next = (*b).transmittance * (1.0 - alpha);
    if (splat_stops(next)) {
        return false;
    }
    (*b).radiance = (*b).radiance + color * (alpha * (*b).transmittance);
    (*b).transmittance = next;
    return true;
}

// The pixel's value: what was blended, and the background through the transmittance left.
fn alpha_blend_end(b: AlphaBlend) -> vec3<f32> {
    return b.radiance + b.transmittance * frame.background;
}

// A Gaussian's maximum response along a ray, for a shape widened to `widened` standard
// deviations (gauss-ray traces its 3-σ ellipsoids): t* the closest approach in the Mahalanobis
// metric, clamped to the ray (t ≥ 0), and m the Mahalanobis distance there, in standard
// deviations. The mapped ray is u(t) = M(o − c) + t·Md (docs/design.md §9).
struct GaussianPeak {
    t_star: f32,
    m: f32,
}

fn gaussian_peak(ray: Ray, p: Particle, widened: f32) -> GaussianPeak {
    var u0 = (ray.origin - p.center) / p.radius;
    var v = ray.direction / p.radius;
    if (HAS_ELLIPSOIDS && p.ellipsoid != NO_ELLIPSOID) {
        let e = ellipsoids[p.ellipsoid];
        u0 = ellipsoid_to_unit(e, ray.origin - p.center);
        v = ellipsoid_to_unit(e, ray.direction);
    }
    let vv = dot(v, v);
    var t_star = 0.0;
    if (vv > 0.0) {
        t_star = max(-dot(u0, v) / vv, 0.0);
    }
    return GaussianPeak(t_star, widened * length(u0 + t_star * v));
}
