//! One vertex to one particle: a 3D Gaussian as an ellipsoid (docs/design.md §9, "3D Gaussian
//! splatting PLY": semi-axes k·exp(scale_i), the normalised quaternion, Θmax = sigmoid(opacity),
//! the colour of the reference rasteriser's spherical harmonics), or a row of pgt export as it
//! is.

use super::layout::{Export, Gaussians, Size};
use super::Options;
use crate::error::{Location, PgtError, Result};
use crate::formats::{EllipsoidRecord, ParticleRecord, ShOrder};
use glam::DVec3;
use std::path::Path;

/// The real spherical-harmonics constants of the reference rasteriser's `computeColorFromSH`,
/// by degree: C0 = ½√(1/π); C1 = ½√(3/π); C2 = (½√(15/π), −½√(15/π), ¼√(5/π), −½√(15/π),
/// ¼√(15/π)); C3 = (−¼√(35/(2π)), ½√(105/π), −¼√(21/(2π)), ¼√(7/π), −¼√(21/(2π)), ¼√(105/π),
/// −¼√(35/(2π))). The signs are the rasteriser's (its basis with the Condon–Shortley phase).
pub const SH_C0: f64 = 0.282_094_791_773_878_14;
pub(super) const SH_C1: f64 = 0.488_602_511_902_919_9;
pub(super) const SH_C2: [f64; 5] = [
    1.092_548_430_592_079_2,
    -1.092_548_430_592_079_2,
    0.315_391_565_252_520_05,
    -1.092_548_430_592_079_2,
    0.546_274_215_296_039_6,
];
pub(super) const SH_C3: [f64; 7] = [
    -0.590_043_589_926_643_5,
    2.890_611_442_640_554,
    -0.457_045_799_464_465_8,
    0.373_176_332_590_115_4,
    -0.457_045_799_464_465_8,
    1.445_305_721_320_277,
    -0.590_043_589_926_643_5,
];

/// A vertex of pgt export's layout: its values as they are (the checks every format shares,
/// `super::check_records`, follow).
pub(super) fn exported(at: Location, v: &[f64], l: &Export) -> ParticleRecord {
    let three = |i: [usize; 3]| DVec3::new(v[i[0]], v[i[1]], v[i[2]]);
    let (radius, ellipsoid) = match l.size {
        Size::Radius(r) => (v[r], None),
        Size::Ellipsoid(axes, q) => {
            let semi_axes = three(axes);
            let rotation = q.map(|k| v[k]);
            let e = EllipsoidRecord {
                semi_axes,
                rotation,
            };
            (semi_axes.max_element(), Some(e))
        }
    };
    ParticleRecord {
        center: three(l.position),
        radius,
        color: Some(three(l.rgb)),
        opacity: Some(v[l.opacity]),
        sigma: Some(v[l.sigma]),
        location: at,
        ellipsoid,
    }
}

/// One vertex as an ellipsoid (docs/design.md §9, "3D Gaussian splatting PLY"): semi-axes
/// k·exp(scale_i), the normalised quaternion, Θmax = sigmoid(opacity), the SH colour; with
/// `keep`, its SH coefficients too (DC first, then `f_rest` as RGB vectors), else none.
pub(super) fn gaussian(
    path: &Path,
    i: usize,
    at: Location,
    v: &[f64],
    l: &Gaussians,
    opts: &Options,
    keep: bool,
) -> Result<(ParticleRecord, Vec<DVec3>)> {
    let err = |msg: String| PgtError::Input {
        path: path.to_path_buf(),
        location: at.clone(),
        message: format!("vertex {i}: {msg}"),
    };
    let center = DVec3::new(v[l.position[0]], v[l.position[1]], v[l.position[2]]);
    if !center.is_finite() {
        return Err(err(format!(
            "the position (x, y, z) = {center} is not finite"
        )));
    }
    let mut semi_axes = [0.0; 3];
    for (k, (&s, a)) in l.scale.iter().zip(&mut semi_axes).enumerate() {
        let log = v[s];
        *a = opts.extent * log.exp();
        if !(a.is_finite() && *a >= f64::MIN_POSITIVE) {
            return Err(err(format!(
                "scale_{k} = {log} gives the semi-axis {}·exp({log}) = {a}, not a finite number > 0 (a scale is the log of a standard deviation)",
                opts.extent
            )));
        }
    }
    let q = l.rot.map(|r| v[r]);
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(err(format!(
            "the rotation (rot_0, rot_1, rot_2, rot_3) = {q:?} is not a finite, non-zero quaternion"
        )));
    }
    let logit = v[l.opacity];
    if logit.is_nan() {
        return Err(err("opacity is NaN".to_string()));
    }
    let dc = DVec3::new(v[l.dc[0]], v[l.dc[1]], v[l.dc[2]]);
    if !dc.is_finite() {
        return Err(err(format!("f_dc_0..2 = {dc} is not finite")));
    }
    let rest = if opts.view {
        let rest = sh_rest(v, &l.rest, opts.order);
        if !rest.iter().all(|c| c.is_finite()) {
            return Err(err("an f_rest_* coefficient is not finite".to_string()));
        }
        rest
    } else {
        Vec::new()
    };
    let color = match opts.view_from {
        None => SH_C0 * dc + 0.5,
        Some(camera) => view_color(dc, &rest, center - camera),
    };
    let coefficients = if keep {
        std::iter::once(dc).chain(rest).collect()
    } else {
        Vec::new()
    };
    let semi_axes = DVec3::from(semi_axes);
    let record = ParticleRecord {
        center,
        radius: semi_axes.max_element(),
        color: Some(color.max(DVec3::ZERO)),
        opacity: Some(sigmoid(logit)),
        sigma: None,
        location: at,
        ellipsoid: Some(EllipsoidRecord {
            semi_axes,
            rotation: q.map(|c| c / norm),
        }),
    };
    Ok((record, coefficients))
}

/// α = 1/(1 + e^(−x)) for a logit x (±∞ give 1 and 0).
pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The higher SH coefficients of a vertex as RGB vectors, coefficient 1 first (index 0).
pub(super) fn sh_rest(v: &[f64], rest: &[usize], order: ShOrder) -> Vec<DVec3> {
    let m = rest.len() / 3;
    (0..m)
        .map(|j| {
            let at = |c: usize| match order {
                ShOrder::ChannelMajor => v[rest[c * m + j]],
                ShOrder::CoefficientMajor => v[rest[3 * j + c]],
            };
            DVec3::new(at(0), at(1), at(2))
        })
        .collect()
}

/// The view-dependent colour of the reference rasteriser's `computeColorFromSH` (before its
/// clamp at 0): 0.5 + Σ C_lm·Y_lm(d)·sh_lm with d the unit direction from the camera to the
/// centre and `rest` the coefficients of degree 1 and up (3, 8 or 15 of them: degree 1, 2, 3).
/// A camera at the centre has no direction: the DC term alone.
pub fn view_color(dc: DVec3, rest: &[DVec3], direction: DVec3) -> DVec3 {
    let mut c = SH_C0 * dc;
    let len = direction.length();
    if rest.len() < 3 || !(len > 0.0 && len.is_finite()) {
        return c + 0.5;
    }
    let d = direction / len;
    let (x, y, z) = (d.x, d.y, d.z);
    c += -SH_C1 * y * rest[0] + SH_C1 * z * rest[1] - SH_C1 * x * rest[2];
    if rest.len() >= 8 {
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, yz, xz) = (x * y, y * z, x * z);
        c += SH_C2[0] * xy * rest[3]
            + SH_C2[1] * yz * rest[4]
            + SH_C2[2] * (2.0 * zz - xx - yy) * rest[5]
            + SH_C2[3] * xz * rest[6]
            + SH_C2[4] * (xx - yy) * rest[7];
        if rest.len() >= 15 {
            c += SH_C3[0] * y * (3.0 * xx - yy) * rest[8]
                + SH_C3[1] * xy * z * rest[9]
                + SH_C3[2] * y * (4.0 * zz - xx - yy) * rest[10]
                + SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * rest[11]
                + SH_C3[4] * x * (4.0 * zz - xx - yy) * rest[12]
                + SH_C3[5] * z * (xx - yy) * rest[13]
                + SH_C3[6] * x * (xx - 3.0 * yy) * rest[14];
        }
    }
    c + 0.5
}
