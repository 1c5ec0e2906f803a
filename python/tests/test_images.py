"""Image files: EXR with the err layer and PNG, read and written as the CLI does."""

from __future__ import annotations

import numpy as np
import pytest

import pgt
from conftest import bits


def test_exr_round_trip_with_err_layer(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.uniform(0, 3, (5, 7, 3)).astype(np.float32)
    err = rng.uniform(0, 1e-5, (5, 7, 3)).astype(np.float32)
    path = tmp_path / "a.exr"
    pgt.write_image(path, image, err=err)
    np.testing.assert_array_equal(bits(pgt.read_image(path)), bits(image))
    np.testing.assert_array_equal(bits(pgt.read_image(path, layer="err")), bits(err))
    # float64 is stored as float32.
    pgt.write_image(path, image.astype(np.float64))
    np.testing.assert_array_equal(bits(pgt.read_image(path)), bits(image))


def test_png_is_srgb_of_the_linear_image_with_exposure(tmp_path):
    image = np.array([[[0.0, 0.5, 1.0], [0.25, 0.25, 2.0]]], dtype=np.float32)
    path = tmp_path / "a.png"
    pgt.write_image(path, image)
    back = pgt.read_image(path)
    # 8-bit sRGB: values come back within one code; 2.0 is clamped to 1.
    np.testing.assert_allclose(back, np.clip(image, 0, 1), atol=0.01)
    pgt.write_image(path, image, exposure=-1.0)
    np.testing.assert_allclose(pgt.read_image(path), np.clip(image / 2, 0, 1), atol=0.01)
    with pytest.raises(pgt.InputError, match="a PNG has no layers"):
        pgt.read_image(path, layer="err")
    with pytest.raises(pgt.InputError, match="--exposure must be a finite number"):
        pgt.write_image(path, image, exposure=float("inf"))


def test_image_file_errors(tmp_path):
    with pytest.raises(pgt.InputError, match="output must end in .exr or .png"):
        pgt.write_image(tmp_path / "a.tiff", np.zeros((2, 2, 3), np.float32))
    # A folder that cannot be made (a file stands where it would go): an OSError with errno.
    (tmp_path / "plain").write_text("a file, not a folder")
    with pytest.raises(pgt.FileError, match="plain") as e:
        pgt.write_image(tmp_path / "plain" / "a.exr", np.zeros((2, 2, 3), np.float32))
    assert isinstance(e.value, OSError) and e.value.errno is not None
    broken = tmp_path / "broken.exr"
    broken.write_bytes(b"not an exr at all")
    with pytest.raises(pgt.InputError, match="broken.exr: cannot read EXR"):
        pgt.read_image(broken)
    with pytest.raises(pgt.FileError, match="missing.exr: No such file or directory"):
        pgt.read_image(tmp_path / "missing.exr")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.exr", "plain"], "nothing half-written"
