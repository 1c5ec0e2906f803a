"""3D Gaussian splatting in pgt's terms: ``Scene.from_gaussians`` (3DGS's tensors as a scene of
Gaussian particles, the particles of the equivalent 3DGS PLY bit for bit) and ``camera_from_K``
(an intrinsic matrix K and a world-to-camera matrix as a scene's ``[camera]`` table).

docs/design.md §9 ("3D Gaussian splatting PLY") gives the mapping: standard deviations
exp(scale_i), the quaternion (w, x, y, z) normalised, opacity sigmoid(logit) (the opacity of a
ray through the centre along the shortest axis), the colour of the reference rasteriser's
``computeColorFromSH`` seen from the eye (or its DC term), clamped at 0. The activations run in
Rust with the PLY reader's own functions (``_pgt.gaussian_particles``), so the bits agree.
"""

from __future__ import annotations

import warnings
from typing import Any, Dict, Mapping, Optional

import numpy as np

from . import _pgt
from ._errors import InputError

# What a bare 3DGS PLY gets (docs/design.md §1, "A splatting file is Gaussians"): the emission
# model on black; the particles' density is Gaussian.
_SPLATTING_MODEL = "emission"


def _as_array(name: str, value: Any) -> np.ndarray:
    """``value`` as a numpy array (arrays as they are, anything else as float64)."""
    if isinstance(value, np.ndarray):
        return value
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(f"{name}: expected an array of numbers ({e})") from None


def from_gaussians(
    means: Any,
    scales: Any,
    quats: Any,
    opacities: Any,
    sh_or_colours: Any,
    *,
    activated: bool = False,
    sh: str = "view",
    camera: Optional[Mapping[str, Any]] = None,
    model: str = _SPLATTING_MODEL,
    defaults: Optional[Mapping[str, Any]] = None,
    **scene: Any,
):
    """A scene of 3D Gaussians from the tensors of 3D Gaussian splatting, with the particles a
    3DGS PLY of the same values gives (``pgt.load_scene`` of the file, bit for bit).

    Arguments (float32 or float64 arrays; lists are converted):
      means          (n, 3) centres.
      scales         (n, 3) natural logs of the standard deviations along the body's axes
                     (3DGS's ``_scaling`` before its exp).
      quats          (n, 4) orientations (w, x, y, z), unnormalised, body to world
                     (3DGS's ``_rotation``); a zero quaternion is refused.
      opacities      (n,) logits (3DGS's ``_opacity`` before its sigmoid); the opacity
                     sigmoid(x) must be < 1 (x below about 36.7).
      sh_or_colours  (n, K, 3) SH coefficients, K = 1, 4, 9 or 16 (degree 0 to 3; 3DGS's
                     ``cat(features_dc, features_rest)``: coefficient, then channel), or
                     (n, 3) linear RGB colours >= 0 taken as they are.
      activated      True: scales are the standard deviations and opacities the opacities in
                     [0, 1) (exp'd and sigmoid'ed, gsplat's activated tensors).
      sh             "view": the colour of the reference rasteriser's computeColorFromSH
                     seen from the scene camera's eye (where the framing or ``camera`` puts
                     it), clamped at 0; "dc": 0.5 + C0·dc, clamped at 0 (``sh`` of a PLY
                     include) ["view"].
      camera         a ``[camera]`` dict: ``pgt.camera_from_K(K, viewmat, width, height)``,
                     position/look_at/up/fov_y, or ``{"from": dataset, "image": name}``
                     [the framing of the Gaussians' 3σ extent, as for a bare PLY].
      model          the optical model ["emission", what a bare 3DGS PLY gets].
      defaults       the scene file's [defaults]; ``density`` is "gaussian" and may not be set.
      scene          the other keywords of ``Scene.from_arrays`` (size, lights, background,
                     tol, ...).

    A radiance field's colour depends on the view; pgt evaluates it once per scene, from the
    camera's eye (for a sequence of cameras, build one scene per camera). Raises InputError
    naming the argument for arrays of the wrong shape, NaN or infinity, a zero quaternion, an
    opacity of 1.
    """
    if sh not in ("view", "dc"):
        raise InputError(f'sh: expected "view" or "dc", got {sh!r}')
    defaults = dict(defaults or {})
    if "density" in defaults:
        raise InputError('defaults: density is "gaussian" for Scene.from_gaussians; it may not be set')
    defaults["density"] = "gaussian"
    colours = _as_array("sh_or_colours", sh_or_colours)
    if colours.ndim == 3:
        sh_arg: Dict[str, Any] = {"sh": colours}
    elif colours.ndim == 2:
        sh_arg = {"colors": colours}
    else:
        raise InputError(
            f"sh_or_colours: expected (n, K, 3) SH coefficients or (n, 3) colours, got shape {colours.shape}"
        )
    means = _as_array("means", means)
    activate = dict(activated=bool(activated), **sh_arg)

    def build(eye: Optional[np.ndarray]):
        p = _pgt.gaussian_particles(means, scales, quats, opacities, eye=eye, **activate)
        return _pgt.Scene.from_arrays(
            means,
            None,
            p["colors"],
            p["opacity"],
            semi_axes=p["semi_axes"],
            rotations=p["rotations"],
            camera=camera,
            model=model,
            defaults=defaults,
            **scene,
        )

    view = sh == "view" and colours.ndim == 3 and colours.shape[1] > 1
    if not view:
        return build(None)
    # The eye is where the camera (or the framing, by the particles alone) puts it: a first
    # scene with the DC colours finds it, as a bare PLY is read a second time from there.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eye = build(None).camera_matrices()["eye"]
    return build(tuple(float(v) for v in eye))


def camera_from_K(K: Any, viewmat: Any, width: int, height: int) -> Dict[str, Any]:
    """A ``[camera]`` table (for ``camera=`` of Scene.from_arrays and Scene.from_gaussians)
    from a pinhole intrinsic matrix and a world-to-camera matrix, as splatting code holds them.

    Arguments:
      K        (3, 3) [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] in pixels, pixel centres at
               +0.5 (COLMAP's and gsplat's convention; docs/design.md §1 "Intrinsics").
      viewmat  (4, 4) (or (3, 4)) world-to-camera [[R, t], [0, 0, 0, 1]] acting on column
               vectors, OpenCV camera axes (x right, y down, z forward): gsplat's
               ``viewmats``; 3DGS's ``world_view_transform`` is its transpose.
      width, height  the image size in pixels.

    Returns {"fx", "fy", "cx", "cy", "R", "t", "width", "height"} (plain floats and lists).
    R must be a rotation to 1e-5 (the scene refuses it naming camera.R). Raises InputError
    naming K or viewmat for a wrong shape, a skewed K, NaN or infinity.
    """
    K = _as_array("K", K).astype(np.float64)
    viewmat = _as_array("viewmat", viewmat).astype(np.float64)
    if K.shape != (3, 3):
        raise InputError(f"K: expected an array of shape (3, 3), got shape {K.shape}")
    if viewmat.shape not in ((4, 4), (3, 4)):
        raise InputError(f"viewmat: expected an array of shape (4, 4) or (3, 4), got shape {viewmat.shape}")
    for name, m in (("K", K), ("viewmat", viewmat)):
        if not np.isfinite(m).all():
            raise InputError(f"{name}: non-finite value; NaN and infinity are refused")
    if K[0, 1] != 0 or K[1, 0] != 0 or tuple(K[2]) != (0.0, 0.0, 1.0):
        raise InputError(f"K: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew), got {K.tolist()}")
    if viewmat.shape == (4, 4) and tuple(viewmat[3]) != (0.0, 0.0, 0.0, 1.0):
        raise InputError(f"viewmat: the last row must be [0, 0, 0, 1], got {viewmat[3].tolist()}")
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise InputError(f"{name}: expected an integer number of pixels, got {v!r}")
    return {
        "fx": float(K[0, 0]),
        "fy": float(K[1, 1]),
        "cx": float(K[0, 2]),
        "cy": float(K[1, 2]),
        "R": viewmat[:3, :3].tolist(),
        "t": viewmat[:3, 3].tolist(),
        "width": int(width),
        "height": int(height),
    }
