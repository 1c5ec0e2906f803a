//! The scene as the GPU sees it (docs/design.md §4): one Rust definition of every struct that the
//! WGSL prelude uses, with explicit padding, so that `bytemuck` can upload them byte for byte.
//! The WGSL declarations are *generated* from these definitions ([`gpu_struct!`] records each
//! field's WGSL type, [`super::wgsl::wgsl_declarations`] writes them); `tests/gpu/layout.rs`
//! parses the result with naga and compares every member offset and struct size with these
//! definitions, so a Rust layout that WGSL would pad differently fails a test instead of
//! silently scrambling the scene.
//!
//! Coordinates are **camera-relative** (world position − camera position, computed in f64 and
//! then rounded to f32): the camera sits at the origin, so f32 keeps its precision where the
//! image is, however far the scene is from the world origin.

use super::contract::{
    FALLOFF_INVERSE_SQUARE, FALLOFF_NONE, LIGHT_DIRECTIONAL, LIGHT_POINT, NO_ELLIPSOID,
    PARAM_SLOTS, PROFILE_CONSTANT, PROFILE_GAUSSIAN, SIGMA_INFINITE,
};
use crate::geometry::{Bvh, Ellipsoid};
use crate::scene::{Falloff, Light, Particle, Profile, Scene};
use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// A Rust struct that has a WGSL twin generated from it.
pub trait WgslStruct {
    /// The WGSL struct's name.
    const WGSL_NAME: &'static str;
    /// (member name, WGSL type) in declaration order, padding included.
    const WGSL_FIELDS: &'static [(&'static str, &'static str)];
}

/// The WGSL type of a Rust field type (only the types the contract uses; another one is a
/// compile error here, not a silent mismatch).
macro_rules! wgsl_type {
    (atomic u32) => {
        "atomic<u32>"
    };
    ($kind:ident u32) => {
        "u32"
    };
    ($kind:ident f32) => {
        "f32"
    };
    ($kind:ident [f32; 3]) => {
        "vec3<f32>"
    };
    ($kind:ident [[u32; 4]; $n:literal]) => {
        concat!("array<vec4<u32>, ", stringify!($n), ">")
    };
}

/// Declares a `#[repr(C)]` Pod struct and its [`WgslStruct`] description from one field list.
/// `plain` structs map `u32` to `u32`, `atomic` ones (counters the shaders raise) to
/// `atomic<u32>`.
macro_rules! gpu_struct {
    (
        $(#[$meta:meta])*
        $kind:ident $wgsl:literal pub struct $name:ident {
            $($(#[$fmeta:meta])* pub $field:ident : $ty:tt,)*
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
        pub struct $name {
            $($(#[$fmeta])* pub $field: $ty,)*
        }

        impl WgslStruct for $name {
            const WGSL_NAME: &'static str = $wgsl;
            const WGSL_FIELDS: &'static [(&'static str, &'static str)] =
                &[$((stringify!($field), wgsl_type!($kind $ty)),)*];
        }
    };
}

gpu_struct! {
    /// WGSL `struct Particle`, 64 bytes.
    plain "Particle" pub struct GpuParticle {
        /// Camera-relative centre (m).
        pub center: [f32; 3],
        /// Radius (m).
        pub radius: f32,
        /// Linear RGB colour C.
        pub color: [f32; 3],
        /// Extinction σ (1/m), or [`SIGMA_INFINITE`].
        pub sigma: f32,
        /// Single-scatter albedo.
        pub albedo: [f32; 3],
        /// Blinn–Phong specular weight.
        pub ks: f32,
        /// Blinn–Phong exponent.
        pub shininess: f32,
        /// The shape (docs/design.md §9): [`NO_ELLIPSOID`] for a sphere of `radius`, else the
        /// index of its [`GpuEllipsoid`] in `ellipsoids` (`radius` is then the bounding radius).
        pub ellipsoid: u32,
        /// The density profile (docs/design.md §9): [`PROFILE_CONSTANT`] or
        /// [`PROFILE_GAUSSIAN`] (`radius` or the ellipsoid's semi-axes are then standard
        /// deviations and `sigma` the peak density).
        pub profile: u32,
        /// A Gaussian's splatting opacity o = 1 − exp(−σ·s_min·√(2π)), s_min its shortest
        /// standard deviation (docs/design.md §9, "The opacity of a Gaussian"; computed in
        /// f64): what a splatting method blends. 0 for constant density.
        pub opacity: f32,
    }
}

gpu_struct! {
    /// WGSL `struct Ellipsoid`, 48 bytes: the map M = S⁻¹Rᵀ of docs/design.md §9 from a world
    /// offset about the centre to unit-sphere coordinates, by rows (row i is the body's axis i
    /// in world coordinates divided by its semi-axis), and the semi-axes s_i (M⁻¹ = R·S has the
    /// columns s_i²·row_i).
    plain "Ellipsoid" pub struct GpuEllipsoid {
        pub row_x: [f32; 3],
        pub semi_x: f32,
        pub row_y: [f32; 3],
        pub semi_y: f32,
        pub row_z: [f32; 3],
        pub semi_z: f32,
    }
}

impl GpuEllipsoid {
    /// The ellipsoid's map (the reference's own M, [`Ellipsoid::to_unit_matrix`]) in f32.
    pub fn new(e: &Ellipsoid) -> GpuEllipsoid {
        let m = e.to_unit_matrix();
        let s = e.semi_axes();
        let row = |i: usize| m.row(i).as_vec3().to_array();
        GpuEllipsoid {
            row_x: row(0),
            semi_x: s.x as f32,
            row_y: row(1),
            semi_y: s.y as f32,
            row_z: row(2),
            semi_z: s.z as f32,
        }
    }
}

gpu_struct! {
    /// WGSL `struct BvhNode`, 32 bytes: the foundation's [`crate::geometry::BvhNode`] in f32
    /// (camera-relative). `count > 0`: a leaf holding `leaf_indices[first..first+count]`;
    /// `count == 0`: an inner node with children `first` and `first + 1`.
    plain "BvhNode" pub struct GpuBvhNode {
        pub min: [f32; 3],
        pub first: u32,
        pub max: [f32; 3],
        pub count: u32,
    }
}

gpu_struct! {
    /// WGSL `struct Light`, 32 bytes (docs/design.md §1).
    plain "Light" pub struct GpuLight {
        /// Directional: the unit direction the light travels. Point: camera-relative position.
        pub vector: [f32; 3],
        /// [`LIGHT_DIRECTIONAL`] or [`LIGHT_POINT`].
        pub kind: u32,
        /// Directional: irradiance E (W/m²). Point: intensity I (W/sr).
        pub power: [f32; 3],
        /// [`FALLOFF_INVERSE_SQUARE`] or [`FALLOFF_NONE`] (point lights).
        pub falloff: u32,
    }
}

gpu_struct! {
    /// WGSL `struct Frame` (the uniform buffer), 176 bytes: camera, background, render settings
    /// and the method's parameters.
    plain "Frame" pub struct GpuFrame {
        /// Camera frame f, r, u of docs/design.md §1 (the camera is at the origin).
        pub forward: [f32; 3],
        /// tan(fov_y / 2).
        pub tan_half_fov: f32,
        pub right: [f32; 3],
        pub width: u32,
        pub up: [f32; 3],
        pub height: u32,
        /// L_bg, linear RGB.
        pub background: [f32; 3],
        pub light_count: u32,
        pub particle_count: u32,
        /// Lit model light weight w (docs/design.md §2: 1/m or 1), from
        /// [`crate::optics::source::light_weight`].
        pub light_weight: f32,
        /// Opaque-mode ambient factor.
        pub ambient: f32,
        /// 1 when the scene's model is `lit` (the `thesis` method lights the first `n_exact`
        /// particles only then), 0 otherwise.
        pub lit: u32,
        /// World position of the camera (f32; for user shaders that need world coordinates:
        /// world = camera-relative + camera_position).
        pub camera_position: [f32; 3],
        /// A multi-pass method (`thesis`) computes the work items with index in
        /// [pair_begin, pair_end) in this pass (for `thesis`: pair = k·samples + j for the k-th
        /// particle from the eye and its j-th sample). Work is split into passes because
        /// lavapipe ends every loop of an invocation after `LOOP_LIMIT` iterations in total
        /// (see `dispatch::PassSchedule`). Pass 0 writes the image, later passes add to it.
        pub pair_begin: u32,
        pub pair_end: u32,
        /// The image band this dispatch computes: rows [row_begin, row_begin + row_count) of
        /// the `width`×`height` image, written to `output` from its index 0 (row `row_begin`).
        /// Images whose output exceeds one storage buffer are rendered band by band (see
        /// `dispatch::bands`); the camera ray still uses the whole image's size.
        pub row_begin: u32,
        pub row_count: u32,
        /// 1 when the camera has intrinsics (docs/design.md §1 "Intrinsics": the camera ray
        /// uses `fx`, `fy`, `cx`, `cy`), 0 for a fov_y camera (`tan_half_fov`).
        pub pinhole: u32,
        /// The splatting methods' per-pixel constants (docs/design.md §4 `splat`, set from the
        /// method's parameters by `splat_tiles::SplatConstants::apply_to`; 3DGS's otherwise):
        /// the α cap, the α below which a splat is skipped, the transmittance below which a
        /// pixel stops, and 1 when it also stops at a transmittance equal to it.
        pub splat_alpha_cap: f32,
        pub splat_alpha_skip: f32,
        pub splat_stop_below: f32,
        pub splat_stop_inclusive: u32,
        /// The method's parameters, slot k at `params[k / 4][k % 4]` (the prelude's
        /// `method_param(slot)`; slots are named by generated `PARAM_<NAME>` constants).
        pub params: [[u32; 4]; 2],
        /// Pinhole intrinsics in pixels (with `pinhole` = 1; else the fov_y camera's own,
        /// [`crate::geometry::Camera::pinhole`]).
        pub fx: f32,
        pub fy: f32,
        pub cx: f32,
        pub cy: f32,
    }
}

// The frame's parameter array has exactly PARAM_SLOTS slots.
const _: () = assert!(std::mem::size_of::<[[u32; 4]; 2]>() / 4 == PARAM_SLOTS);

gpu_struct! {
    /// WGSL `struct Splat`, 32 bytes: one Gaussian projected to the image by the splatting
    /// methods' preprocessing ([`super::splat_tiles`], docs/design.md §4 `splat`).
    plain "Splat" pub struct GpuSplat {
        /// Centre on the image, pixels (pixel centres at +0.5, y down).
        pub mean_x: f32,
        pub mean_y: f32,
        /// The conic Σ₂D⁻¹ = [[a, b], [b, c]] of the dilated 2D covariance, 1/px².
        pub conic_a: f32,
        pub conic_b: f32,
        pub conic_c: f32,
        /// The particle's splatting opacity o (`Particle.opacity`).
        pub opacity: f32,
        /// View depth of the centre.
        pub depth: f32,
        /// Index of the particle in `particles`.
        pub particle: u32,
    }
}

gpu_struct! {
    /// WGSL `struct Stats`: counters the shaders raise (atomics).
    atomic "Stats" pub struct GpuStats {
        /// Hit lists that were full: the farthest hits were dropped (see `MAX_HITS`).
        pub hit_overflows: u32,
        /// Pixels whose shader ran at least `LOOP_BUDGET` loop iterations (counted in the
        /// prelude's and pgt's loops): on lavapipe such a pixel may have been cut short.
        pub loop_limited: u32,
        /// Pixels that have work items beyond this pass's range: another pass follows.
        pub more_work: u32,
        /// The most loop iterations any pixel counted in this pass.
        pub max_loop_iterations: u32,
    }
}

/// The scene converted for upload.
#[derive(Debug, Clone)]
pub struct SceneBuffers {
    pub particles: Vec<GpuParticle>,
    /// The ellipsoids' maps, in particle order (empty in a scene of spheres).
    pub ellipsoids: Vec<GpuEllipsoid>,
    pub nodes: Vec<GpuBvhNode>,
    pub leaf_indices: Vec<u32>,
    pub lights: Vec<GpuLight>,
    /// Depth of the BVH (root = 1), checked against the shader's traversal stack.
    pub bvh_depth: u32,
    /// The splatting methods' projected Gaussians ([`super::splat_tiles::build`]); empty for
    /// the other methods.
    pub splats: Vec<GpuSplat>,
    /// The splatting methods' tile lists ([`super::splat_tiles::build`]); empty otherwise.
    pub tile_entries: Vec<u32>,
}

fn rel(v: DVec3, origin: DVec3) -> [f32; 3] {
    (v - origin).as_vec3().to_array()
}

/// σ in f32: +∞ or beyond f32's range becomes the sentinel.
fn sigma_f32(sigma: f64) -> f32 {
    let s = sigma as f32;
    if s.is_finite() {
        s
    } else {
        SIGMA_INFINITE
    }
}

/// Rounds a camera-relative box outwards by a relative margin so that the f32 box still contains
/// the f32 sphere: rounding the corners to nearest could cull a grazing ray.
pub(crate) fn widen(min: DVec3, max: DVec3, origin: DVec3) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = (min - origin, max - origin);
    let pad = (hi - lo).max_element().max(0.0) * 1e-6 + lo.abs().max(hi.abs()).max_element() * 1e-6;
    (
        (lo - DVec3::splat(pad)).as_vec3().to_array(),
        (hi + DVec3::splat(pad)).as_vec3().to_array(),
    )
}

impl SceneBuffers {
    /// Converts the scene and its BVH (built by the foundation's binned SAH) to the GPU layout.
    pub fn new(scene: &Scene, bvh: &Bvh) -> SceneBuffers {
        let origin = scene.camera.position;
        let mut ellipsoids = Vec::new();
        let particles = scene
            .particles
            .iter()
            .map(|p| GpuParticle {
                ellipsoid: match &p.ellipsoid {
                    None => NO_ELLIPSOID,
                    Some(e) => {
                        ellipsoids.push(GpuEllipsoid::new(e));
                        ellipsoids.len() as u32 - 1
                    }
                },
                center: rel(p.center, origin),
                radius: p.radius as f32,
                color: p.color.as_vec3().to_array(),
                sigma: sigma_f32(p.sigma),
                albedo: p.albedo.as_vec3().to_array(),
                ks: p.ks as f32,
                shininess: p.shininess as f32,
                profile: match p.profile {
                    Profile::Constant => PROFILE_CONSTANT,
                    Profile::Gaussian => PROFILE_GAUSSIAN,
                },
                opacity: match p.profile {
                    Profile::Constant => 0.0,
                    Profile::Gaussian => gaussian_opacity(p) as f32,
                },
            })
            .collect();
        let nodes = gpu_nodes(bvh, origin);
        let lights = scene
            .lights
            .iter()
            .map(|l| match *l {
                Light::Directional {
                    direction,
                    irradiance,
                } => GpuLight {
                    vector: direction.normalize().as_vec3().to_array(),
                    kind: LIGHT_DIRECTIONAL,
                    power: irradiance.as_vec3().to_array(),
                    falloff: FALLOFF_NONE,
                },
                Light::Point {
                    position,
                    intensity,
                    falloff,
                } => GpuLight {
                    vector: rel(position, origin),
                    kind: LIGHT_POINT,
                    power: intensity.as_vec3().to_array(),
                    falloff: match falloff {
                        Falloff::InverseSquare => FALLOFF_INVERSE_SQUARE,
                        Falloff::None => FALLOFF_NONE,
                    },
                },
            })
            .collect();
        SceneBuffers {
            particles,
            ellipsoids,
            nodes,
            leaf_indices: bvh.indices.clone(),
            lights,
            bvh_depth: bvh_depth(bvh),
            splats: Vec::new(),
            tile_entries: Vec::new(),
        }
    }

    /// Widens every Gaussian particle's shape to `k` standard deviations (radius·k, the
    /// ellipsoid's map M/k and semi-axes·k): what `gauss-ray` traces (its BVH is built over the
    /// same widened shapes, [`widened_gaussians`]).
    pub fn widen_gaussians(&mut self, k: f64) {
        let k32 = k as f32;
        for p in &mut self.particles {
            if p.profile != PROFILE_GAUSSIAN {
                continue;
            }
            p.radius *= k32;
            if let Some(e) = self.ellipsoids.get_mut(p.ellipsoid as usize) {
                for (row, semi) in [
                    (&mut e.row_x, &mut e.semi_x),
                    (&mut e.row_y, &mut e.semi_y),
                    (&mut e.row_z, &mut e.semi_z),
                ] {
                    *row = row.map(|v| v / k32);
                    *semi *= k32;
                }
            }
        }
    }
}

/// A Gaussian particle's splatting opacity o = 1 − exp(−σ·s_min·√(2π)) (docs/design.md §9,
/// the inverse of [`crate::optics::gaussian::sigma_from_peak_opacity`]); σ = +∞ gives 1.
pub fn gaussian_opacity(p: &Particle) -> f64 {
    let shortest = p
        .ellipsoid
        .as_ref()
        .map_or(p.radius, |e| e.shortest_semi_axis());
    -(-p.sigma * shortest * (2.0 * std::f64::consts::PI).sqrt()).exp_m1()
}

/// The scene with every Gaussian particle's shape widened to `k` standard deviations (radius
/// and semi-axes times k), for the BVH of a method that traces the Gaussians' k-σ ellipsoids.
pub fn widened_gaussians(scene: &Scene, k: f64) -> Scene {
    let mut out = scene.clone();
    for p in &mut out.particles {
        if p.profile != Profile::Gaussian {
            continue;
        }
        p.radius *= k;
        if let Some(e) = &p.ellipsoid {
            p.ellipsoid = Some(Ellipsoid::new(e.semi_axes() * k, e.rotation()));
        }
    }
    out
}

/// The nodes of `bvh` as the shaders read them: boxes relative to `origin`, widened outwards to
/// f32 ([`widen`]); the empty tree's root an inverted box no ray enters.
pub fn gpu_nodes(bvh: &Bvh, origin: DVec3) -> Vec<GpuBvhNode> {
    bvh.nodes
        .iter()
        .map(|n| {
            let (min, max) = if n.min.x <= n.max.x {
                widen(n.min, n.max, origin)
            } else {
                ([f32::MAX; 3], [f32::MIN; 3])
            };
            GpuBvhNode {
                min,
                first: n.first,
                max,
                count: n.count,
            }
        })
        .collect()
}

/// Depth of the tree (a lone root is 1), by an explicit stack: no recursion on deep trees.
pub fn bvh_depth(bvh: &Bvh) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1u32)];
    while let Some((n, d)) = stack.pop() {
        deepest = deepest.max(d);
        let Some(node) = bvh.nodes.get(n) else {
            continue;
        };
        if node.count == 0 && !bvh.is_empty() {
            stack.push((node.first as usize, d + 1));
            stack.push((node.first as usize + 1, d + 1));
        }
    }
    deepest
}

impl GpuFrame {
    /// The frame uniform of a scene: camera of docs/design.md §1, the render settings and the
    /// method's parameter values by slot (at most [`PARAM_SLOTS`]; the caller validates).
    pub fn new(scene: &Scene, params: &[u32]) -> GpuFrame {
        let cam = &scene.camera;
        let k = cam.pinhole();
        let mut slots = [[0u32; 4]; 2];
        for (k, v) in params.iter().take(PARAM_SLOTS).enumerate() {
            slots[k / 4][k % 4] = *v;
        }
        GpuFrame {
            forward: cam.forward.as_vec3().to_array(),
            tan_half_fov: cam.tan_half_fov as f32,
            right: cam.right.as_vec3().to_array(),
            width: cam.width,
            up: cam.up.as_vec3().to_array(),
            height: cam.height,
            background: scene.render.background.as_vec3().to_array(),
            light_count: scene.lights.len() as u32,
            particle_count: scene.particles.len() as u32,
            light_weight: crate::optics::source::light_weight(
                scene.render.light_weight,
                scene.lights.len(),
            ) as f32,
            ambient: scene.render.ambient as f32,
            lit: (scene.render.model == crate::optics::models::LIT) as u32,
            camera_position: cam.position.as_vec3().to_array(),
            pair_begin: 0,
            pair_end: u32::MAX,
            row_begin: 0,
            row_count: cam.height,
            params: slots,
            pinhole: cam.intrinsics.is_some() as u32,
            fx: k.fx as f32,
            fy: k.fy as f32,
            cx: k.cx as f32,
            cy: k.cy as f32,
            splat_alpha_cap: super::contract::SPLAT_ALPHA_MAX,
            splat_alpha_skip: super::contract::SPLAT_ALPHA_MIN,
            splat_stop_below: super::contract::SPLAT_T_MIN,
            splat_stop_inclusive: 0,
        }
    }
}
