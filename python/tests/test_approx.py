"""pgt.approx: the GPU methods on whatever adapter wgpu finds (lavapipe in CI), bit-identical
to `pgt approx`, and the errors: no adapter, unknown method, bad parameter."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import pgt
from conftest import REPO, bits, in_ci


@pytest.fixture
def scene(example):
    return pgt.load_scene(example("disjoint_lit.toml"), size=(40, 32))


@pytest.fixture
def gpu(scene):
    """Skips (fails under CI=true) without a GPU adapter."""
    try:
        pgt.approx(pgt.load_scene(scene.source, size=(4, 4)))
    except pgt.NoAdapterError as e:
        if in_ci():
            pytest.fail(f"CI=true and no GPU adapter: {e}")
        pytest.skip(f"no GPU adapter ({e})")


def test_methods_are_listed():
    methods = {m["name"]: m for m in pgt.approx_methods()}
    assert {"thesis", "sorted-blend", "opaque"} <= set(methods)
    params = {p["name"]: p for p in methods["thesis"]["params"]}
    assert {"samples", "n_exact"} <= set(params)
    assert params["samples"]["min"] <= params["samples"]["default"] <= params["samples"]["max"]


@pytest.mark.parametrize(
    "model, method, params, flags",
    [
        (None, None, {}, []),
        (None, "thesis", {"samples": 8, "n_exact": "all"}, ["--method", "thesis", "--samples", "8", "--n-exact", "all"]),
        ("emission", "sorted-blend", {}, ["--model", "emission", "--method", "sorted-blend"]),
    ],
)
def test_bit_identical_to_the_cli(gpu, example, tmp_path, run_cli, model, method, params, flags):
    out = tmp_path / "cli.exr"
    run_cli("approx", example("disjoint_lit.toml"), "--size", "40x32", "-o", out, *flags)
    scene = pgt.load_scene(example("disjoint_lit.toml"), size=(40, 32), model=model)
    result = pgt.approx(scene, method, **params)
    assert result.image.shape == (32, 40, 3) and result.image.dtype == np.float32
    np.testing.assert_array_equal(bits(result.image), bits(pgt.read_image(out)))
    assert result.method == (method or "thesis")
    assert result.gpu_seconds > 0 and result.passes >= 1 and result.adapter
    assert result.image.max() > 0, "the particles are lit, so the image is not black"
    if method == "thesis":
        assert dict(result.params) == {"samples": 8, "n_exact": pgt._pgt.N_EXACT_ALL}


def test_a_user_shader(gpu, scene, example, tmp_path, run_cli):
    shader = REPO / "shaders" / "examples" / "no_shadows.wgsl"
    out = tmp_path / "cli.exr"
    run_cli("approx", example("disjoint_lit.toml"), "--size", "40x32", "--shader", shader, "-o", out)
    result = pgt.approx(scene, shader=shader)
    np.testing.assert_array_equal(bits(result.image), bits(pgt.read_image(out)))
    assert result.method.startswith("user shader")
    broken = tmp_path / "broken.wgsl"
    broken.write_text("fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> { return oops; }\n")
    with pytest.raises(pgt.Error, match="broken.wgsl"):
        pgt.approx(scene, shader=broken)


def test_argument_errors(scene):
    with pytest.raises(pgt.InputError, match="unknown approximation method 'fast'; the methods are: "):
        pgt.approx(scene, "fast")
    with pytest.raises(pgt.InputError, match="give a method or a shader, not both"):
        pgt.approx(scene, "thesis", shader="x.wgsl")
    with pytest.raises(pgt.InputError, match="samples: expected a non-negative integer or 'all', got -3"):
        pgt.approx(scene, "thesis", samples=-3)
    with pytest.raises(pgt.InputError, match="method thesis has no parameter 'wiggles'"):
        pgt.approx(scene, "thesis", wiggles=3)


def test_no_adapter_says_what_to_install():
    """Without any Vulkan driver wgpu finds no adapter: a NoAdapterError (a GpuError, a
    RuntimeError) with the CLI's message. In a subprocess: the loader reads the variables once."""
    code = (
        "import pgt, sys\n"
        "s = pgt.Scene.from_arrays([[0, 0, 0]], [1.0], size=(4, 4))\n"
        "try:\n"
        "    pgt.approx(s)\n"
        "except pgt.NoAdapterError as e:\n"
        "    assert isinstance(e, pgt.GpuError) and isinstance(e, RuntimeError)\n"
        "    print(e)\n"
        "    sys.exit(0)\n"
        "sys.exit(1)\n"
    )
    env = {
        **os.environ,
        "VK_ICD_FILENAMES": "/nonexistent/icd.json",
        "VK_DRIVER_FILES": "/nonexistent/icd.json",
    }
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "install mesa-vulkan-drivers and libvulkan1" in done.stdout
