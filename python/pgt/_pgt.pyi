# Type stubs of the extension module pgt._pgt (python/src/*.rs). The documented public
# functions are in pgt/__init__.py; the classes are re-exported from there.
import os
import pathlib
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]
_Image = npt.NDArray[np.float32]
_Gate = Union[Mapping[str, Any], _Path]

__version__: str
DEFAULT_PIXELS_PER_DEGREE: float
N_EXACT_ALL: int

@final
class Scene:
    """A scene: particles, lights, camera and render settings, validated and resolved."""

    @staticmethod
    def from_arrays(
        centers: npt.ArrayLike,
        radii: Optional[npt.ArrayLike],
        colors: Optional[npt.ArrayLike] = None,
        opacity: Union[None, float, npt.ArrayLike] = None,
        kappa: Union[None, float, npt.ArrayLike] = None,
        *,
        semi_axes: Optional[npt.ArrayLike] = None,
        rotations: Optional[npt.ArrayLike] = None,
        lights: Optional[Sequence[Mapping[str, Any]]] = None,
        camera: Optional[Mapping[str, Any]] = None,
        size: Optional[Tuple[int, int]] = None,
        mode: Optional[str] = None,
        model: Optional[str] = None,
        background: Optional[Sequence[float]] = None,
        tol: Optional[float] = None,
        lambda_: Optional[float] = None,
        light_weight: Optional[str] = None,
        emission_weight: Optional[float] = None,
        ambient: Optional[float] = None,
        defaults: Optional[Mapping[str, Any]] = None,
    ) -> Scene: ...
    @staticmethod
    def from_gaussians(
        means: npt.ArrayLike,
        scales: npt.ArrayLike,
        quats: npt.ArrayLike,
        opacities: npt.ArrayLike,
        sh_or_colours: npt.ArrayLike,
        *,
        activated: bool = False,
        sh: str = "view",
        camera: Optional[Mapping[str, Any]] = None,
        model: str = "emission",
        defaults: Optional[Mapping[str, Any]] = None,
        **scene: Any,
    ) -> Scene:
        """3D Gaussian splatting's tensors (log scales, w-x-y-z quaternions, logit opacities,
        SH (n, K, 3) or colours (n, 3)) as a scene of Gaussians: the particles of a 3DGS PLY of
        the same values, bit for bit (pgt._gaussians.from_gaussians documents the arguments)."""
        ...
    def particles(self) -> Dict[str, npt.NDArray[np.float64]]: ...
    def camera_matrices(self, api: str = "opengl") -> Dict[str, Any]: ...
    @property
    def source(self) -> Optional[pathlib.Path]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def mode(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def tol(self) -> float: ...
    @property
    def background(self) -> Tuple[float, float, float]: ...
    @property
    def lights(self) -> List[Dict[str, Any]]: ...
    @property
    def warnings(self) -> List[str]: ...
    def __len__(self) -> int: ...

@final
class RenderResult:
    """A finished reference render."""

    @property
    def image(self) -> _Image: ...
    @property
    def err(self) -> Optional[_Image]: ...
    @property
    def seconds(self) -> float: ...
    @property
    def primary_rays(self) -> int: ...
    @property
    def shadow_rays(self) -> int: ...
    @property
    def max_error(self) -> Optional[float]: ...
    @property
    def mean_error(self) -> Optional[float]: ...
    @property
    def unconverged(self) -> int: ...
    @property
    def worst_unconverged(self) -> Optional[Tuple[int, int, float]]: ...
    @property
    def tol(self) -> float: ...
    def write(self, path: _Path, *, exposure: float = 0.0) -> None: ...

@final
class ApproxResult:
    """A finished GPU approximation."""

    @property
    def image(self) -> _Image: ...
    @property
    def gpu_seconds(self) -> float: ...
    @property
    def timing(self) -> str: ...
    @property
    def adapter(self) -> str: ...
    @property
    def method(self) -> str: ...
    @property
    def params(self) -> List[Tuple[str, int]]: ...
    @property
    def passes(self) -> int: ...
    @property
    def hit_overflow_pixels(self) -> int: ...
    @property
    def loop_limited_pixels(self) -> int: ...

@final
class PerChannel:
    """A metric per channel and the mean of the three."""

    @property
    def r(self) -> float: ...
    @property
    def g(self) -> float: ...
    @property
    def b(self) -> float: ...
    @property
    def mean(self) -> float: ...
    def as_dict(self) -> Dict[str, float]: ...

@final
class GateCheck:
    """The outcome of one threshold of a gate."""

    @property
    def name(self) -> str: ...
    @property
    def value(self) -> float: ...
    @property
    def threshold(self) -> float: ...
    @property
    def passed(self) -> bool: ...

@final
class GateResult:
    """A gate evaluated on a comparison; true when every threshold passed."""

    @property
    def passed(self) -> Optional[bool]: ...
    @property
    def checks(self) -> List[GateCheck]: ...
    @property
    def failed(self) -> List[GateCheck]: ...
    @property
    def verdict(self) -> str: ...
    def __bool__(self) -> bool: ...
    def __str__(self) -> str: ...

@final
class Comparison:
    """An image pair with everything measured about it."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def data_range(self) -> float: ...
    @property
    def data_range_source(self) -> str: ...
    @property
    def ssim(self) -> Optional[PerChannel]: ...
    @property
    def ssim_note(self) -> Optional[str]: ...
    @property
    def rmse(self) -> PerChannel: ...
    @property
    def psnr(self) -> PerChannel: ...
    @property
    def mean_abs(self) -> PerChannel: ...
    @property
    def mean_rel(self) -> PerChannel: ...
    @property
    def max_abs(self) -> List[Tuple[str, float, Tuple[int, int]]]: ...
    @property
    def flip(self) -> Optional[float]: ...
    @property
    def flip_note(self) -> Optional[str]: ...
    @property
    def reference_uncertainty(self) -> Optional[Dict[str, float]]: ...
    @property
    def seconds(self) -> float: ...
    @property
    def abs_error(self) -> _Image: ...
    @property
    def rel_error(self) -> _Image: ...
    @property
    def ssim_map(self) -> Optional[_Image]: ...
    @property
    def flip_map(self) -> Optional[npt.NDArray[np.float32]]: ...
    def gate(self, gate: _Gate) -> GateResult: ...
    def summary(self, gate: Optional[_Gate] = None) -> Dict[str, Any]: ...
    def verdict(self, gate: Optional[_Gate] = None) -> str: ...
    def write_report(
        self,
        directory: _Path,
        *,
        gate: Optional[_Gate] = None,
        error_scale: Optional[float] = None,
        rel_scale: Optional[float] = None,
    ) -> pathlib.Path: ...

class Frames:
    """A scene whose particles or camera change from frame to frame (pgt.load_frames)."""

    @property
    def frame_count(self) -> Optional[int]: ...
    @property
    def time_step_ps(self) -> Optional[float]: ...
    def frame(self, index: int) -> Scene: ...
    def __len__(self) -> int: ...

def load_frames(
    path: _Path,
    *,
    size: Optional[Tuple[int, int]] = None,
    mode: Optional[str] = None,
    model: Optional[str] = None,
    tol: Optional[float] = None,
    format: Optional[str] = None,
) -> Frames: ...
def load_scene(
    path: _Path,
    *,
    size: Optional[Tuple[int, int]] = None,
    mode: Optional[str] = None,
    model: Optional[str] = None,
    tol: Optional[float] = None,
    format: Optional[str] = None,
) -> Scene: ...
def render(
    scene: Scene,
    *,
    threads: Optional[int] = None,
    spp: int = 1,
    tol: Optional[float] = None,
    integrator: str = "adaptive",
    samples: int = 100,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> RenderResult: ...
def approx(
    scene: Scene,
    method: Optional[str] = None,
    *,
    shader: Optional[_Path] = None,
    adapter: Optional[str] = None,
    params: Optional[Mapping[str, Union[int, str]]] = None,
) -> ApproxResult: ...
def approx_methods() -> List[Dict[str, Any]]: ...
def compare(
    reference: Any,
    approximation: Any,
    *,
    reference_err: Optional[npt.ArrayLike] = None,
    data_range: Optional[float] = None,
    flip: bool = True,
    ppd: float = ...,
    flip_exposures: Optional[Tuple[float, float]] = None,
    layer: Optional[str] = None,
) -> Comparison: ...
def read_image(path: _Path, *, layer: Optional[str] = None) -> _Image: ...
def write_image(
    path: _Path,
    image: npt.ArrayLike,
    *,
    err: Optional[npt.ArrayLike] = None,
    exposure: float = 0.0,
) -> None: ...

class SequenceComparison:
    @property
    def frames(self) -> int: ...
    @property
    def verdict(self) -> str: ...
    @property
    def passed(self) -> Optional[bool]: ...
    @property
    def report_page(self) -> Optional[pathlib.Path]: ...
    def summary(self) -> Dict[str, Any]: ...

def gaussian_particles(
    centers: npt.ArrayLike,
    scales: npt.ArrayLike,
    quats: npt.ArrayLike,
    opacities: npt.ArrayLike,
    *,
    sh: Optional[npt.ArrayLike] = None,
    colors: Optional[npt.ArrayLike] = None,
    activated: bool = False,
    eye: Optional[Tuple[float, float, float]] = None,
) -> Dict[str, npt.NDArray[np.float64]]: ...
def dataset_cameras(path: _Path) -> List[Dict[str, Any]]: ...
def is_sequence(path: _Path) -> bool: ...
def compare_sequences(
    reference: _Path,
    approximation: _Path,
    *,
    data_range: Optional[float] = None,
    flip: bool = True,
    ppd: float = ...,
    flip_exposures: Optional[Tuple[float, float]] = None,
    pop_threshold: Optional[float] = None,
    gate: Any = None,
    report: Optional[_Path] = None,
) -> SequenceComparison: ...
def sweep(
    experiment: _Path,
    report: _Path,
    *,
    size: Optional[Tuple[int, int]] = None,
    threads: Optional[int] = None,
) -> Tuple[int, pathlib.Path]: ...
def merge(
    parts: Sequence[_Path], output: Optional[_Path] = None, *, exposure: float = 0.0
) -> Tuple[_Image, Optional[_Image]]: ...
def bench(
    *,
    size: int = 512,
    workloads: Sequence[str] = ("1uun", "random", "million"),
    no_baselines: bool = False,
    accuracy: bool = False,
    threads: Optional[int] = None,
    repeat: int = 1,
    frames: Optional[int] = None,
    data: _Path = "../shared/data",
) -> str: ...
