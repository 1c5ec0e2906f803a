#!/usr/bin/env python3
"""FLIP test vectors on float images, for pgt's float FLIP (src/metrics/flip_float.rs).

NVIDIA's `flip-evaluator` (pip) evaluates LDR-FLIP on float sRGB input and HDR-FLIP on float
linear input, without quantising; pgt's former FLIP (through the nv-flip bindings) quantised
every image to 8 bits. These vectors are float32 linear images that are NOT 8-bit
representable, so the difference between the two paths shows:

* `ldr`: a smooth gradient and a noisy copy, values in [0, 1]. flip-evaluator gets them encoded
  to sRGB (IEC 61966-2-1 in float64, then float32); pgt gets the linear float32 values.
* `hdr`: a wider image with values up to ~40, automatic exposures.

Each float32 is written as the shortest decimal of its float64 value, so pgt reads the same
bits. Usage:  pip install flip-evaluator numpy;  python3 scripts/flip_float_vectors.py
Writes tests/data/compare/flip_float_vectors.json.
"""

import json
import os
import sys

import flip_evaluator as flip
import numpy as np


def linear_to_srgb(c):
    c = np.clip(c.astype(np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def flat(a):
    return [float(v) for v in np.asarray(a, dtype=np.float32).reshape(-1)]


def main(out_dir):
    rng = np.random.default_rng(20261129)
    h, w = 32, 48
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack(
        [xx / (w - 1), 0.3 + 0.3 * np.cos(yy * 0.3), 0.5 + 0.4 * np.sin(xx * 0.2 + yy * 0.1)], axis=2
    )
    ref = base.astype(np.float32)
    test = np.clip(base + rng.normal(0.0, 0.01, base.shape), 0.0, 1.0).astype(np.float32)
    err, mean, params = flip.evaluate(
        linear_to_srgb(ref).astype(np.float32),
        linear_to_srgb(test).astype(np.float32),
        "LDR",
        applyMagma=False,
    )
    doc = {
        "generator": "scripts/flip_float_vectors.py",
        "flip_evaluator": getattr(flip, "__version__", "unknown"),
        "ppd": float(params.get("ppd", 67.0)),
        "ldr": {
            "width": w,
            "height": h,
            "reference": flat(ref),
            "approximation": flat(test),
            "mean": float(mean),
            "map": [float(v) for v in np.asarray(err, dtype=np.float64).reshape(-1)],
        },
    }
    h, w = 40, 56
    yy, xx = np.mgrid[0:h, 0:w]
    light = np.exp(rng.normal(0.0, 0.5, (h, w, 1))) * (0.1 + 10.0 * (xx[..., None] / (w - 1)) ** 2)
    tint = np.stack([0.9 + 0.1 * np.sin(0.3 * yy), 0.7 + 0.3 * np.cos(0.2 * xx), 0.5 + 0.0 * xx], axis=2)
    ref = (light * tint).astype(np.float32)
    test = (ref * (1.0 + rng.normal(0.0, 0.05, ref.shape))).clip(0.0, None).astype(np.float32)
    herr, hmean, hparams = flip.evaluate(ref, test, "HDR", applyMagma=False)
    doc["hdr"] = {
        "width": w,
        "height": h,
        "reference": flat(ref),
        "approximation": flat(test),
        "mean": float(hmean),
        "num_exposures": int(hparams["numExposures"]),
        "map": [float(v) for v in np.asarray(herr, dtype=np.float64).reshape(-1)],
    }
    with open(os.path.join(out_dir, "flip_float_vectors.json"), "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data/compare")
