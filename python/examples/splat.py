"""A particle renderer as a researcher writes one in numpy, measured against pgt's truth.

The renderer is sorted splatting, the way rasterising renderers draw transparent particles:
each sphere is composited whole, back to front by the depth of its centre, with its own
emission closed form alpha = 1 - exp(-sigma * chord). Where spheres overlap, that order is
wrong and the result differs from the exact integral; pgt says by how much, and a gate turns
"by how much" into a test (tests/test_example.py asserts it).

Run it:  python splat.py [REPORT_DIR]
"""

from __future__ import annotations

import sys

import numpy as np

import pgt

# What this renderer must reach on the scene below to pass (the assertion of a test suite).
# Sorting back to front reaches SSIM 0.9996, RMSE 0.004 and a 99th-percentile error of 0.012;
# sorting the wrong way fails every threshold.
GATE = {
    "min_ssim": 0.999,
    "max_rmse": 0.01,
    "percentiles": [{"map": "abs", "percentile": 99.0, "max": 0.03}],
}


def make_scene(n: int = 150, size: int = 128, seed: int = 1) -> pgt.Scene:
    """Glowing, partly overlapping particles in a unit cube (emission model: the colour is
    what each particle emits)."""
    rng = np.random.default_rng(seed)
    return pgt.Scene.from_arrays(
        centers=rng.uniform(-1, 1, (n, 3)),
        radii=rng.uniform(0.05, 0.15, n),
        colors=rng.uniform(0.1, 1.0, (n, 3)),
        opacity=rng.uniform(0.2, 0.8, n),
        model="emission",
        size=(size, size),
    )


def splat(scene: pgt.Scene, order: str = "back-to-front") -> np.ndarray:
    """Sorted splatting in numpy: every sphere composited whole over the pixels of its screen
    footprint, in the order of its centre's depth."""
    p = scene.particles()
    cam = scene.camera_matrices("opengl")
    w, h, t = cam["width"], cam["height"], cam["tan_half_fov_y"]
    # One ray per pixel centre, as pgt samples them (cam["pixel_convention"]).
    a = (2 * (np.arange(w) + 0.5) / w - 1) * cam["aspect"] * t
    b = (1 - 2 * (np.arange(h) + 0.5) / h) * t
    rays = cam["forward"] + a[None, :, None] * cam["right"] + b[:, None, None] * cam["up"]
    rays /= np.linalg.norm(rays, axis=2, keepdims=True)
    image = np.broadcast_to(np.asarray(scene.background, np.float32), (h, w, 3)).copy()
    # The footprint: the centre projected with the camera's matrices, and a conservative
    # radius in pixels.
    ndc = cam["projection"] @ cam["view"] @ np.c_[p["center"], np.ones(len(p["radius"]))].T
    px = (ndc[0] / ndc[3] + 1) / 2 * w
    py = (1 - ndc[1] / ndc[3]) / 2 * h
    depth = (p["center"] - cam["eye"]) @ cam["forward"]
    reach = 1.5 * p["radius"] / (np.maximum(depth, 1e-9) * t) * h / 2 + 2
    indices = np.argsort(-depth) if order == "back-to-front" else np.argsort(depth)
    for i in indices:
        if depth[i] <= 0:
            continue
        x0, x1 = int(max(px[i] - reach[i], 0)), int(min(px[i] + reach[i] + 1, w))
        y0, y1 = int(max(py[i] - reach[i], 0)), int(min(py[i] + reach[i] + 1, h))
        if x0 >= x1 or y0 >= y1:
            continue
        to_centre = p["center"][i] - cam["eye"]
        along = rays[y0:y1, x0:x1] @ to_centre  # closest approach of each ray
        miss2 = to_centre @ to_centre - along**2
        chord = 2 * np.sqrt(np.clip(p["radius"][i] ** 2 - miss2, 0, None))
        alpha = (1 - np.exp(-p["sigma"][i] * chord))[..., None]
        tile = image[y0:y1, x0:x1]
        tile[:] = tile * (1 - alpha) + p["color"][i] * alpha
    return image


def main(report_dir: str = "splat_report") -> pgt.GateResult:
    scene = make_scene()
    truth = pgt.render(scene)
    mine = splat(scene)
    cmp = pgt.compare(truth, mine)
    result = cmp.gate(GATE)
    print(result.verdict)
    print("report:", cmp.write_report(report_dir, gate=GATE))
    return result


if __name__ == "__main__":
    sys.exit(0 if main(*sys.argv[1:]) else 1)
