//! The one definition of the CPU–GPU contract (docs/design.md §4): every number, binding index and
//! struct that Rust and WGSL share is defined here or in [`super::layout`], and
//! [`wgsl_declarations`] writes the WGSL for it, which [`super::shader`] prepends to every
//! program. `shaders/` uses the names only; `tests/gpu_contract.rs` checks that no file there
//! repeats a number or declaration made here.

use super::layout::{GpuBvhNode, GpuFrame, GpuLight, GpuParticle, GpuStats, WgslStruct};
use std::fmt::Write as _;

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
/// multi-pass method on a Cpu adapter, redoes the pass with less work): half of
/// [`LOOP_LIMIT`], because lavapipe counts the loops of a group of 8 SIMD lanes together, each
/// loop as long as its slowest lane, so its count runs ahead of pgt's (measured: its limit
/// struck when pgt's count read 43,000).
pub const LOOP_BUDGET: u32 = 32768;

/// Side of the square compute workgroup (`@workgroup_size(WORKGROUP_SIDE, WORKGROUP_SIDE, 1)`).
pub const WORKGROUP_SIDE: u32 = 8;

/// Slots for method parameters in `GpuFrame::params` (u32 each, packed in vec4s because a
/// uniform array's stride is 16 bytes).
pub const PARAM_SLOTS: usize = 8;

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

/// The uniform `frame` ([`GpuFrame`]).
pub const BINDING_FRAME: u32 = 0;
/// `particles` ([`GpuParticle`]).
pub const BINDING_PARTICLES: u32 = 1;
/// `nodes` ([`GpuBvhNode`]).
pub const BINDING_NODES: u32 = 2;
/// `leaf_indices` (u32).
pub const BINDING_LEAF_INDICES: u32 = 3;
/// `lights` ([`GpuLight`]).
pub const BINDING_LIGHTS: u32 = 4;
/// `output`, one vec4 per pixel (RGB and 1).
pub const BINDING_OUTPUT: u32 = 5;
/// `stats` ([`GpuStats`]).
pub const BINDING_STATS: u32 = 6;

/// Every binding of group 0, in index order (the pipeline layout and the WGSL come from this).
pub const BINDINGS: [Binding; 7] = [
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
];

/// A WGSL `const` written from a Rust constant.
#[derive(Debug, Clone, PartialEq)]
pub enum WgslConst {
    U32(&'static str, u32),
    F32(&'static str, f32),
}

/// The constants the prelude gets, with the Rust names and values.
pub fn constants() -> Vec<WgslConst> {
    use WgslConst::{F32, U32};
    vec![
        U32("MAX_HITS", MAX_HITS),
        U32("STACK_SIZE", STACK_SIZE),
        F32("T_FAR", T_FAR),
        F32("SIGMA_INFINITE", SIGMA_INFINITE),
        U32("NO_PARTICLE", NO_PARTICLE),
        F32("PI", std::f32::consts::PI),
        U32("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        U32("LIGHT_POINT", LIGHT_POINT),
        U32("FALLOFF_INVERSE_SQUARE", FALLOFF_INVERSE_SQUARE),
        U32("FALLOFF_NONE", FALLOFF_NONE),
        U32("LOOP_LIMIT", LOOP_LIMIT),
        U32("LOOP_LIMIT_REPORT", LOOP_BUDGET),
        U32("WORKGROUP_SIDE", WORKGROUP_SIDE),
        U32("PARAM_SLOTS", PARAM_SLOTS as u32),
    ]
}

impl WgslConst {
    /// The constant's name.
    pub fn name(&self) -> &'static str {
        match self {
            WgslConst::U32(n, _) | WgslConst::F32(n, _) => n,
        }
    }

    /// `const NAME: u32 = 128u;`. f32 values are written with `{:e}`, which round-trips.
    pub fn declaration(&self) -> String {
        match self {
            WgslConst::U32(n, v) => format!("const {n}: u32 = {v}u;"),
            WgslConst::F32(n, v) => format!("const {n}: f32 = {v:e};"),
        }
    }
}

fn struct_declaration<T: WgslStruct>(out: &mut String) {
    let _ = writeln!(out, "struct {} {{", T::WGSL_NAME);
    for (name, ty) in T::WGSL_FIELDS {
        let _ = writeln!(out, "    {name}: {ty},");
    }
    out.push_str("}\n\n");
}

/// Everything the prelude `shaders/common.wgsl` takes from Rust: the constants, the structs of
/// [`super::layout`] and the bindings of group 0.
pub fn wgsl_declarations() -> String {
    let mut out = String::from(
        "// Generated by pgt from src/approx/contract.rs and src/approx/layout.rs: the\n\
         // constants, structs and bindings that Rust and WGSL share (their docs are there).\n\n",
    );
    for c in constants() {
        out.push_str(&c.declaration());
        out.push('\n');
    }
    out.push('\n');
    struct_declaration::<GpuParticle>(&mut out);
    struct_declaration::<GpuBvhNode>(&mut out);
    struct_declaration::<GpuLight>(&mut out);
    struct_declaration::<GpuFrame>(&mut out);
    struct_declaration::<GpuStats>(&mut out);
    for b in BINDINGS {
        let space = match b.kind {
            BindingKind::Uniform => "uniform",
            BindingKind::StorageRead => "storage, read",
            BindingKind::StorageReadWrite => "storage, read_write",
        };
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var<{space}> {}: {};",
            b.index, b.name, b.wgsl_type
        );
    }
    out
}

/// The constants naming a method's parameter slots, `const PARAM_SAMPLES: u32 = 0u;` for the
/// first parameter `samples`: the method reads it as `method_param(PARAM_SAMPLES)`.
pub fn param_declarations<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let mut out = String::from("// Generated by pgt: this method's parameter slots.\n");
    for (slot, name) in names.into_iter().enumerate() {
        let _ = writeln!(
            out,
            "const PARAM_{}: u32 = {slot}u;",
            name.to_ascii_uppercase().replace('-', "_")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_numbered_in_order() {
        for (i, b) in BINDINGS.iter().enumerate() {
            assert_eq!(b.index as usize, i, "{}", b.name);
        }
    }

    #[test]
    fn f32_constants_round_trip_through_their_wgsl_text() {
        for c in constants() {
            if let WgslConst::F32(name, v) = c {
                let text = c.declaration();
                let literal = text
                    .trim_end_matches(';')
                    .rsplit(' ')
                    .next()
                    .unwrap_or_default();
                assert_eq!(literal.parse::<f32>().ok(), Some(v), "{name}: {text}");
            }
        }
    }

    #[test]
    fn parameter_slots_are_named_after_the_parameters() {
        let text = param_declarations(["samples", "n_exact"]);
        assert!(text.contains("const PARAM_SAMPLES: u32 = 0u;"), "{text}");
        assert!(text.contains("const PARAM_N_EXACT: u32 = 1u;"), "{text}");
    }
}
