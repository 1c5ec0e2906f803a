//! The WGSL of the GPU reference and the layout it shares with Rust (docs/design.md §12): the
//! constants, the buffers' strides and offsets, the structs and the bindings are generated here
//! and prepended to `shaders/f64_math.wgsl`, `shaders/nearest_events.wgsl` (the batch and its
//! traversal, shared with the approximations) and `shaders/reference_emission.wgsl`, so the host
//! code below and the shader read one definition.

use super::math::{EXPM1_ULPS, EXP_ULPS, F64_MATH_WGSL};
use crate::approx::contract::STACK_SIZE;
use crate::approx::layout::GpuBvhNode;
use crate::approx::shader::{ShaderPart, ShaderProgram, NEAREST_EVENTS};
use crate::approx::wgsl::struct_declaration;
use bytemuck::{Pod, Zeroable};
use std::borrow::Cow;
use std::fmt::Write;

/// `shaders/reference_emission.wgsl`.
pub const EMISSION_WGSL: &str = include_str!("../../../shaders/reference_emission.wgsl");

/// The entry point of the GPU reference.
pub const ENTRY_POINT: &str = "reference_main";

/// Events one BVH traversal keeps (the batch).
pub const BATCH: u32 = 32;
/// The most particles a ray may be inside at once; more is refused by name.
pub const INSIDE_MAX: u32 = 64;
/// Invocations per workgroup (one ray each, 1D).
pub const WORKGROUP: u32 = 64;

/// `particle_data`: per particle centre (3), radius, σ (−1 for Θmax = 1), colour (3) and the
/// index of its ellipsoid in `ellipsoid_data` (−1 for a sphere), as f64.
pub const PARTICLE_STRIDE: usize = 9;
pub const P_RADIUS: usize = 3;
pub const P_SIGMA: usize = 4;
pub const P_COLOR: usize = 5;
pub const P_SHAPE: usize = 8;
/// `ellipsoid_data`: the rows of M = S⁻¹Rᵀ (9) and its Frobenius norm.
pub const ELLIPSOID_STRIDE: usize = 10;

/// `scene_data`: the rays' origin, that origin relative to the camera (the BVH boxes are
/// camera-relative), the background, Cmax (per channel the largest colour or background), the
/// total finite σ of the particles and how far the rays' computed unit directions may lie from
/// the exact ones.
pub const SCENE_ORIGIN: usize = 0;
pub const SCENE_RELATIVE_ORIGIN: usize = 3;
pub const SCENE_BACKGROUND: usize = 6;
pub const SCENE_CMAX: usize = 9;
pub const SCENE_SIGMA_TOTAL: usize = 12;
pub const SCENE_DIRECTION_ERROR: usize = 13;
pub const SCENE_LEN: usize = 14;

/// `state`, per ray: radiance (3), its rounding bound (3), T, T's relative error bound, the last
/// event's t and key, the summed optical-depth uncertainty of the events taken, the status.
pub const STATE_STRIDE: usize = 12;
pub const STATE_RADIANCE: usize = 0;
pub const STATE_ERROR: usize = 3;
pub const STATE_TRANSMITTANCE: usize = 6;
pub const STATE_TRANSMITTANCE_REL: usize = 7;
pub const STATE_T_LAST: usize = 8;
pub const STATE_KEY_LAST: usize = 9;
pub const STATE_DEPTH: usize = 10;
pub const STATE_STATUS: usize = 11;

/// A ray's status in `state`.
pub const STATUS_RUNNING: u32 = 0;
pub const STATUS_DONE: u32 = 1;
pub const STATUS_INSIDE_OVERFLOW: u32 = 2;
pub const STATUS_LOOP_LIMITED: u32 = 3;

/// The factor on every first-order bound of a chord end that covers the second-order terms.
pub const SAFETY: f64 = 1.25;
/// A ray whose transmittance falls below this stops; what lies behind is bounded (Cmax·T).
pub const T_STOP: f64 = 8.470329472543003e-22; // 2^-70
/// A depth that stands for "unbounded" (an uncertain Θmax = 1 ghost).
pub const HUGE: f64 = 1e300;

// Every offset lies inside its stride.
const _: () = assert!(P_SHAPE < PARTICLE_STRIDE && P_COLOR + 3 <= PARTICLE_STRIDE);
const _: () = assert!(STATE_STATUS < STATE_STRIDE && SCENE_SIGMA_TOTAL < SCENE_LEN);

/// The uniform `params`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct RefParams {
    /// Rays in this dispatch.
    pub ray_count: u32,
    pub particle_count: u32,
    /// Loop iterations after which a ray stops at the end of a batch and waits for the next
    /// pass.
    pub pass_yield: u32,
    /// Loop iterations of one pass beyond which a ray is reported (lavapipe's loop limit).
    pub loop_budget: u32,
}

/// (binding, name, address space, WGSL type) of group 0.
pub const BINDINGS: [(u32, &str, &str, &str); 9] = [
    (0, "params", "uniform", "RefParams"),
    (1, "scene_data", "storage, read", "array<f64>"),
    (2, "particle_data", "storage, read", "array<f64>"),
    (3, "ellipsoid_data", "storage, read", "array<f64>"),
    (4, "nodes", "storage, read", "array<BvhNode>"),
    (5, "leaf_indices", "storage, read", "array<u32>"),
    (6, "rays", "storage, read", "array<f64>"),
    (7, "state", "storage, read_write", "array<f64>"),
    (8, "counters", "storage, read_write", "RefCounters"),
];

/// The generated part of a GPU reference program (this one's and the Gaussian one's): a header
/// naming its source, the u32 and f64 constants, `BvhNode`, the program's own `structs` (its
/// params and counters) and the bindings of group 0.
pub(super) fn generated_declarations(
    source: &str,
    u32s: &[(&str, usize)],
    f64s: &[(&str, f64)],
    structs: &str,
    bindings: &[(u32, &str, &str, &str)],
) -> String {
    let mut out = format!("// Generated by pgt from {source} and math.rs (docs there).\n\n");
    for (name, v) in u32s {
        let _ = writeln!(out, "const {name}: u32 = {v}u;");
    }
    for (name, v) in f64s {
        let _ = writeln!(out, "const {name}: f64 = {v:e}lf;");
    }
    out.push('\n');
    struct_declaration::<GpuBvhNode>(&mut out);
    out.push_str(structs);
    for (index, name, space, ty) in bindings {
        let _ = writeln!(
            out,
            "@group(0) @binding({index}) var<{space}> {name}: {ty};"
        );
    }
    out
}

/// A GPU reference program: the generated declarations of `source`, the f64 functions, the
/// shared traversal (`shaders/nearest_events.wgsl`) and the renderer `file` with its `text`.
pub(super) fn f64_program(
    source: &str,
    declarations: String,
    file: &str,
    text: &'static str,
) -> ShaderProgram {
    ShaderProgram::from_parts(vec![
        ShaderPart {
            name: format!("<generated from {source}>"),
            text: Cow::Owned(declarations),
        },
        ShaderPart {
            name: "shaders/f64_math.wgsl".into(),
            text: Cow::Borrowed(F64_MATH_WGSL),
        },
        NEAREST_EVENTS.part(),
        ShaderPart {
            name: file.to_string(),
            text: Cow::Borrowed(text),
        },
    ])
}

/// The declarations the shader takes from Rust.
pub fn declarations() -> String {
    let u32s: [(&str, usize); 29] = [
        ("REF_BATCH", BATCH as usize),
        ("REF_INSIDE_MAX", INSIDE_MAX as usize),
        ("REF_WORKGROUP", WORKGROUP as usize),
        ("STACK_SIZE", STACK_SIZE as usize),
        ("REF_PARTICLE_STRIDE", PARTICLE_STRIDE),
        ("REF_P_RADIUS", P_RADIUS),
        ("REF_P_SIGMA", P_SIGMA),
        ("REF_P_COLOR", P_COLOR),
        ("REF_P_SHAPE", P_SHAPE),
        ("REF_ELLIPSOID_STRIDE", ELLIPSOID_STRIDE),
        ("SCENE_ORIGIN", SCENE_ORIGIN),
        ("SCENE_RELATIVE_ORIGIN", SCENE_RELATIVE_ORIGIN),
        ("SCENE_BACKGROUND", SCENE_BACKGROUND),
        ("SCENE_CMAX", SCENE_CMAX),
        ("SCENE_SIGMA_TOTAL", SCENE_SIGMA_TOTAL),
        ("SCENE_DIRECTION_ERROR", SCENE_DIRECTION_ERROR),
        ("STATE_STRIDE", STATE_STRIDE),
        ("STATE_RADIANCE", STATE_RADIANCE),
        ("STATE_ERROR", STATE_ERROR),
        ("STATE_TRANSMITTANCE", STATE_TRANSMITTANCE),
        ("STATE_TRANSMITTANCE_REL", STATE_TRANSMITTANCE_REL),
        ("STATE_T_LAST", STATE_T_LAST),
        ("STATE_KEY_LAST", STATE_KEY_LAST),
        ("STATE_DEPTH", STATE_DEPTH),
        ("STATE_STATUS", STATE_STATUS),
        ("STATUS_RUNNING", STATUS_RUNNING as usize),
        ("STATUS_DONE", STATUS_DONE as usize),
        ("STATUS_INSIDE_OVERFLOW", STATUS_INSIDE_OVERFLOW as usize),
        ("STATUS_LOOP_LIMITED", STATUS_LOOP_LIMITED as usize),
    ];
    let f64s: [(&str, f64); 5] = [
        ("REF_SAFETY", SAFETY),
        ("REF_T_STOP", T_STOP),
        ("REF_HUGE", HUGE),
        ("REF_EXP_ULPS", EXP_ULPS),
        ("REF_EXPM1_ULPS", EXPM1_ULPS),
    ];
    generated_declarations(
        "src/reference/gpu/program.rs",
        &u32s,
        &f64s,
        "struct RefParams {\n    ray_count: u32,\n    particle_count: u32,\n    pass_yield: u32,\n    loop_budget: u32,\n}\n\n\
         struct RefCounters {\n    running: atomic<u32>,\n}\n\n",
        &BINDINGS,
    )
}

/// The GPU reference's program: the declarations, the f64 functions, the renderer.
pub fn program() -> ShaderProgram {
    f64_program(
        "src/reference/gpu/program.rs",
        declarations(),
        "shaders/reference_emission.wgsl",
        EMISSION_WGSL,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_validates_with_f64() {
        let caps = naga::valid::Capabilities::FLOAT64;
        if let Err(e) = program().validate_with(caps) {
            panic!("{e}");
        }
    }
}
