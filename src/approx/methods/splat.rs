//! # `splat` — the forward model of 3D Gaussian splatting's rasteriser
//!
//! What a Gaussian splatting rasteriser draws, docs/design.md §4: each Gaussian projected to
//! a 2D Gaussian by EWA, Σ₂D = J·W·Σ·Wᵀ·Jᵀ with J the perspective Jacobian at the centre (x/z,
//! y/z clamped to `jacobian_clamp`·tan of the half field of view), + `dilation` px² on the
//! diagonal, a footprint binned into 16×16-pixel tiles, one global sort by the centres' view
//! depth, and per pixel, front to back, α = min(`alpha_cap`, o·G₂D), splats with α below the
//! skip threshold skipped, stopping at the first splat that would take T below the stop
//! threshold: L = Σ αᵢTᵢCᵢ + T·L_bg (`shaders/splat.wgsl`). o is the Gaussian's splatting
//! opacity, 1 − exp(−σ·s_min·√(2π)) (docs/design.md §9).
//!
//! Every constant is a parameter, and a preset per rasteriser sets them all
//! (`--rasteriser 3dgs|gsplat`, [`PRESETS`]): `3dgs` (the defaults) is the reference rasteriser
//! (graphdeco-inria `diff-gaussian-rasterization`), `gsplat` is nerfstudio-project `gsplat`
//! 1.5.3 in its classic mode. Where each value is in their code:
//!
//! | parameter | 3DGS | gsplat 1.5.3 |
//! |---|---|---|
//! | `footprint` | 0: radius ⌈3·√λ_max⌉ (`forward.cu` `preprocessCUDA`, `auxiliary.h` `getRect`) | 1: box ⌈3.33·√Σxx⌉ × ⌈3.33·√Σyy⌉ (`ProjectionEWA3DGSFused.cu`, `IntersectTile.cu` `isect_tiles`) |
//! | `alpha_cap` | 0.99 (`forward.cu` `renderCUDA`: `min(0.99f, …)`) | 0.999 (`RasterizeToPixels3DGSFwd.cu`: `min(0.999f, …)`) |
//! | `near` | 0.2, culls depth ≤ 0.2 (`auxiliary.h` `in_frustum`) | 0.01, culls depth < 0.01 (`rendering.py` `near_plane=0.01`) |
//! | `jacobian_clamp` | 1.3 (`forward.cu` `computeCov2D`: `limx = 1.3f * tan_fovx`) | 1.3 (`include/Utils.cuh` `persp_proj`: `lim_x = cx/fx + 0.3f * tan_fovx`, 1.3·tan for a centred principal point) |
//! | `dilation` | 0.3 px² (`forward.cu` `computeCov2D`) | 0.3 px² (`rendering.py` `eps2d=0.3`) |
//! | `skip_denominator` | α < 1/255 (`forward.cu` `renderCUDA`) | α < 1/255 (`RasterizeToPixels3DGSFwd.cu` `ALPHA_THRESHOLD`) |
//! | `stop_below`, `stop_inclusive` | T·(1 − α) < 1e-4 (`forward.cu` `renderCUDA`) | T·(1 − α) ≤ 1e-4 (`RasterizeToPixels3DGSFwd.cu`) |
//!
//! (3DGS in `cuda_rasterizer/`; gsplat in `gsplat/cuda/csrc/`, `gsplat/cuda/include/` and `gsplat/rendering.py`.)
//! gsplat's box shrinks with the opacity (`extend = min(3.33, √(2·ln(255·o)))`); that only
//! leaves out list entries whose α is below 1/255, which the skip drops anyway, so the image is
//! the same and pgt keeps the 3.33σ box.
//!
//! | parameter | default | range | meaning |
//! |---|---|---|---|
//! | `footprint` | 0 | 0..=1 | tiles a splat is listed in: 0, 3DGS's radius ⌈3·√λ_max⌉; 1, gsplat's box ⌈3.33·√Σxx⌉ × ⌈3.33·√Σyy⌉ |
//! | `alpha_cap` | 990000 | 1..=1000000 | the most opacity one splat gives a pixel, in millionths (3DGS 0.99, gsplat 0.999) |
//! | `near` | 200000 | 0..=1000000000 | centres at view depth up to this are culled, in millionths of a scene unit (3DGS 0.2, gsplat 0.01) |
//! | `jacobian_clamp` | 130 | 1..=100000 | x/z and y/z clamped to this many hundredths of tan(fov/2) for the Jacobian (1.3 in both) |
//! | `dilation` | 300 | 0..=1000000 | added to the 2D covariance's diagonal, in thousandths of px² (0.3 in both) |
//! | `skip_denominator` | 255 | 1..=1000000 | splats with α below 1/this at a pixel are skipped (255 in both) |
//! | `stop_below` | 100 | 0..=1000000 | a pixel stops before the splat that takes its transmittance below this, in millionths (1e-4 in both) |
//! | `stop_inclusive` | 0 | 0..=1 | 1: it stops at a transmittance equal to stop_below too (gsplat's ≤); 0: strictly below (3DGS's <) |
//!
//! The projection, binning and sort run **on the CPU in f32** before the dispatch
//! (`approx::splat_tiles`: pgt's dispatch has one per-pixel pass and no place for a
//! preprocessing pass); their time is counted in the method's time. The blending is on the GPU,
//! one invocation per pixel walking its tile's list. Volume mode, emission model, Gaussian
//! particles only (a scene with a constant-density particle is refused by name); spheres and
//! ellipsoids.
//!
//! ```sh
//! pgt approx gaussians.toml --method splat -o splat.exr
//! pgt approx scene.ply --method splat --rasteriser gsplat -o gsplat.exr
//! ```

use super::{ApproxMethod, Computes, Preparation};
use crate::approx::contract::{
    SPLAT_ALPHA_MAX_MILLIONTHS, SPLAT_ALPHA_SKIP_DENOMINATOR, SPLAT_T_MIN_MILLIONTHS,
};
use crate::approx::param_spec::ParamSpec;
use crate::optics::models;

/// The `splat` method (see the module docs).
pub struct Splat;

/// The parameters, in slot order; the defaults are 3DGS's constants (the per-pixel ones from
/// `approx::contract`, their one definition).
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "footprint",
        quiet_default: true,
        default: 0,
        min: 0,
        max: 1,
        doc: "tiles a splat is listed in: 0, 3DGS's radius ⌈3·√λ_max⌉; 1, gsplat's box ⌈3.33·√Σxx⌉ × ⌈3.33·√Σyy⌉",
    },
    ParamSpec {
        name: "alpha_cap",
        quiet_default: true,
        default: SPLAT_ALPHA_MAX_MILLIONTHS,
        min: 1,
        max: 1_000_000,
        doc: "the most opacity one splat gives a pixel, in millionths (3DGS 0.99, gsplat 0.999)",
    },
    ParamSpec {
        name: "near",
        quiet_default: true,
        default: 200_000,
        min: 0,
        max: 1_000_000_000,
        doc: "centres at view depth up to this are culled, in millionths of a scene unit (3DGS 0.2, gsplat 0.01)",
    },
    ParamSpec {
        name: "jacobian_clamp",
        quiet_default: true,
        default: 130,
        min: 1,
        max: 100_000,
        doc: "x/z and y/z clamped to this many hundredths of tan(fov/2) for the Jacobian (1.3 in both)",
    },
    ParamSpec {
        name: "dilation",
        quiet_default: true,
        default: 300,
        min: 0,
        max: 1_000_000,
        doc: "added to the 2D covariance's diagonal, in thousandths of px² (0.3 in both)",
    },
    ParamSpec {
        name: "skip_denominator",
        quiet_default: true,
        default: SPLAT_ALPHA_SKIP_DENOMINATOR,
        min: 1,
        max: 1_000_000,
        doc: "splats with α below 1/this at a pixel are skipped (255 in both)",
    },
    ParamSpec {
        name: "stop_below",
        quiet_default: true,
        default: SPLAT_T_MIN_MILLIONTHS,
        min: 0,
        max: 1_000_000,
        doc: "a pixel stops before the splat that takes its transmittance below this, in millionths (1e-4 in both)",
    },
    ParamSpec {
        name: "stop_inclusive",
        quiet_default: true,
        default: 0,
        min: 0,
        max: 1,
        doc: "1: it stops at a transmittance equal to stop_below too (gsplat's ≤); 0: strictly below (3DGS's <)",
    },
];

/// The rasterisers' presets (`--rasteriser NAME`): the parameter values that differ from the
/// defaults (3DGS's). Sources in the module docs.
pub const PRESETS: &[(&str, &[(&str, u32)])] = &[
    ("3dgs", &[]),
    (
        "gsplat",
        &[
            ("footprint", 1),
            ("alpha_cap", 999_000),
            ("near", 10_000),
            ("stop_inclusive", 1),
        ],
    ),
];

/// The parameter values of the preset `name` (every parameter, in slot order); the error
/// lists the presets.
pub fn preset(name: &str) -> crate::error::Result<Vec<(String, u32)>> {
    let (_, changes) = PRESETS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| {
            crate::error::PgtError::Usage(format!(
                "unknown rasteriser '{name}'; the presets of splat are: {}",
                PRESETS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ))
        })?;
    Ok(PARAMS
        .iter()
        .map(|p| {
            let v = changes
                .iter()
                .find(|(n, _)| *n == p.name)
                .map_or(p.default, |(_, v)| *v);
            (p.name.to_string(), v)
        })
        .collect())
}

impl ApproxMethod for Splat {
    fn name(&self) -> &'static str {
        "splat"
    }
    fn summary(&self) -> &'static str {
        "Gaussian splatting's rasteriser: EWA footprints in 16×16 tiles, one sort by centre depth, α = min(cap, o·G₂D) front to back; constants by preset (3dgs, gsplat); Gaussians only, volume mode"
    }
    fn wgsl_path(&self) -> &'static str {
        "shaders/splat.wgsl"
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../../shaders/splat.wgsl")
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn computes(&self) -> Computes {
        Computes::Volume(&[models::EMISSION])
    }
    fn draws_gaussians(&self) -> bool {
        true
    }
    fn preparation(&self) -> Preparation {
        Preparation {
            splat_tiles: true,
            ..Preparation::default()
        }
    }
}
