"""pgt — particle ground truth, from Python.

Exact reference renders of particle scenes (spheres of glowing, absorbing gas), GPU
approximations, and the measured difference, with numpy arrays in and out. The same library
as the ``pgt`` command line: the values are the CLI's, bit for bit.

    import pgt
    scene = pgt.load_scene("1uun.pdb", size=(256, 256))
    truth = pgt.render(scene)                  # .image, .err: float32 (H, W, 3)
    mine = my_renderer(scene.particles(), scene.camera_matrices("opengl"))
    cmp = pgt.compare(truth, mine)             # SSIM, RMSE, PSNR, FLIP, maps
    assert cmp.gate({"min_ssim": 0.95})
    cmp.write_report("report/")

Scenes: load_scene, Scene.from_arrays, Scene.from_gaussians (3D Gaussian splatting's tensors),
camera_from_K (K and a world-to-camera matrix as a camera), directional_light, point_light;
load_frames -> Frames (trajectories, sequences, camera orbits: .frame(t) is a Scene).
Rendering: render (exact, CPU), approx (GPU methods and WGSL files), approx_methods.
Measuring: compare -> Comparison (.gate, .summary, .write_report) of two images, or
SequenceComparison (.summary, .verdict, .passed) of two sequences of frames; sweep (an
experiment file and its report).
Cluster renders and speed: merge (the parts of `pgt render --part`), bench.
Images: read_image, write_image (EXR with the err layer, PNG).
Errors: Error, InputError (ValueError), FileError (OSError), GpuError, NoAdapterError;
warnings: PgtWarning.

The GIL is released while pgt works, so other Python threads run; Ctrl-C stops a render
within a fraction of a second.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

from . import _pgt
from ._errors import Error, FileError, GpuError, InputError, NoAdapterError, PgtWarning
from ._gaussians import camera_from_K
from ._pgt import (
    ApproxResult,
    Comparison,
    Frames,
    GateCheck,
    GateResult,
    PerChannel,
    RenderResult,
    Scene,
    SequenceComparison,
    approx_methods,
    bench,
    dataset_cameras,
    merge,
    read_image,
    sweep,
    write_image,
)

__version__: str = _pgt.__version__

__all__ = [
    "ApproxResult",
    "Comparison",
    "Error",
    "FileError",
    "Frames",
    "GateCheck",
    "GateResult",
    "GpuError",
    "InputError",
    "NoAdapterError",
    "PerChannel",
    "PgtWarning",
    "RenderResult",
    "Scene",
    "SequenceComparison",
    "approx",
    "approx_methods",
    "bench",
    "camera_from_K",
    "compare",
    "dataset_cameras",
    "directional_light",
    "load_frames",
    "load_scene",
    "merge",
    "point_light",
    "read_image",
    "render",
    "sweep",
    "write_image",
]

PathLike = Union[str, "os.PathLike[str]"]
Vec3 = Union[Sequence[float], Any]
ProgressCallback = Callable[[int, int], Any]


def load_scene(
    path: PathLike,
    *,
    size: Optional[Tuple[int, int]] = None,
    mode: Optional[str] = None,
    model: Optional[str] = None,
    tol: Optional[float] = None,
    format: Optional[str] = None,
) -> Scene:
    """Load a scene: a scene file (.toml) or a bare particle file (PDB, mmCIF, VRML, MMPLD,
    XYZ, CSV, GRO, PLY), which gets the default scene (camera framing the particles from -z,
    the thesis's two lights, black background). A scene moves when its includes play frames
    (trajectories, models, sequences): see ``load_frames``.

    Arguments (the overrides of ``pgt render SCENE``):
      path   scene file (.toml) or a bare particle file.
      size   (width, height) in pixels, overriding the scene (--size WxH).
      mode   "volume" or "opaque" (--mode).
      model  "emission", "lit" or "single-scatter" (--model).
      tol    absolute radiance tolerance of the quadrature, per pixel and channel (--tol).
      format the format of a bare particle file whatever its extension, e.g. "pdb", "xyz"
             (--format).

    The scene's warnings (an empty scene, skipped records) are issued as PgtWarning.
    Raises InputError naming the file, line and field; FileError for a file that cannot be read.
    """
    return _pgt.load_scene(path, size=size, mode=mode, model=model, tol=tol, format=format)


def load_frames(
    path: PathLike,
    *,
    size: Optional[Tuple[int, int]] = None,
    mode: Optional[str] = None,
    model: Optional[str] = None,
    tol: Optional[float] = None,
    format: Optional[str] = None,
) -> Frames:
    """Load a scene over frames (docs/design.md §10): a scene file whose includes play frames
    (MMPLD frames, PDB/mmCIF models, multi-frame XYZ, a numbered ``sequence``, a DCD/XTC
    ``trajectory`` with its topology) or whose camera moves (``[camera.orbit]``,
    ``[[camera.keyframes]]``), or a bare particle file with frames.

    Arguments: those of load_scene.

    Returns a Frames: ``.frame_count`` (None when only the camera moves: any frame number
    goes), ``.time_step_ps``, ``len(frames)``, and ``.frame(t)``, the Scene of frame t (read
    on demand), to render, export or measure like any other:

        frames = pgt.load_frames("md.toml", size=(256, 256))
        truths = [pgt.render(frames.frame(t)) for t in range(len(frames))]

    Raises InputError naming the file, line and field (or the frame); FileError for a file
    that cannot be read.
    """
    return _pgt.load_frames(path, size=size, mode=mode, model=model, tol=tol, format=format)


def directional_light(direction: Vec3, irradiance: Vec3) -> Dict[str, Any]:
    """A directional light for Scene.from_arrays: ``direction`` is the way the light travels
    (any non-zero length), ``irradiance`` the RGB irradiance in W/m² on a surface facing it."""
    return {"type": "directional", "direction": direction, "irradiance": irradiance}


def point_light(
    position: Vec3, intensity: Vec3, falloff: str = "inverse-square"
) -> Dict[str, Any]:
    """A point light for Scene.from_arrays: RGB ``intensity`` in W/sr at ``position``;
    ``falloff`` "inverse-square" (irradiance I/d²) or "none" (I)."""
    return {"type": "point", "position": position, "intensity": intensity, "falloff": falloff}


class _TextProgress:
    """Progress on stderr when tqdm is not installed: one line, rewritten in place."""

    def __init__(self) -> None:
        self.shown = -1

    def __call__(self, done: int, total: int) -> None:
        percent = 100 * done // max(total, 1)
        if percent != self.shown:
            self.shown = percent
            sys.stderr.write(f"\rrendering: {percent:3d}% ({done}/{total} tiles)")
            sys.stderr.flush()

    def close(self) -> None:
        if self.shown >= 0:
            sys.stderr.write("\n")
            sys.stderr.flush()


class _TqdmProgress:
    """Progress as a tqdm bar (tqdm.auto: a widget in a notebook, text in a terminal)."""

    def __init__(self, tqdm: Any) -> None:
        self.tqdm = tqdm
        self.bar: Any = None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            self.bar = self.tqdm(total=total, unit="tile", desc="rendering")
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _progress(progress: Union[None, bool, ProgressCallback]) -> Any:
    """The callback for ``progress``: None/False nothing, True a tqdm bar (or a line on
    stderr without tqdm), a callable itself."""
    if progress is None or progress is False:
        return None
    if progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return _TextProgress()
        return _TqdmProgress(tqdm)
    if callable(progress):
        return progress
    raise InputError(f"progress: expected None, True or a callable(done, total), got {progress!r}")


def render(
    scene: Scene,
    *,
    threads: Optional[int] = None,
    spp: int = 1,
    tol: Optional[float] = None,
    integrator: str = "adaptive",
    samples: int = 100,
    progress: Union[None, bool, ProgressCallback] = None,
    gpu: bool = False,
    adapter: Optional[str] = None,
) -> RenderResult:
    """Render the exact reference image of a scene (``pgt render``): f64 throughout, adaptive
    Gauss-Kronrod quadrature to ``tol`` with a per-pixel error bound.

    Arguments:
      scene       a Scene (pgt.load_scene, Scene.from_arrays).
      threads     worker threads (the image is identical for any count) [all cores].
      spp         stratified spp x spp samples per pixel [1].
      tol         absolute radiance tolerance of the quadrature, per pixel and channel
                  [the scene's].
      integrator  "adaptive" (the exact reference) or "riemann" (the thesis's midpoint sums).
      samples     samples per interval for integrator="riemann" [100].
      progress    None (silent), True (a tqdm bar if tqdm is installed, else a line on
                  stderr) or a callable(done, total) called with tiles done from this thread.
      gpu         render on the GPU in f64 (``pgt render --gpu``): the same image and err
                  within both errs; the emission model of spheres and ellipsoids or of
                  Gaussian particles, an adapter with f64 (others are refused with a
                  GpuError) [False].
      adapter     with gpu=True: the adapter whose name contains this [the first hardware
                  adapter, else lavapipe].

    Returns a RenderResult: ``.image`` and ``.err`` (float32 arrays (height, width, 3), the
    values of ``pgt render``'s EXR and its err layer), ``.seconds``, ``.primary_rays``,
    ``.shadow_rays``, ``.max_error``, ``.mean_error``, ``.unconverged``,
    ``.worst_unconverged``, ``.write(path)``.

    The GIL is released while rendering. Ctrl-C (KeyboardInterrupt), or an exception raised by
    the progress callback, stops the render within a fraction of a second and propagates;
    nothing keeps running. Pixels that did not reach tol are reported as a PgtWarning.
    """
    callback = _progress(progress)
    try:
        return _pgt.render(
            scene,
            threads=threads,
            spp=spp,
            tol=tol,
            integrator=integrator,
            samples=samples,
            progress=callback,
            gpu=gpu,
            adapter=adapter,
        )
    finally:
        if callback is not None and hasattr(callback, "close"):
            callback.close()


def approx(
    scene: Scene,
    method: Optional[str] = None,
    *,
    shader: Optional[PathLike] = None,
    adapter: Optional[str] = None,
    **params: Union[int, str],
) -> ApproxResult:
    """Render a scene with a GPU approximation (``pgt approx``).

    Arguments:
      scene    a Scene.
      method   a built-in method ("thesis", "sorted-blend", "opaque", ...; see
               pgt.approx_methods()) [opaque for opaque scenes, thesis otherwise].
      shader   a WGSL file defining ``fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>``
               (docs/user-shaders.md), instead of a method.
      adapter  use the adapter whose name contains this (case-insensitive).
      params   the method's parameters as keywords, e.g. samples=100, n_exact=5 or
               n_exact="all" (--param NAME=VALUE).

    Returns an ApproxResult: ``.image`` (float32 (height, width, 3)), ``.gpu_seconds``,
    ``.adapter``, ``.method``, ``.params``, ``.passes``.
    Raises NoAdapterError when wgpu finds no adapter: install mesa-vulkan-drivers and
    libvulkan1 (lavapipe) or a GPU driver. The GIL is released while the GPU works.
    """
    return _pgt.approx(scene, method, shader=shader, adapter=adapter, params=params)


ImageLike = Union[Any, PathLike, RenderResult, ApproxResult]


def compare(
    reference: ImageLike,
    approximation: ImageLike,
    *,
    reference_err: Optional[Any] = None,
    data_range: Optional[float] = None,
    flip: bool = True,
    ppd: float = _pgt.DEFAULT_PIXELS_PER_DEGREE,
    flip_exposures: Optional[Tuple[float, float]] = None,
    layer: Optional[str] = None,
    pop_threshold: Optional[float] = None,
    gate: Union[None, Mapping[str, Any], PathLike] = None,
    report: Optional[PathLike] = None,
) -> Union[Comparison, SequenceComparison]:
    """Compare an approximation with the reference (``pgt compare``): SSIM, RMSE, PSNR, mean
    absolute and relative error, max absolute error, FLIP, per channel and mean, and the maps.

    Arguments:
      reference      the reference: an array (height, width, 3) of linear float32/float64
                     values, an image file (.exr or .png), or a RenderResult (its err layer
                     becomes reference_err).
      approximation  the approximation: an array, an image file, or a RenderResult /
                     ApproxResult.
      reference_err  the reference's per-pixel error bound (an array like the image); read
                     from the err layer when the reference is an EXR file.
      data_range     data range R of SSIM and PSNR [1 for LDR inputs, derived from the
                     reference for HDR].
      flip           compute FLIP (--no-flip is flip=False).
      ppd            FLIP's viewing condition in pixels per degree.
      flip_exposures HDR-FLIP exposure range (start, stop) in stops [from the reference].
      layer          EXR layer to compare (channels LAYER.R/G/B) in both files.

    Two sequences of frames (each a folder, or a printf pattern such as ``ref/f_%04d.exr``)
    are compared frame by frame, with the temporal error of every frame after the first
    (docs/design.md §10), as ``pgt compare REF_SEQ APPROX_SEQ`` does:
      pop_threshold  the temporal error above which a pixel pops [0.05 × the data range].
      gate           a dict of thresholds or a gate file: the per-image ones held by every
                     frame, the temporal ones (max_temporal_p99, ...) by the worst frame.
      report         a folder for the report that plays the sequences.
    It returns a SequenceComparison: ``.summary()`` (the CLI's JSON), ``.verdict``,
    ``.passed``, ``.frames``, ``.report_page``. A sequence against one image is an InputError.

    Returns a Comparison (two images): ``.ssim``, ``.rmse``, ``.psnr``, ``.mean_abs``, ``.mean_rel``
    (PerChannel: .r .g .b .mean), ``.max_abs``, ``.flip``, the maps ``.abs_error``,
    ``.rel_error``, ``.ssim_map``, ``.flip_map``, and ``.gate(dict or path)``,
    ``.summary()``, ``.verdict()``, ``.write_report(directory)``.

    Arrays are copied once (into pgt's image type); NaN and infinity are refused with an
    InputError naming the argument. The GIL is released while measuring.
    """
    paths = [p for p in (reference, approximation) if isinstance(p, (str, os.PathLike))]
    sequences = [_pgt.is_sequence(p) for p in paths]
    if len(paths) == 2 and all(sequences):
        if layer is not None:
            raise InputError("layer compares one layer of two images; it does not apply to sequences")
        return _pgt.compare_sequences(
            reference,
            approximation,
            data_range=data_range,
            flip=flip,
            ppd=ppd,
            flip_exposures=flip_exposures,
            pop_threshold=pop_threshold,
            gate=gate,
            report=report,
        )
    if any(sequences):
        raise InputError(
            "compare two sequences of frames (folders or %d patterns) or two images, not a sequence and an image"
        )
    for name, value in (("pop_threshold", pop_threshold), ("gate", gate), ("report", report)):
        if value is not None:
            raise InputError(
                f"{name} applies to sequences of frames; for two images use Comparison.gate() and .write_report()"
            )
    if isinstance(reference, RenderResult):
        if reference_err is None:
            reference_err = reference.err
        reference = reference.image
    elif isinstance(reference, ApproxResult):
        reference = reference.image
    if isinstance(approximation, (RenderResult, ApproxResult)):
        approximation = approximation.image
    return _pgt.compare(
        reference,
        approximation,
        reference_err=reference_err,
        data_range=data_range,
        flip=flip,
        ppd=ppd,
        flip_exposures=flip_exposures,
        layer=layer,
    )
