"""Arrays of the wrong shape or dtype, or with NaN or infinity, are refused with an InputError
(a ValueError) that names the argument; good arrays in any float layout are taken."""

from __future__ import annotations

import numpy as np
import pytest

import pgt
from conftest import random_particles

CENTERS, RADII, COLORS, OPACITY = random_particles(6)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"centers": CENTERS[:, :2]}, r"centers: expected an array of shape \(n, 3\), got shape \(6, 2\)"),
        ({"centers": CENTERS.ravel()}, r"centers: expected an array of shape \(n, 3\), got shape \(18,\)"),
        ({"radii": RADII[:5]}, r"radii: expected an array of shape \(6,\), got shape \(5,\) \(n = 6"),
        ({"colors": COLORS[:, :1]}, r"colors: expected an array of shape \(6, 3\)"),
        ({"opacity": OPACITY[:, None]}, r"opacity: expected an array of shape \(6,\)"),
        ({"centers": CENTERS.astype(np.int64)}, "centers: expected float32 or float64 values, got dtype int64"),
        ({"radii": RADII.astype(np.complex128)}, "radii: expected float32 or float64 values, got dtype complex128"),
        ({"colors": COLORS.astype(object)}, "colors: expected float32 or float64 values, got dtype object"),
        ({"centers": np.where(np.arange(18).reshape(6, 3) == 7, np.nan, CENTERS)}, r"centers: non-finite value \(NaN\) at row 2, column 1"),
        ({"radii": np.where(np.arange(6) == 4, np.inf, RADII)}, r"radii: non-finite value \(inf\) at index 4"),
        ({"opacity": float("nan")}, r"opacity: non-finite value \(NaN\)"),
        ({"centers": [[0, 0], [1, 1]]}, r"centers: expected an array of shape \(n, 3\), got shape \(2, 2\)"),
        ({"centers": [[0, 0, 0], [1, 1]]}, "centers: expected an array of numbers"),
    ],
)
def test_from_arrays_refuses_bad_arrays(kwargs, message):
    args = {"centers": CENTERS, "radii": RADII, "colors": COLORS, "opacity": OPACITY, **kwargs}
    with pytest.raises(pgt.InputError, match=message) as e:
        pgt.Scene.from_arrays(**args)
    assert isinstance(e.value, ValueError)


def test_from_arrays_takes_any_float_layout():
    want = pgt.Scene.from_arrays(CENTERS, RADII, COLORS, OPACITY).particles()
    # Fortran order, a strided view, float32 (exact for these values after the round trip
    # below), lists.
    f32 = CENTERS.astype(np.float32)
    strided = np.zeros((6, 6))
    strided[:, ::2] = CENTERS
    got = pgt.Scene.from_arrays(np.asfortranarray(CENTERS), RADII, COLORS, OPACITY).particles()
    np.testing.assert_array_equal(got["center"], want["center"])
    got = pgt.Scene.from_arrays(strided[:, ::2], RADII.tolist(), COLORS, OPACITY).particles()
    np.testing.assert_array_equal(got["center"], want["center"])
    got = pgt.Scene.from_arrays(f32, RADII, COLORS, OPACITY).particles()
    np.testing.assert_array_equal(got["center"], f32.astype(np.float64))


def image(h=8, w=9, seed=3, dtype=np.float32):
    return np.random.default_rng(seed).uniform(0, 1, size=(h, w, 3)).astype(dtype)


@pytest.mark.parametrize(
    "bad, message",
    [
        (image()[..., :2], r"approximation: expected an array of shape \(H, W, 3\), got shape \(8, 9, 2\)"),
        (image()[0], r"approximation: expected an array of shape \(H, W, 3\), got shape \(9, 3\)"),
        (np.zeros((0, 4, 3), np.float32), "approximation: an image needs at least one pixel"),
        ((image() * 255).astype(np.uint8), "approximation: expected float32 or float64 values, got dtype uint8"),
        (np.where(np.arange(3) == 2, np.nan, image()), r"approximation: non-finite value \(NaN\) at row 0, column 2"),
        (np.full((8, 9, 3), 1e300), r"approximation: value 1e300 at pixel \(0, 0\), channel R is beyond the range of float32"),
        ("not/an/image.txt", "expected an .exr or .png image"),
    ],
)
def test_compare_refuses_bad_images(bad, message):
    with pytest.raises(pgt.Error, match=message):
        pgt.compare(image(), bad)


def test_compare_takes_float64_and_strided_images():
    a, b = image(16, 16, seed=1), image(16, 16, seed=2)
    want = pgt.compare(a, b)
    assert want.ssim is not None
    strided = np.zeros((16, 32, 3), np.float32)
    strided[:, ::2] = b
    for variant in (strided[:, ::2], b.astype(np.float64), np.asfortranarray(b)):
        got = pgt.compare(a, variant)
        assert (got.rmse.mean, got.ssim.mean) == (want.rmse.mean, want.ssim.mean)


def test_write_image_refuses_bad_arrays(tmp_path):
    with pytest.raises(pgt.InputError, match=r"image: non-finite value \(inf\)"):
        pgt.write_image(tmp_path / "x.exr", np.full((2, 2, 3), np.inf, np.float32))
    with pytest.raises(pgt.InputError, match=r"err: expected the image's shape \(2, 2, 3\), got \(2, 3, 3\)"):
        pgt.write_image(tmp_path / "x.exr", np.zeros((2, 2, 3), np.float32), err=np.zeros((2, 3, 3), np.float32))
    assert list(tmp_path.iterdir()) == []


def test_images_come_out_without_a_copy(small_scene):
    """The render's arrays are views of the library's own buffers, handed over, not copied:
    numpy does not own their data (a PySliceContainer keeps the Rust allocation alive)."""
    result = pgt.render(small_scene)
    for a in (result.image, result.err):
        assert a.dtype == np.float32 and a.shape == (32, 48, 3)
        assert a.flags.c_contiguous and not a.flags.owndata
        assert type(a.base).__name__ == "PySliceContainer"
