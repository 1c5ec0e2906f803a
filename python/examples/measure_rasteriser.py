"""Measure a Gaussian-splatting rasteriser against pgt's exact reference along a camera path.

Your rasteriser is a Python function ``render(viewmat, K, width, height) -> image``: viewmat
the (4, 4) world-to-camera matrix in OpenCV axes (x right, y down, z forward; gsplat's
``viewmats``), K the (3, 3) intrinsics in pixels with pixel centres at +0.5, the image a
linear float (height, width, 3) array. ``measure`` renders, per camera, pgt's exact image of
the same Gaussians (``pgt.Scene.from_gaussians`` with ``pgt.camera_from_K``: the volume the
Gaussians describe, with a per-pixel error bound), calls your function, writes both sequences
as EXR frames and compares them as ``pgt compare REF_SEQ APPROX_SEQ`` does: the metrics of
every frame, the temporal error of every frame after the first (does the error flicker as the
camera moves?), the report that plays both sequences.

The stand-in rasteriser below, ``numpy_rasteriser``, is the forward model of the 3DGS
reference rasteriser in numpy (EWA projection with the Jacobian at the centre, +0.3 px²
dilation, 3σ footprint, α = min(0.99, o·exp(−½ dᵀΣ₂D⁻¹d)), α < 1/255 skipped, front to back by
centre depth); replace it with yours (a wrapper around gsplat's ``rasterization``, say).

Along a dataset's cameras: ``pgt.dataset_cameras`` reads a COLMAP model, a transforms.json or a
3DGS cameras.json into the same (viewmat, K) per image; ``colmap_points_as_gaussians`` starts
the Gaussians as 3DGS training does, one per point of the model's sparse cloud.

Run it:  python measure_rasteriser.py [OUT_DIR] [SIZE] [FRAMES | COLMAP_TEXT_MODEL_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable, Dict, List, Tuple

import numpy as np

import pgt

Render = Callable[[np.ndarray, np.ndarray, int, int], np.ndarray]
SH_C0 = 0.28209479177387814  # ½√(1/π), the degree-0 SH constant of 3DGS


def make_gaussians(n: int = 80, seed: int = 3) -> Dict[str, np.ndarray]:
    """Random Gaussians in 3DGS's tensors: means, log scales, w-x-y-z quaternions, logit
    opacities and degree-0 SH coefficients (n, 1, 3)."""
    rng = np.random.default_rng(seed)
    return {
        "means": rng.uniform(-0.8, 0.8, (n, 3)),
        "scales": np.log(rng.uniform(0.04, 0.18, (n, 3))),
        "quats": rng.normal(size=(n, 4)),
        "opacities": rng.uniform(-1.0, 2.5, n),
        "sh_or_colours": rng.uniform(-1.2, 1.5, (n, 1, 3)),
    }


def orbit(
    frames: int, width: int, height: int, distance: float = 3.5, fov_y_deg: float = 40.0
) -> List[Tuple[np.ndarray, np.ndarray]]:
    """(viewmat, K) of ``frames`` cameras on a circle around the origin, 20° above it, looking
    at the origin; K of a centred principal point and the vertical angle fov_y."""
    fy = (height / 2) / np.tan(np.radians(fov_y_deg) / 2)
    K = np.array([[fy, 0.0, width / 2], [0.0, fy, height / 2], [0.0, 0.0, 1.0]])
    cameras = []
    for k in range(frames):
        angle = 2 * np.pi * k / max(frames, 1) * 0.25  # a quarter turn over the sequence
        eye = distance * np.array([np.sin(angle) * np.cos(0.35), np.sin(0.35), -np.cos(angle) * np.cos(0.35)])
        f = -eye / np.linalg.norm(eye)
        r = np.cross(f, [0.0, 1.0, 0.0])
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        R = np.stack([r, -u, f])  # OpenCV rows: x right, y down, z forward
        viewmat = np.eye(4)
        viewmat[:3, :3] = R
        viewmat[:3, 3] = -R @ eye
        cameras.append((viewmat, K))
    return cameras


def dataset(path: str, width: int) -> Tuple[List[Tuple[np.ndarray, np.ndarray]], int, int]:
    """(viewmat, K) of every image of a dataset (``pgt.dataset_cameras``), with the images
    scaled to ``width`` pixels (K's first two rows scale with them), and the scaled size."""
    cameras = pgt.dataset_cameras(path)
    scale = width / cameras[0]["width"]
    height = max(1, round(cameras[0]["height"] * scale))
    out = []
    for c in cameras:
        K = c["K"].copy()
        K[:2] *= scale
        out.append((c["viewmat"], K))
    return out, width, height


def colmap_points_as_gaussians(model: str) -> Dict[str, np.ndarray]:
    """3DGS's initialisation from a COLMAP text model's ``points3D.txt``: one round Gaussian per
    point, its standard deviation the root mean square distance to its three nearest points,
    opacity 0.1, the point's colour as the degree-0 SH coefficient."""
    rows = [
        line.split()
        for line in (Path(model) / "points3D.txt").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    means = np.array([[float(v) for v in r[1:4]] for r in rows])
    rgb = np.array([[float(v) for v in r[4:7]] for r in rows]) / 255.0
    d2 = ((means[:, None, :] - means[None, :, :]) ** 2).sum(-1)
    np.fill_diagonal(d2, np.inf)
    nearest = np.sort(d2, axis=1)[:, :3].mean(1)
    n = len(means)
    return {
        "means": means,
        "scales": np.tile(0.5 * np.log(np.maximum(nearest, 1e-7))[:, None], (1, 3)),
        "quats": np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
        "opacities": np.full(n, np.log(0.1 / 0.9)),
        "sh_or_colours": ((rgb - 0.5) / SH_C0)[:, None, :],
    }


def numpy_rasteriser(g: Dict[str, np.ndarray]) -> Render:
    """The 3DGS forward model in numpy for the Gaussians ``g`` (degree-0 SH), as a
    ``render(viewmat, K, width, height)`` function."""
    means = np.asarray(g["means"], np.float64)
    scales = np.exp(g["scales"])
    q = g["quats"] / np.linalg.norm(g["quats"], axis=1, keepdims=True)
    w, x, y, z = q.T
    rot = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        1,
    )
    m = rot * scales[:, None, :]
    cov3 = m @ m.transpose(0, 2, 1)
    opacity = 1 / (1 + np.exp(-g["opacities"]))
    colour = np.maximum(SH_C0 * g["sh_or_colours"][:, 0, :] + 0.5, 0)

    def render(viewmat: np.ndarray, K: np.ndarray, width: int, height: int) -> np.ndarray:
        W, t = viewmat[:3, :3], viewmat[:3, 3]
        cam = means @ W.T + t
        fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
        image = np.zeros((height, width, 3))
        transmittance = np.ones((height, width))
        px, py = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
        for i in np.argsort(cam[:, 2]):
            cx_, cy_, cz = cam[i]
            if cz <= 0.2:
                continue
            J = np.array([[fx / cz, 0, -fx * cx_ / cz**2], [0, fy / cz, -fy * cy_ / cz**2]])
            cov2 = J @ W @ cov3[i] @ W.T @ J.T + 0.3 * np.eye(2)
            u, v = fx * cx_ / cz + cx, fy * cy_ / cz + cy
            reach = 3 * np.sqrt(np.linalg.eigvalsh(cov2).max())
            x0, x1 = max(int(u - reach), 0), min(int(u + reach) + 1, width)
            y0, y1 = max(int(v - reach), 0), min(int(v + reach) + 1, height)
            if x0 >= x1 or y0 >= y1:
                continue
            inv = np.linalg.inv(cov2)
            dx, dy = px[y0:y1, x0:x1] - u, py[y0:y1, x0:x1] - v
            power = -0.5 * (inv[0, 0] * dx * dx + 2 * inv[0, 1] * dx * dy + inv[1, 1] * dy * dy)
            alpha = np.minimum(0.99, opacity[i] * np.exp(power))
            alpha[alpha < 1 / 255] = 0
            T = transmittance[y0:y1, x0:x1]
            image[y0:y1, x0:x1] += (T * alpha)[..., None] * colour[i]
            T *= 1 - alpha
        return image.astype(np.float32)

    return render


def measure(
    render: Render,
    gaussians: Dict[str, np.ndarray],
    cameras: List[Tuple[np.ndarray, np.ndarray]],
    width: int,
    height: int,
    out_dir: Path,
    gate: Dict = None,
) -> pgt.SequenceComparison:
    """Render the exact reference and call ``render`` for every camera, write both sequences
    (``out_dir/reference/f_NNNN.exr`` with the err layer, ``out_dir/rasteriser/f_NNNN.exr``)
    and compare them (the report in ``out_dir/report``)."""
    out_dir = Path(out_dir)
    ref_dir, mine_dir = out_dir / "reference", out_dir / "rasteriser"
    ref_dir.mkdir(parents=True, exist_ok=True)
    mine_dir.mkdir(parents=True, exist_ok=True)
    for k, (viewmat, K) in enumerate(cameras):
        # One scene per camera: the SH colour is evaluated from that camera's eye.
        scene = pgt.Scene.from_gaussians(**gaussians, camera=pgt.camera_from_K(K, viewmat, width, height))
        truth = pgt.render(scene)
        pgt.write_image(ref_dir / f"f_{k:04d}.exr", truth.image, err=truth.err)
        pgt.write_image(mine_dir / f"f_{k:04d}.exr", np.asarray(render(viewmat, K, width, height), np.float32))
    return pgt.compare(
        str(ref_dir / "f_%04d.exr"),
        str(mine_dir / "f_%04d.exr"),
        gate=gate,
        report=out_dir / "report",
    )


def main(out_dir: str = "measure_rasteriser", size: str = "96", frames: str = "8") -> pgt.SequenceComparison:
    width = int(size)
    if Path(frames).is_dir():
        gaussians = colmap_points_as_gaussians(frames)
        cameras, width, height = dataset(frames, width)
    else:
        height = max(1, width * 3 // 4)
        gaussians = make_gaussians()
        cameras = orbit(int(frames), width, height)
    cmp = measure(numpy_rasteriser(gaussians), gaussians, cameras, width, height, Path(out_dir))
    for frame in cmp.summary()["frames"]:
        line = f"frame {frame['frame']}: SSIM {frame['ssim']:.4f}  RMSE {frame['rmse']:.4f}  max {frame['max_abs']:.3f}"
        if frame["temporal"] is not None:  # every frame after the first
            line += f"  temporal p99 {frame['temporal']['p99']['mean']:.4f}, {frame['temporal']['pops']} pixels pop"
        print(line)
    print(cmp.verdict)
    print("report:", cmp.report_page)
    return cmp


if __name__ == "__main__":
    main(*sys.argv[1:])
