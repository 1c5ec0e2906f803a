//! 3D Gaussian splatting's tensors as pgt's particles (`pgt.Scene.from_gaussians`): the
//! activations of the 3DGS PLY reader (`pgt::formats::ply`, docs/design.md §9 "3D Gaussian
//! splatting PLY") applied to arrays with the reader's own functions and in its order of
//! operations, so a scene from the arrays has the particles of the PLY bit for bit.

use crate::arrays::{floats, vec_to_array, Floats, Size};
use crate::errors::input_error;
use glam::DVec3;
use numpy::ndarray::{Ix1, Ix2, Ix3};
use pgt::formats::ply::{sigmoid, view_color, SH_C0};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The numbers of SH coefficients per channel of degrees 0 to 3.
const SH_COUNTS: [usize; 4] = [1, 4, 9, 16];

/// One row's standard deviations: exp(scale) (or the scales as they are when `activated`),
/// each a finite number ≥ the smallest normal f64, as the PLY reader requires.
fn semi_axes(
    py: Python<'_>,
    scales: &Floats<'_, Ix2>,
    i: usize,
    activated: bool,
) -> PyResult<[f64; 3]> {
    let mut axes = [0.0; 3];
    for (k, a) in axes.iter_mut().enumerate() {
        let s = scales.get((i, k));
        *a = if activated { s } else { s.exp() };
        if !(a.is_finite() && *a >= f64::MIN_POSITIVE) {
            let what = if activated {
                format!("{s}")
            } else {
                format!("exp({s}) = {a}")
            };
            return Err(input_error(
                py,
                format!(
                    "scales: row {i}, column {k}: the standard deviation {what} is not a finite number > 0{}",
                    if activated { "" } else { " (scales are logs of standard deviations; activated=True takes them as they are)" }
                ),
            ));
        }
    }
    Ok(axes)
}

/// One row's quaternion (w, x, y, z) normalised as the PLY reader normalises it.
fn rotation(py: Python<'_>, quats: &Floats<'_, Ix2>, i: usize) -> PyResult<[f64; 4]> {
    let q = [0, 1, 2, 3].map(|k| quats.get((i, k)));
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(input_error(
            py,
            format!("quats: row {i} = {q:?} is not a finite, non-zero quaternion (w, x, y, z)"),
        ));
    }
    Ok(q.map(|c| c / norm))
}

/// One row's opacity: sigmoid(logit) (or the value as it is when `activated`), in [0, 1)
/// since a Gaussian's opacity 1 would be an infinite peak density.
fn opacity(
    py: Python<'_>,
    opacities: &Floats<'_, Ix1>,
    i: usize,
    activated: bool,
) -> PyResult<f64> {
    let x = opacities.get(i);
    let o = if activated { x } else { sigmoid(x) };
    if !(0.0..1.0).contains(&o) {
        let what = if activated {
            format!("{x}")
        } else {
            format!("sigmoid({x}) = {o}")
        };
        return Err(input_error(
            py,
            format!(
                "opacities: index {i}: the opacity {what} is not in [0, 1) (a Gaussian's opacity 1 would be an infinite peak density)"
            ),
        ));
    }
    Ok(o)
}

/// One row's colour from its SH coefficients (K, 3): the DC colour 0.5 + C0·dc without `eye`,
/// else the view-dependent colour seen from `eye`; clamped at 0 as the PLY reader does.
fn sh_color(sh: &Floats<'_, Ix3>, i: usize, center: DVec3, eye: Option<DVec3>) -> DVec3 {
    let coefficient =
        |j: usize| DVec3::new(sh.get((i, j, 0)), sh.get((i, j, 1)), sh.get((i, j, 2)));
    let dc = coefficient(0);
    let color = match eye {
        None => SH_C0 * dc + 0.5,
        Some(eye) => {
            let rest: Vec<DVec3> = (1..sh.shape()[1]).map(coefficient).collect();
            view_color(dc, &rest, center - eye)
        }
    };
    color.max(DVec3::ZERO)
}

/// The particles of 3D Gaussians given as 3DGS's tensors, as the 3DGS PLY reader makes them:
/// a dict of float64 arrays "semi_axes" (n, 3) (the standard deviations), "rotations" (n, 4)
/// (normalised), "opacity" (n,) and "colors" (n, 3), for `Scene.from_arrays` with
/// `defaults={"density": "gaussian"}`. `sh` (n, K, 3) with K = 1, 4, 9 or 16 gives the colours
/// (from `eye` when given, else the DC term), or `colors` (n, 3) are taken as they are.
#[pyfunction]
#[pyo3(signature = (centers, scales, quats, opacities, *, sh=None, colors=None, activated=false, eye=None))]
#[allow(clippy::too_many_arguments)]
pub fn gaussian_particles<'py>(
    py: Python<'py>,
    centers: &Bound<'py, PyAny>,
    scales: &Bound<'py, PyAny>,
    quats: &Bound<'py, PyAny>,
    opacities: &Bound<'py, PyAny>,
    sh: Option<&Bound<'py, PyAny>>,
    colors: Option<&Bound<'py, PyAny>>,
    activated: bool,
    eye: Option<[f64; 3]>,
) -> PyResult<Bound<'py, PyDict>> {
    let centers: Floats<Ix2> = floats("means", centers, &[Size::Any("n"), Size::Is(3)])?;
    let n = centers.shape()[0];
    let scales: Floats<Ix2> = floats("scales", scales, &[Size::Is(n), Size::Is(3)])?;
    let quats: Floats<Ix2> = floats("quats", quats, &[Size::Is(n), Size::Is(4)])?;
    let opacities: Floats<Ix1> = floats("opacities", opacities, &[Size::Is(n)])?;
    let sh: Option<Floats<Ix3>> = sh
        .map(|s| {
            floats(
                "sh_or_colours",
                s,
                &[Size::Is(n), Size::Any("K"), Size::Is(3)],
            )
        })
        .transpose()?;
    let colors: Option<Floats<Ix2>> = colors
        .map(|c| floats("sh_or_colours", c, &[Size::Is(n), Size::Is(3)]))
        .transpose()?;
    if let Some(k) = sh.as_ref().map(|s| s.shape()[1]) {
        if !SH_COUNTS.contains(&k) {
            return Err(input_error(
                py,
                format!("sh_or_colours: (n, K, 3) SH coefficients need K = 1, 4, 9 or 16 (degree 0 to 3), got K = {k}"),
            ));
        }
    }
    let eye = match eye.map(DVec3::from) {
        Some(e) if !e.is_finite() => {
            return Err(input_error(py, format!("eye: {e} is not finite")))
        }
        e => e,
    };
    let (mut axes, mut rotations, mut opacity_out, mut color_out) = (
        Vec::with_capacity(3 * n),
        Vec::with_capacity(4 * n),
        Vec::with_capacity(n),
        Vec::with_capacity(3 * n),
    );
    for i in 0..n {
        axes.extend(semi_axes(py, &scales, i, activated)?);
        rotations.extend(rotation(py, &quats, i)?);
        opacity_out.push(opacity(py, &opacities, i, activated)?);
        let center = DVec3::new(
            centers.get((i, 0)),
            centers.get((i, 1)),
            centers.get((i, 2)),
        );
        let color = match (&sh, &colors) {
            (Some(sh), _) => sh_color(sh, i, center, eye),
            (None, Some(c)) => DVec3::new(c.get((i, 0)), c.get((i, 1)), c.get((i, 2))),
            (None, None) => DVec3::ONE,
        };
        color_out.extend(color.to_array());
    }
    let out = PyDict::new(py);
    out.set_item("semi_axes", vec_to_array(py, axes, Ix2(n, 3)))?;
    out.set_item("rotations", vec_to_array(py, rotations, Ix2(n, 4)))?;
    out.set_item("opacity", vec_to_array(py, opacity_out, Ix1(n)))?;
    out.set_item("colors", vec_to_array(py, color_out, Ix2(n, 3)))?;
    Ok(out)
}
