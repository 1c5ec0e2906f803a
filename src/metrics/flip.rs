//! FLIP, NVIDIA's perceptual difference metric (Andersson et al. 2020; HDR-FLIP 2021).
//!
//! [`flip_ldr`] and [`flip_hdr`] run pgt's own f32 implementation ([`super::flip_float`]) on the
//! linear images: LDR-FLIP clamps them to [0, 1]; HDR-FLIP (Andersson et al. 2021) picks an
//! exposure range from the reference's luminance, exposes and tone-maps (ACES) both images at
//! each exposure, compares them with LDR-FLIP and keeps the per-pixel maximum. It follows
//! NVIDIA's C++ (`FLIP.h`, `image.h::computeExposures`) step for step, in float throughout, as
//! NVIDIA's tool does.
//!
//! The `nv-flip` bindings to NVIDIA's C++ LDR-FLIP are kept as the oracle ([`flip_srgb8`],
//! [`flip_ldr_8bit`], [`flip_hdr_8bit`]): they only accept 8-bit sRGB, so each image (each
//! tone-mapped exposure) was quantised to 8 bits, which pgt no longer does; and they are
//! single-threaded (`cargo bench --bench compare`, benches/compare.rs, times both).
//!
//! Checked against `flip-evaluator` (pip, `evaluate(ref, test, "LDR")` and `"HDR"`) on committed
//! vectors in tests/compare/flip.rs, and against nv-flip on identical 8-bit input in
//! `flip_float`'s tests.

use crate::image_io::{linear_to_srgb8, RgbImage};

/// FLIP's default viewing condition: 0.7 m from a 0.7 m wide 3840-pixel monitor, about 67
/// pixels per degree.
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The FLIP error of an image pair.
#[derive(Debug, Clone)]
pub struct Flip {
    /// Mean of the map (the number FLIP reports).
    pub mean: f64,
    /// Per-pixel FLIP error in [0, 1], row-major.
    pub map: Vec<f32>,
    pub pixels_per_degree: f32,
    /// HDR-FLIP only: the exposures (stops) compared, first to last, and how many.
    pub exposures: Option<(f32, f32, usize)>,
}

/// Why FLIP was not computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlipError {
    #[error("FLIP: inputs have values above 1 (largest {0}); LDR-FLIP would need clamping; use HDR-FLIP")]
    Hdr(f32),
    #[error("FLIP: images differ in size")]
    SizeMismatch,
    #[error("FLIP: image too large for the nv-flip bindings (3·width·height must fit in 32 bits)")]
    TooLarge,
    #[error("HDR-FLIP: cannot choose exposures: the reference's {0} luminance is 0 (pass the exposure range explicitly)")]
    NoExposureRange(&'static str),
    #[error("HDR-FLIP: exposure range must be finite with start <= stop, got {0} .. {1}")]
    BadExposureRange(f32, f32),
}

/// LDR-FLIP of two linear images whose values lie in [0, 1] (negative values count as 0),
/// evaluated in float ([`super::flip_float`]).
pub fn flip_ldr(
    reference: &RgbImage,
    approximation: &RgbImage,
    pixels_per_degree: f32,
) -> Result<Flip, FlipError> {
    check_sizes(reference, approximation)?;
    let largest = largest_value(reference, approximation);
    if largest > 1.0 {
        return Err(FlipError::Hdr(largest));
    }
    let map = super::flip_float::flip_max_map(
        &reference.pixels,
        &approximation.pixels,
        reference.width,
        reference.height,
        pixels_per_degree,
        &[|p: [f32; 3]| p.map(|v| v.clamp(0.0, 1.0))],
    );
    Ok(Flip {
        mean: mean_of(&map),
        map,
        pixels_per_degree,
        exposures: None,
    })
}

/// The size checks shared by every FLIP entry point.
fn check_sizes(reference: &RgbImage, approximation: &RgbImage) -> Result<(), FlipError> {
    if reference.width != approximation.width || reference.height != approximation.height {
        return Err(FlipError::SizeMismatch);
    }
    // nv-flip computes width·height·3 in u32; pgt keeps the same limit for every path.
    if (reference.width as u64) * (reference.height as u64) * 3 > u32::MAX as u64 {
        return Err(FlipError::TooLarge);
    }
    Ok(())
}

fn largest_value(reference: &RgbImage, approximation: &RgbImage) -> f32 {
    reference
        .pixels
        .iter()
        .chain(&approximation.pixels)
        .flatten()
        .fold(0.0f32, |m, &v| m.max(v))
}

/// Mean of a FLIP map (the number FLIP reports), summed in f64.
fn mean_of(map: &[f32]) -> f64 {
    map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64
}

/// LDR-FLIP through nv-flip: each linear image encoded to 8-bit sRGB first (the oracle and the
/// former implementation; negative values are clamped to 0 by the encoding).
pub fn flip_ldr_8bit(
    reference: &RgbImage,
    approximation: &RgbImage,
    pixels_per_degree: f32,
) -> Result<Flip, FlipError> {
    check_sizes(reference, approximation)?;
    let largest = largest_value(reference, approximation);
    if largest > 1.0 {
        return Err(FlipError::Hdr(largest));
    }
    let encode = |img: &RgbImage| -> Vec<u8> {
        img.pixels
            .iter()
            .flat_map(|p| p.map(|v| linear_to_srgb8(v, 1.0)))
            .collect()
    };
    let (w, h) = (reference.width, reference.height);
    let map = flip_srgb8(
        w,
        h,
        &encode(reference),
        &encode(approximation),
        pixels_per_degree,
    );
    Ok(Flip {
        mean: mean_of(&map),
        map,
        pixels_per_degree,
        exposures: None,
    })
}

/// Rows of one band of the parallel FLIP evaluation.
const FLIP_BAND: u32 = 128;

/// How far (in pixels) one FLIP pixel sees: the spatial (CSF) filter radius plus the feature
/// filter radius of NVIDIA's code (`calculateSpatialFilterRadius`: ⌈3·√(0.04/(2π²))·ppd⌉, the
/// largest Gaussian scale b1.z = 0.04; feature filter ⌈3·0.5·0.082·ppd⌉), plus a margin.
/// Their sum bounds the reach of the two passes even if they were chained.
pub fn flip_reach(pixels_per_degree: f32) -> u32 {
    let pi_sq = std::f32::consts::PI * std::f32::consts::PI;
    let spatial = (3.0 * (0.04f32 / (2.0 * pi_sq)).sqrt() * pixels_per_degree).ceil();
    let feature = (3.0 * 0.5 * 0.082f32 * pixels_per_degree).ceil();
    (spatial + feature) as u32 + 2
}

/// LDR-FLIP map of two 8-bit sRGB images (row-major RGB bytes), evaluated in parallel bands of
/// rows: each band is run by nv-flip with [`flip_reach`] extra rows above and below, and only its
/// own rows are kept. FLIP is local (no image-wide statistics), so the map equals the one of a
/// single call (tests/compare/flip.rs checks bit equality); nv-flip itself is single-threaded.
pub fn flip_srgb8(w: u32, h: u32, reference: &[u8], approximation: &[u8], ppd: f32) -> Vec<f32> {
    use rayon::prelude::*;
    let halo = flip_reach(ppd);
    let row = 3 * w as usize;
    let bands: Vec<u32> = (0..h).step_by(FLIP_BAND as usize).collect();
    let parts: Vec<Vec<f32>> = bands
        .par_iter()
        .map(|&y0| {
            let y1 = (y0 + FLIP_BAND).min(h);
            let (lo, hi) = (y0.saturating_sub(halo), (y1 + halo).min(h));
            let rows = lo as usize * row..hi as usize * row;
            let r = nv_flip::FlipImageRgb8::with_data(w, hi - lo, &reference[rows.clone()]);
            let a = nv_flip::FlipImageRgb8::with_data(w, hi - lo, &approximation[rows]);
            let map = nv_flip::flip(r, a, ppd).to_vec();
            let skip = ((y0 - lo) * w) as usize;
            map[skip..skip + ((y1 - y0) * w) as usize].to_vec()
        })
        .collect();
    parts.concat()
}

/// Single-call LDR-FLIP (no bands), the reference that [`flip_srgb8`] is tested against.
pub fn flip_srgb8_whole(
    w: u32,
    h: u32,
    reference: &[u8],
    approximation: &[u8],
    ppd: f32,
) -> Vec<f32> {
    let r = nv_flip::FlipImageRgb8::with_data(w, h, reference);
    let a = nv_flip::FlipImageRgb8::with_data(w, h, approximation);
    nv_flip::flip(r, a, ppd).to_vec()
}

/// ACES filmic tone mapper of HDR-FLIP (NVIDIA `tensor.h`, `ToneMappingCoefficients[1]`; the
/// 0.6 factors cancel the curve's pre-exposure): t(x) = (a·x² + b·x + c) / (d·x² + e·x + f).
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

/// Luminance of linear sRGB (Rec. 709 weights), in f32 as NVIDIA's code computes it.
fn luminance(p: &[f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// HDR-FLIP's automatic exposure range (NVIDIA `computeExposures`, FLIP 1.7): the exposure at
/// which the reference's maximum luminance, and the one at which its median luminance, tone-map
/// to 0.85.
pub fn exposure_range(reference: &RgbImage) -> Result<(f32, f32), FlipError> {
    let t = 0.85f32;
    let (a, b, c) = (
        ACES[0] - t * ACES[3],
        ACES[1] - t * ACES[4],
        ACES[2] - t * ACES[5],
    );
    // a·x² + b·x + c = 0, the larger root (sharedflip.h::solveSecondDegree).
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        let d2 = ((d1 * d1) - (c / a)).sqrt();
        d1 + d2
    };
    let mut lum: Vec<f32> = reference.pixels.iter().map(luminance).collect();
    if lum.len() < 2 {
        return Err(FlipError::NoExposureRange("median"));
    }
    let y_max = lum.iter().fold(-1e30f32, |m, &v| m.max(v));
    // FLIP 1.7 (flip-evaluator) takes the element at n/2 of the sorted luminances; the older C++
    // bundled with nv-flip averaged elements n/2 − 1 and n/2. pgt follows 1.7. Selected, not
    // sorted: the same element in linear time (a full sort of a 4K image's luminances took
    // 0.4 s on one core).
    let middle = lum.len() / 2;
    let (_, &mut y_median, _) = lum.select_nth_unstable_by(middle, |p, q| p.total_cmp(q));
    if y_max <= 0.0 {
        return Err(FlipError::NoExposureRange("maximum"));
    }
    if y_median <= 0.0 {
        return Err(FlipError::NoExposureRange("median"));
    }
    Ok(((x_max / y_max).log2(), (x_max / y_median).log2()))
}

/// HDR-FLIP's exposures: (start, stop, count, step) from the given or the automatic range.
fn exposures_of(
    reference: &RgbImage,
    exposures: Option<(f32, f32)>,
) -> Result<(f32, f32, usize, f32), FlipError> {
    let (start, stop) = match exposures {
        Some(r) => r,
        None => exposure_range(reference)?,
    };
    if !(start.is_finite() && stop.is_finite() && start <= stop) {
        return Err(FlipError::BadExposureRange(start, stop));
    }
    // FLIP.h: at least two exposures, about one per stop.
    let count = (stop - start).ceil().max(2.0) as usize;
    let step = (stop - start) / (count - 1) as f32;
    Ok((start, stop, count, step))
}

/// ACES tone mapping of one linear value at exposure multiplier `m`, clamped to [0, 1]
/// (negative values count as 0).
#[inline]
fn tone_map(v: f32, m: f32) -> f32 {
    let x = v.max(0.0) * m;
    let t = ((x * x) * ACES[0] + x * ACES[1] + ACES[2]) / (x * x * ACES[3] + x * ACES[4] + ACES[5]);
    t.clamp(0.0, 1.0)
}

/// HDR-FLIP of two linear images (negative values count as 0). `exposures`: the (start, stop)
/// range in stops; `None` picks it from the reference as NVIDIA's FLIP does. Each exposure is
/// tone-mapped and compared in float ([`super::flip_float`]); bands of rows run in parallel.
pub fn flip_hdr(
    reference: &RgbImage,
    approximation: &RgbImage,
    pixels_per_degree: f32,
    exposures: Option<(f32, f32)>,
) -> Result<Flip, FlipError> {
    check_sizes(reference, approximation)?;
    let (start, stop, count, step) = exposures_of(reference, exposures)?;
    let transforms: Vec<_> = (0..count)
        .map(|i| {
            let m = 2f32.powf(start + i as f32 * step);
            move |p: [f32; 3]| p.map(|v| tone_map(v, m))
        })
        .collect();
    let map = super::flip_float::flip_max_map(
        &reference.pixels,
        &approximation.pixels,
        reference.width,
        reference.height,
        pixels_per_degree,
        &transforms,
    );
    Ok(Flip {
        mean: mean_of(&map),
        map,
        pixels_per_degree,
        exposures: Some((start, stop, count)),
    })
}

/// HDR-FLIP through nv-flip, each tone-mapped exposure quantised to 8-bit sRGB (the former
/// implementation, kept to measure what the quantisation cost and how much faster pgt's own is).
pub fn flip_hdr_8bit(
    reference: &RgbImage,
    approximation: &RgbImage,
    pixels_per_degree: f32,
    exposures: Option<(f32, f32)>,
) -> Result<Flip, FlipError> {
    use rayon::prelude::*;
    check_sizes(reference, approximation)?;
    let (start, stop, count, step) = exposures_of(reference, exposures)?;
    let (w, h) = (reference.width, reference.height);
    let tone_mapped = |img: &RgbImage, exposure: f32| -> Vec<u8> {
        let m = 2f32.powf(exposure);
        img.pixels
            .iter()
            .flat_map(|p| p.map(|v| linear_to_srgb8(tone_map(v, m), 1.0)))
            .collect()
    };
    let maps: Vec<Vec<f32>> = (0..count)
        .into_par_iter()
        .map(|i| {
            let exposure = start + i as f32 * step;
            flip_srgb8(
                w,
                h,
                &tone_mapped(reference, exposure),
                &tone_mapped(approximation, exposure),
                pixels_per_degree,
            )
        })
        .collect();
    let mut map = maps[0].clone();
    for m in &maps[1..] {
        for (d, s) in map.iter_mut().zip(m) {
            *d = d.max(*s);
        }
    }
    Ok(Flip {
        mean: mean_of(&map),
        map,
        pixels_per_degree,
        exposures: Some((start, stop, count)),
    })
}
