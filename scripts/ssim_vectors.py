#!/usr/bin/env python3
"""Test vectors for pgt's comparison metrics (docs/design.md §5), computed by independent oracles.

SSIM, MSE and PSNR come from scikit-image (the contract's oracle):

    structural_similarity(ref, approx, gaussian_weights=True, sigma=1.5,
                          use_sample_covariance=False, data_range=R,
                          channel_axis=2, full=True)

FLIP comes from NVIDIA's `flip-evaluator` (LDR), the other statistics from plain numpy.

Every image is generated here from a fixed seed as float32 values (what pgt holds in memory) and
written into the JSON exactly (each float32 printed as the shortest decimal of its float64 value,
which round-trips). scikit-image works in float64 on float64 input, so the arrays are cast to
float64 before the call, exactly as pgt casts its f32 pixels to f64.

Usage:  pip install scikit-image flip-evaluator
        python3 scripts/ssim_vectors.py tests/data/compare
Writes  ssim_vectors.json, and png16_ref.png / png16_approx.png (16-bit sRGB PNGs, whose
linear decoding is the input of the `png16` case), flip_ref.png / flip_approx.png (8-bit) with
flip_vectors.json.
"""

import json
import os
import sys

import imageio.v3 as iio
import numpy as np
import skimage
from skimage.metrics import (
    mean_squared_error,
    peak_signal_noise_ratio,
    structural_similarity,
)


def write_png16(path, rgb16):
    """A minimal 16-bit RGB PNG writer (Pillow cannot write 16-bit RGB)."""
    import struct
    import zlib

    h, w, _ = rgb16.shape
    raw = b"".join(b"\x00" + rgb16[y].astype(">u2").tobytes() for y in range(h))

    def chunk(tag, data):
        body = tag + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def srgb_to_linear(s):
    """IEC 61966-2-1 decoding, as pgt's PNG reader does it."""
    s = np.asarray(s, dtype=np.float64)
    return np.where(s <= 0.04045, s / 12.92, ((s + 0.055) / 1.055) ** 2.4)


def ssim_case(name, ref32, approx32, data_range, note=""):
    """One case: two H×W×3 float32 arrays and the oracle's answers."""
    assert ref32.dtype == np.float32 and approx32.dtype == np.float32
    h, w, _ = ref32.shape
    ref = ref32.astype(np.float64)
    approx = approx32.astype(np.float64)
    case = {
        "name": name,
        "note": note,
        "width": w,
        "height": h,
        "data_range": data_range,
        # Row-major, row 0 first, [r, g, b] per pixel.
        "reference": [float(v) for v in ref32.reshape(-1)],
        "approximation": [float(v) for v in approx32.reshape(-1)],
    }
    try:
        per_channel = []
        maps = []
        for c in range(3):
            m, s = structural_similarity(
                ref[:, :, c],
                approx[:, :, c],
                gaussian_weights=True,
                sigma=1.5,
                use_sample_covariance=False,
                data_range=data_range,
                full=True,
            )
            per_channel.append(float(m))
            maps.append([float(v) for v in s.reshape(-1)])
        mean = structural_similarity(
            ref,
            approx,
            gaussian_weights=True,
            sigma=1.5,
            use_sample_covariance=False,
            data_range=data_range,
            channel_axis=2,
        )
        case["ssim"] = {"per_channel": per_channel, "mean": float(mean), "maps": maps}
    except ValueError as e:
        # scikit-image refuses images smaller than the 11×11 window; pgt must refuse too.
        case["ssim"] = {"error": str(e)}
    mse = [float(mean_squared_error(ref[:, :, c], approx[:, :, c])) for c in range(3)]
    psnr = []
    for c in range(3):
        if mse[c] == 0.0:
            psnr.append(None)  # infinite; scikit-image warns and returns inf
        else:
            psnr.append(
                float(
                    peak_signal_noise_ratio(ref[:, :, c], approx[:, :, c], data_range=data_range)
                )
            )
    diff = np.abs(ref - approx)
    case["mse"] = mse
    case["psnr"] = psnr
    case["rmse"] = [float(np.sqrt(m)) for m in mse]
    case["mean_abs"] = [float(diff[:, :, c].mean()) for c in range(3)]
    case["max_abs"] = [float(diff[:, :, c].max()) for c in range(3)]
    # First pixel (row-major) where the channel's maximum is reached.
    argmax = []
    for c in range(3):
        i = int(np.argmax(diff[:, :, c]))
        argmax.append([i % w, i // w])
    case["max_abs_pixel"] = argmax
    return case


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    rng = np.random.default_rng(20261123)
    f32 = np.float32
    cases = []

    # 1. Uniform noise against noisy copy (values slightly outside [0, 1]).
    ref = rng.random((30, 40, 3)).astype(f32)
    approx = (ref + rng.normal(0.0, 0.05, ref.shape)).astype(f32)
    cases.append(ssim_case("noise", ref, approx, 1.0, "uniform noise vs +N(0, 0.05)"))

    # 2. Odd size, smooth gradients in different directions per image.
    h, w = 23, 37
    yy, xx = np.mgrid[0:h, 0:w]
    ref = np.stack([xx / (w - 1), yy / (h - 1), (xx + yy) / (w + h - 2)], axis=2).astype(f32)
    approx = np.stack([yy / (h - 1), xx / (w - 1), 0.5 * (xx + yy) / (w + h - 2)], axis=2).astype(f32)
    cases.append(ssim_case("gradients_odd", ref, approx, 1.0, "37x23 gradients"))

    # 3. Constant images: structure terms degenerate (variance 0), only luminance counts.
    ref = np.full((16, 16, 3), 0.5, dtype=f32)
    approx = np.full((16, 16, 3), [0.25, 0.5, 0.75], dtype=f32)
    cases.append(ssim_case("constant", ref, approx, 1.0, "constant 0.5 vs constant per channel"))

    # 4. Identical images: SSIM 1 and RMSE 0 exactly.
    ref = rng.random((20, 24, 3)).astype(f32)
    cases.append(ssim_case("identical", ref, ref.copy(), 1.0, "identical noise"))

    # 5. HDR values far above 1 with an explicit data range.
    ref = (np.exp(rng.normal(1.0, 1.2, (20, 32, 3)))).astype(f32)
    approx = (ref * (1.0 + rng.normal(0.0, 0.1, ref.shape))).astype(f32)
    dr = float(ref.astype(np.float64).max() - min(0.0, float(ref.min())))
    cases.append(ssim_case("hdr", ref, approx, dr, "log-normal HDR values, data_range = max(ref)"))

    # 6. HDR with data range 1 (what a user gets without --data-range): still must match.
    cases.append(ssim_case("hdr_range1", ref, approx, 1.0, "HDR values, data_range 1"))

    # 7. Exactly the window size.
    ref = rng.random((11, 11, 3)).astype(f32)
    approx = (ref * 0.8 + 0.1).astype(f32)
    cases.append(ssim_case("window_11", ref, approx, 1.0, "11x11, one valid pixel after cropping"))

    # 8. Thin image.
    ref = rng.random((11, 64, 3)).astype(f32)
    approx = np.clip(ref + rng.normal(0.0, 0.2, ref.shape), 0, 1).astype(f32)
    cases.append(ssim_case("thin_11x64", ref, approx, 1.0, "11 rows"))

    # 9. Anti-correlated: negative SSIM.
    ref = rng.random((24, 24, 3)).astype(f32)
    cases.append(ssim_case("inverted", ref, (1.0 - ref).astype(f32), 1.0, "1 - ref"))

    # 10. Smaller than the window: scikit-image raises ValueError.
    ref = rng.random((8, 30, 3)).astype(f32)
    cases.append(ssim_case("too_small", ref, (ref * 0.5).astype(f32), 1.0, "8 rows < 11"))

    # 11. Negative values and a sparse bright feature (difference-like images).
    ref = (rng.random((25, 19, 3)) - 0.3).astype(f32)
    approx = ref.copy()
    approx[12, 9, :] += 3.0
    cases.append(ssim_case("spike", ref, approx.astype(f32), 4.0, "one pixel +3, data_range 4"))

    # 12. 16-bit sRGB PNGs on disk, decoded to linear (tests the PNG reader end to end).

    h, w = 18, 24
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx / (w - 1), yy / (h - 1), 0.5 + 0.5 * np.sin(xx * 0.7 + yy * 0.3)], axis=2)
    ref16 = np.round(base * 65535).astype(np.uint16)
    app16 = np.clip(np.round((base + rng.normal(0, 0.03, base.shape)) * 65535), 0, 65535).astype(np.uint16)
    write_png16(os.path.join(out_dir, "png16_ref.png"), ref16)
    write_png16(os.path.join(out_dir, "png16_approx.png"), app16)
    # (Pillow reads 16-bit RGB as 8-bit, so no read-back here: pgt's test decodes the files and
    # must reproduce the SSIM of the arrays written.)
    ref_lin = srgb_to_linear(ref16 / 65535.0).astype(f32)
    app_lin = srgb_to_linear(app16 / 65535.0).astype(f32)
    c = ssim_case("png16", ref_lin, app_lin, 1.0, "png16_ref.png vs png16_approx.png, linear")
    c["files"] = ["png16_ref.png", "png16_approx.png"]
    cases.append(c)

    doc = {
        "generator": "scripts/ssim_vectors.py",
        "scikit_image": skimage.__version__,
        "numpy": np.__version__,
        "call": "structural_similarity(gaussian_weights=True, sigma=1.5, "
        "use_sample_covariance=False, data_range=R[, channel_axis=2])",
        "cases": cases,
    }
    with open(os.path.join(out_dir, "ssim_vectors.json"), "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")

    flip_vectors(out_dir, rng)


def flip_vectors(out_dir, rng):
    """LDR-FLIP means and maps from NVIDIA's flip-evaluator, on 8-bit sRGB PNGs."""
    try:
        import flip_evaluator as flip
    except ImportError:
        print("flip-evaluator not installed; no FLIP vectors", file=sys.stderr)
        return

    h, w = 40, 48
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack(
        [xx / (w - 1), 0.5 + 0.5 * np.cos(yy * 0.4), 0.5 + 0.5 * np.sin(xx * 0.5 + yy * 0.2)], axis=2
    )
    ref8 = np.round(base * 255).astype(np.uint8)
    noisy = base + rng.normal(0, 0.04, base.shape)
    noisy[10:20, 10:20, :] = [1.0, 0.0, 0.0]
    app8 = np.clip(np.round(noisy * 255), 0, 255).astype(np.uint8)
    iio.imwrite(os.path.join(out_dir, "flip_ref.png"), ref8)
    iio.imwrite(os.path.join(out_dir, "flip_approx.png"), app8)
    err, mean, params = flip.evaluate(
        ref8.astype(np.float32) / 255.0,
        app8.astype(np.float32) / 255.0,
        "LDR",
        applyMagma=False,
    )
    err = np.asarray(err, dtype=np.float64).reshape(h, w)
    doc = {
        "generator": "scripts/ssim_vectors.py",
        "flip_evaluator": getattr(flip, "__version__", "unknown"),
        "files": ["flip_ref.png", "flip_approx.png"],
        "ppd": float(params.get("ppd", 67.0)),
        "mean": float(mean),
        "map": [float(v) for v in err.reshape(-1)],
    }

    # HDR-FLIP on float32 linear images (no zero median luminance, so that FLIP's automatic
    # exposure range is defined).
    h, w = 36, 44
    yy, xx = np.mgrid[0:h, 0:w]
    light = np.exp(rng.normal(0.0, 1.0, (h, w, 1))) * (0.2 + 4.0 * xx[..., None] / (w - 1))
    tint = np.stack([0.9 + 0.1 * np.sin(0.3 * yy), 0.7 + 0.3 * np.cos(0.2 * xx), 0.5 + 0.0 * xx], axis=2)
    ref = (light * tint).astype(np.float32)
    test = (ref * (1.0 + rng.normal(0.0, 0.15, ref.shape))).clip(0.0, None).astype(np.float32)
    herr, hmean, hparams = flip.evaluate(ref, test, "HDR", applyMagma=False)
    doc["hdr"] = {
        "width": w,
        "height": h,
        "reference": [float(v) for v in ref.reshape(-1)],
        "approximation": [float(v) for v in test.reshape(-1)],
        "mean": float(hmean),
        "start_exposure": float(hparams["startExposure"]),
        "stop_exposure": float(hparams["stopExposure"]),
        "num_exposures": int(hparams["numExposures"]),
        "tonemapper": str(hparams.get("tonemapper", "ACES")),
        "map": [float(v) for v in np.asarray(herr, dtype=np.float64).reshape(-1)],
    }
    with open(os.path.join(out_dir, "flip_vectors.json"), "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data/compare")
