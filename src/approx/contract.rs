//! The one definition of the CPU–GPU contract (docs/design.md §4): every number and binding
//! index that Rust and WGSL share is defined here, and every struct in `layout.rs`;
//! `wgsl.rs` writes the WGSL for both, which `shader.rs` prepends to every program. The
//! definitions come first and the WGSL is generated from them, never the other way.
//! `shaders/` uses the names only; a GPU test checks that no file there repeats a number or
//! declaration made here.

/// Most particles one hit list holds. A ray that crosses more keeps the nearest `MAX_HITS` and
/// the pixel is counted in `stats.hit_overflows` (pgt reports it), never dropped silently.
pub const MAX_HITS: u32 = 128;

/// Entries of the WGSL BVH traversal stack.
pub const STACK_SIZE: u32 = 64;

/// Deepest BVH the WGSL traversal handles: one less than [`STACK_SIZE`], since a node's two
/// children are pushed together.
pub const STACK_DEPTH: u32 = STACK_SIZE - 1;

/// σ = +∞ (Θmax = 1) has no reliable f32 encoding in WGSL (implementations may assume no
/// infinities), so it travels as this sentinel; `particle_transmittance` in the prelude maps it
/// back to a transmittance of 0.
pub const SIGMA_INFINITE: f32 = -1.0;

/// "No upper bound" for a ray parameter t: a finite stand-in for +∞, for the same reason.
pub const T_FAR: f32 = 3.0e38;

/// "No particle" for the traversal's `skip` argument (no particle has this index).
pub const NO_PARTICLE: u32 = u32::MAX;

/// Light kinds in `GpuLight::kind`.
pub const LIGHT_DIRECTIONAL: u32 = 0;
pub const LIGHT_POINT: u32 = 1;
/// Point-light falloffs in `GpuLight::falloff` (docs/design.md §1).
pub const FALLOFF_INVERSE_SQUARE: u32 = 0;
pub const FALLOFF_NONE: u32 = 1;

/// lavapipe (llvmpipe) ends all loops of an invocation after this many iterations *in total*
/// (`LP_MAX_TGSI_LOOP_ITERATIONS`, shared by every loop of a shader) and carries on with wrong
/// values. pgt's loops count their iterations so that this can be reported and avoided.
pub const LOOP_LIMIT: u32 = 65535;

/// Loop iterations of one pixel in one pass at which pgt reports the pixel (and, for a
/// multi-pass method on a Cpu adapter, redoes the pass with less work): an eighth of
/// [`LOOP_LIMIT`], because lavapipe counts the loops of a group of 8 SIMD lanes together, each
/// loop as long as its slowest lane, so its count runs ahead of pgt's by a factor that grows
/// with how far the lanes' work differs: past 2 where neighbouring pixels' shadow rays cross very
/// different numbers of particles (a dense set such as "cool random"; docs/performance.md).
pub const LOOP_BUDGET: u32 = 8192;

/// Side of the square compute workgroup (`@workgroup_size(WORKGROUP_SIDE, WORKGROUP_SIDE, 1)`).
pub const WORKGROUP_SIDE: u32 = 8;

/// Slots for method parameters in `GpuFrame::params` (u32 each, packed in vec4s because a
/// uniform array's stride is 16 bytes).
pub const PARAM_SLOTS: usize = 8;

/// The most events one batch of the `ever` method holds (its `batch` parameter's maximum and
/// the size of its batch arrays).
pub const EVER_MAX_BATCH: u32 = 64;

/// `Particle.ellipsoid` of a sphere: no entry in `ellipsoids`.
pub const NO_ELLIPSOID: u32 = u32::MAX;

/// `Particle.profile` (docs/design.md §9): constant density σ inside the shape.
pub const PROFILE_CONSTANT: u32 = 0;
/// `Particle.profile`: Gaussian density σ·exp(−½m²), the shape's axes its standard deviations.
pub const PROFILE_GAUSSIAN: u32 = 1;

// 3D Gaussian splatting's per-pixel constants (graphdeco-inria `forward.cu` `renderCUDA`), each
// defined once here: the `splat` method's parameters take them as defaults in the parameters'
// integer units, and their f32 values reach the shaders as the frame's splat_* of every method
// but `splat`, which sets its parameters there (`layout::GpuFrame`), and as the generated WGSL
// constants SPLAT_* (`gauss-ray`'s α cap; it blends as 3DGS does, as 3DGRT keeps it).

/// The most opacity one splat gives a pixel, in millionths: `min(0.99f, con_o.w * exp(power))`.
pub const SPLAT_ALPHA_MAX_MILLIONTHS: u32 = 990_000;
/// A splat whose opacity at a pixel is below 1/this is skipped: `alpha < 1.0f / 255.0f`.
pub const SPLAT_ALPHA_SKIP_DENOMINATOR: u32 = 255;
/// A pixel stops at the first splat that would take its transmittance below this, in
/// millionths; that splat is not added: `test_T < 0.0001f`, tested before the colour is added.
pub const SPLAT_T_MIN_MILLIONTHS: u32 = 100;

/// [`SPLAT_ALPHA_MAX_MILLIONTHS`] as a fraction.
pub const SPLAT_ALPHA_MAX: f32 = ratio_f32(SPLAT_ALPHA_MAX_MILLIONTHS, 1e6);
/// 1/[`SPLAT_ALPHA_SKIP_DENOMINATOR`].
pub const SPLAT_ALPHA_MIN: f32 = ratio_f32(1, SPLAT_ALPHA_SKIP_DENOMINATOR as f64);
/// [`SPLAT_T_MIN_MILLIONTHS`] as a fraction.
pub const SPLAT_T_MIN: f32 = ratio_f32(SPLAT_T_MIN_MILLIONTHS, 1e6);

/// A parameter's value in its unit, `value/unit`, as the f32 a decimal literal of it would be
/// (a correctly rounded f64 division, then rounded to f32): how the `splat` method's integer
/// parameters become the frame's f32 constants.
pub const fn ratio_f32(value: u32, unit: f64) -> f32 {
    (value as f64 / unit) as f32
}

/// The standard deviations at which `gauss-ray` cuts each Gaussian: it traces the 3-σ
/// ellipsoids (3DGRT's bounding primitives; 3DGS's footprint radius is also 3σ).
pub const GAUSSIAN_TRACE_SIGMAS: f32 = 3.0;

/// Hits per BVH traversal of `gauss-ray`: each traversal keeps the nearest this many by t*
/// beyond the last one blended (EVER's 16 hits per trace, as `ever`'s default batch).
pub const GAUSS_RAY_BATCH: u32 = 16;

/// Side of the square image tiles of the splatting methods' lists, in pixels (3D Gaussian
/// splatting's `BLOCK_X` = `BLOCK_Y` = 16, `cuda_rasterizer/config.h`).
pub const TILE_SIDE: u32 = 16;

/// The pipeline-overridable constant (WGSL `override`, default true) that says whether the scene
/// has ellipsoids. pgt compiles each method twice as needed: with false for a scene of spheres,
/// so that the shape test folds away and sphere scenes run the sphere code alone (a branch that
/// is never taken still costs lavapipe, which executes both sides of a branch under a mask).
pub const OVERRIDE_HAS_ELLIPSOIDS: &str = "HAS_ELLIPSOIDS";

/// How a binding is declared in WGSL.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindingKind {
    Uniform,
    StorageRead,
    StorageReadWrite,
}

/// One buffer of bind group 0, as both sides see it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Binding {
    /// `@binding(index)`.
    pub index: u32,
    /// The WGSL variable's name.
    pub name: &'static str,
    pub kind: BindingKind,
    /// The WGSL type of the variable.
    pub wgsl_type: &'static str,
}

/// The uniform `frame` ([`GpuFrame`](super::layout::GpuFrame)).
pub const BINDING_FRAME: u32 = 0;
/// `particles` ([`GpuParticle`](super::layout::GpuParticle)).
pub const BINDING_PARTICLES: u32 = 1;
/// `nodes` ([`GpuBvhNode`](super::layout::GpuBvhNode)).
pub const BINDING_NODES: u32 = 2;
/// `leaf_indices` (u32).
pub const BINDING_LEAF_INDICES: u32 = 3;
/// `lights` ([`GpuLight`](super::layout::GpuLight)).
pub const BINDING_LIGHTS: u32 = 4;
/// `output`, one vec4 per pixel (RGB and 1).
pub const BINDING_OUTPUT: u32 = 5;
/// `stats` ([`GpuStats`](super::layout::GpuStats)).
pub const BINDING_STATS: u32 = 6;
/// `ellipsoids` ([`GpuEllipsoid`](super::layout::GpuEllipsoid)), indexed by
/// `Particle.ellipsoid`.
pub const BINDING_ELLIPSOIDS: u32 = 7;

/// `splats` ([`GpuSplat`](super::layout::GpuSplat)): the splatting methods' projected
/// Gaussians in order of view depth (one zeroed element for the other methods).
pub const BINDING_SPLATS: u32 = 8;
/// `tile_entries` (u32): per tile its range in this array, then the tiles' lists of splats
/// (`approx::splat_tiles::build`).
pub const BINDING_TILE_ENTRIES: u32 = 9;

/// Every binding of group 0, in index order (the pipeline layout and the WGSL come from this).
pub const BINDINGS: [Binding; 10] = [
    Binding {
        index: BINDING_FRAME,
        name: "frame",
        kind: BindingKind::Uniform,
        wgsl_type: "Frame",
    },
    Binding {
        index: BINDING_PARTICLES,
        name: "particles",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<Particle>",
    },
    Binding {
        index: BINDING_NODES,
        name: "nodes",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<BvhNode>",
    },
    Binding {
        index: BINDING_LEAF_INDICES,
        name: "leaf_indices",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<u32>",
    },
    Binding {
        index: BINDING_LIGHTS,
        name: "lights",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<Light>",
    },
    Binding {
        index: BINDING_OUTPUT,
        name: "output",
        kind: BindingKind::StorageReadWrite,
        wgsl_type: "array<vec4<f32>>",
    },
    Binding {
        index: BINDING_STATS,
        name: "stats",
        kind: BindingKind::StorageReadWrite,
        wgsl_type: "Stats",
    },
    Binding {
        index: BINDING_ELLIPSOIDS,
        name: "ellipsoids",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<Ellipsoid>",
    },
    Binding {
        index: BINDING_SPLATS,
        name: "splats",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<Splat>",
    },
    Binding {
        index: BINDING_TILE_ENTRIES,
        name: "tile_entries",
        kind: BindingKind::StorageRead,
        wgsl_type: "array<u32>",
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splat_constants_are_the_f32s_of_3dgs_literals() {
        assert_eq!(SPLAT_ALPHA_MAX, 0.99_f32);
        assert_eq!(SPLAT_ALPHA_MIN, 1.0_f32 / 255.0_f32);
        assert_eq!(SPLAT_T_MIN, 0.0001_f32);
    }

    #[test]
    fn bindings_are_numbered_in_order() {
        for (i, b) in BINDINGS.iter().enumerate() {
            assert_eq!(b.index as usize, i, "{}", b.name);
        }
    }
}
