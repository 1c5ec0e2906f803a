//! The Rust structs of `src/approx/layout.rs` and the WGSL structs generated from them
//! (`pgt::approx::wgsl::wgsl_declarations`, prepended to `shaders/common.wgsl`) must agree
//! byte for byte (docs/design.md §4): generating the text does not make WGSL's alignment rules
//! Rust's. naga computes the WGSL layout; this compares every named member's offset and every
//! struct's size with `offset_of!` and `size_of`. No GPU needed.

use pgt::approx::layout::{
    GpuBvhNode, GpuEllipsoid, GpuFrame, GpuLight, GpuParticle, GpuSplat, GpuStats,
};
use pgt::approx::shader::prelude_source;
use std::mem::{offset_of, size_of};

/// (member name, offset) of a WGSL struct, and its size, as naga lays it out.
fn wgsl_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let m = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect();
                return (m, *span);
            }
        }
    }
    panic!("struct {name} not found in the prelude");
}

/// Compares the named (non-padding) members and the size; padding members must exist on both
/// sides only as far as the size says.
fn check(module: &naga::Module, name: &str, rust_size: usize, rust: &[(&str, usize)]) {
    let (members, size) = wgsl_layout(module, name);
    assert_eq!(
        size as usize, rust_size,
        "{name}: WGSL size {size}, Rust size {rust_size}"
    );
    let named: Vec<&(String, u32)> = members
        .iter()
        .filter(|(n, _)| !n.starts_with('_'))
        .collect();
    assert_eq!(
        named.len(),
        rust.len(),
        "{name}: WGSL has members {named:?}, the Rust check lists {rust:?}"
    );
    for ((wn, wo), (rn, ro)) in named.iter().zip(rust) {
        assert_eq!(wn, rn, "{name}: member order differs");
        assert_eq!(
            *wo as usize, *ro,
            "{name}.{wn}: WGSL offset {wo}, Rust offset {ro}"
        );
    }
}

fn particle_members() -> Vec<(&'static str, usize)> {
    vec![
        ("center", offset_of!(GpuParticle, center)),
        ("radius", offset_of!(GpuParticle, radius)),
        ("color", offset_of!(GpuParticle, color)),
        ("sigma", offset_of!(GpuParticle, sigma)),
        ("albedo", offset_of!(GpuParticle, albedo)),
        ("ks", offset_of!(GpuParticle, ks)),
        ("shininess", offset_of!(GpuParticle, shininess)),
        ("ellipsoid", offset_of!(GpuParticle, ellipsoid)),
        ("profile", offset_of!(GpuParticle, profile)),
        ("opacity", offset_of!(GpuParticle, opacity)),
    ]
}

#[test]
fn rust_and_wgsl_struct_layouts_agree() {
    let module = naga::front::wgsl::parse_str(&prelude_source()).expect("the prelude parses");
    check(
        &module,
        "Particle",
        size_of::<GpuParticle>(),
        &particle_members(),
    );
    check(
        &module,
        "Ellipsoid",
        size_of::<GpuEllipsoid>(),
        &[
            ("row_x", offset_of!(GpuEllipsoid, row_x)),
            ("semi_x", offset_of!(GpuEllipsoid, semi_x)),
            ("row_y", offset_of!(GpuEllipsoid, row_y)),
            ("semi_y", offset_of!(GpuEllipsoid, semi_y)),
            ("row_z", offset_of!(GpuEllipsoid, row_z)),
            ("semi_z", offset_of!(GpuEllipsoid, semi_z)),
        ],
    );
    check(
        &module,
        "BvhNode",
        size_of::<GpuBvhNode>(),
        &[
            ("min", offset_of!(GpuBvhNode, min)),
            ("first", offset_of!(GpuBvhNode, first)),
            ("max", offset_of!(GpuBvhNode, max)),
            ("count", offset_of!(GpuBvhNode, count)),
        ],
    );
    check(
        &module,
        "Light",
        size_of::<GpuLight>(),
        &[
            ("vector", offset_of!(GpuLight, vector)),
            ("kind", offset_of!(GpuLight, kind)),
            ("power", offset_of!(GpuLight, power)),
            ("falloff", offset_of!(GpuLight, falloff)),
        ],
    );
    check(
        &module,
        "Frame",
        size_of::<GpuFrame>(),
        &[
            ("forward", offset_of!(GpuFrame, forward)),
            ("tan_half_fov", offset_of!(GpuFrame, tan_half_fov)),
            ("right", offset_of!(GpuFrame, right)),
            ("width", offset_of!(GpuFrame, width)),
            ("up", offset_of!(GpuFrame, up)),
            ("height", offset_of!(GpuFrame, height)),
            ("background", offset_of!(GpuFrame, background)),
            ("light_count", offset_of!(GpuFrame, light_count)),
            ("particle_count", offset_of!(GpuFrame, particle_count)),
            ("light_weight", offset_of!(GpuFrame, light_weight)),
            ("ambient", offset_of!(GpuFrame, ambient)),
            ("lit", offset_of!(GpuFrame, lit)),
            ("camera_position", offset_of!(GpuFrame, camera_position)),
            ("pair_begin", offset_of!(GpuFrame, pair_begin)),
            ("pair_end", offset_of!(GpuFrame, pair_end)),
            ("row_begin", offset_of!(GpuFrame, row_begin)),
            ("row_count", offset_of!(GpuFrame, row_count)),
            ("pinhole", offset_of!(GpuFrame, pinhole)),
            ("splat_alpha_cap", offset_of!(GpuFrame, splat_alpha_cap)),
            ("splat_alpha_skip", offset_of!(GpuFrame, splat_alpha_skip)),
            ("splat_stop_below", offset_of!(GpuFrame, splat_stop_below)),
            (
                "splat_stop_inclusive",
                offset_of!(GpuFrame, splat_stop_inclusive),
            ),
            ("params", offset_of!(GpuFrame, params)),
            ("fx", offset_of!(GpuFrame, fx)),
            ("fy", offset_of!(GpuFrame, fy)),
            ("cx", offset_of!(GpuFrame, cx)),
            ("cy", offset_of!(GpuFrame, cy)),
        ],
    );
    check(
        &module,
        "Splat",
        size_of::<GpuSplat>(),
        &[
            ("mean_x", offset_of!(GpuSplat, mean_x)),
            ("mean_y", offset_of!(GpuSplat, mean_y)),
            ("conic_a", offset_of!(GpuSplat, conic_a)),
            ("conic_b", offset_of!(GpuSplat, conic_b)),
            ("conic_c", offset_of!(GpuSplat, conic_c)),
            ("opacity", offset_of!(GpuSplat, opacity)),
            ("depth", offset_of!(GpuSplat, depth)),
            ("particle", offset_of!(GpuSplat, particle)),
        ],
    );
    check(
        &module,
        "Stats",
        size_of::<GpuStats>(),
        &[
            ("hit_overflows", offset_of!(GpuStats, hit_overflows)),
            ("loop_limited", offset_of!(GpuStats, loop_limited)),
            ("more_work", offset_of!(GpuStats, more_work)),
            (
                "max_loop_iterations",
                offset_of!(GpuStats, max_loop_iterations),
            ),
        ],
    );
}

#[test]
fn the_check_catches_a_shifted_member() {
    // The subtle mismatch: `profile` moved in front of `ellipsoid`. Same size, same types, two
    // u32 members swapped (52 and 56); the check must still fail.
    let prelude = prelude_source();
    let wrong = prelude.replace(
        "    ellipsoid: u32,\n    profile: u32,",
        "    profile: u32,\n    ellipsoid: u32,",
    );
    assert_ne!(wrong, prelude, "the replacement must apply");
    let module = naga::front::wgsl::parse_str(&wrong).expect("still valid WGSL");
    assert_eq!(
        wgsl_layout(&module, "Particle").1 as usize,
        size_of::<GpuParticle>()
    );
    let result = std::panic::catch_unwind(|| {
        check(
            &module,
            "Particle",
            size_of::<GpuParticle>(),
            &particle_members(),
        )
    });
    assert!(result.is_err());
}
