"""pgt.render: the CLI's values bit for bit, the summary, progress, and the options."""

from __future__ import annotations

import numpy as np
import pytest

import pgt
from conftest import bits, in_ci


def cli_render(run_cli, tmp_path, scene_path, *flags):
    """The CLI's EXR, its image and its err layer (None in opaque mode, which has none)."""
    out = tmp_path / "cli.exr"
    run_cli("render", scene_path, "-o", out, *flags)
    try:
        err = pgt.read_image(out, layer="err")
    except pgt.InputError as e:
        assert "has no layer 'err'" in str(e)
        err = None
    return out, pgt.read_image(out), err


@pytest.mark.parametrize(
    "name, flags, size",
    [
        ("disjoint_lit.toml", [], (64, 48)),
        ("inside.toml", [], (40, 30)),
        ("shadows.toml", ["--spp", "2"], (32, 32)),
        ("disjoint_lit.toml", ["--model", "single-scatter", "--tol", "1e-4"], (48, 48)),
    ],
)
def test_bit_identical_to_the_cli(tmp_path, run_cli, example, name, flags, size):
    scene_path = example(name)
    w, h = size
    cli_out, cli_image, cli_err = cli_render(run_cli, tmp_path, scene_path, "--size", f"{w}x{h}", *flags)
    model = flags[flags.index("--model") + 1] if "--model" in flags else None
    tol = float(flags[flags.index("--tol") + 1]) if "--tol" in flags else None
    spp = int(flags[flags.index("--spp") + 1]) if "--spp" in flags else 1
    scene = pgt.load_scene(scene_path, size=size, model=model)
    result = pgt.render(scene, spp=spp, tol=tol)
    assert result.image.shape == (h, w, 3)
    np.testing.assert_array_equal(bits(result.image), bits(cli_image))
    if scene.mode == "opaque":
        assert result.err is None and cli_err is None
    else:
        np.testing.assert_array_equal(bits(result.err), bits(cli_err))
    # Written from Python, the file is the CLI's byte for byte.
    mine = tmp_path / "py.exr"
    result.write(mine)
    assert mine.read_bytes() == cli_out.read_bytes()


def test_bit_identical_to_the_cli_on_1uun(tmp_path, run_cli, shared):
    pdb = shared("pdb/1uun_opm_oriented.pdb")
    _, cli_image, cli_err = cli_render(run_cli, tmp_path, pdb, "--size", "48x48")
    result = pgt.render(pgt.load_scene(pdb, size=(48, 48)), threads=2)
    np.testing.assert_array_equal(bits(result.image), bits(cli_image))
    np.testing.assert_array_equal(bits(result.err), bits(cli_err))


def test_summary_attributes(small_scene):
    result = pgt.render(small_scene)
    assert result.primary_rays == 48 * 32
    assert result.shadow_rays > 0
    assert result.seconds > 0
    assert result.max_error == pytest.approx(float(result.err.max()), rel=1e-6)
    assert result.mean_error == pytest.approx(float(result.err.astype(np.float64).mean()), rel=1e-6)
    assert result.unconverged == 0 and result.worst_unconverged is None
    assert result.tol == 1e-5
    assert "48x32" in repr(result)
    twice = pgt.render(small_scene, spp=2, threads=1)
    assert twice.primary_rays == 4 * 48 * 32
    assert not np.array_equal(twice.image, result.image)


def test_tol_integrator_and_their_errors(small_scene):
    coarse = pgt.render(small_scene, tol=1e-2)
    assert coarse.tol == 1e-2 and small_scene.tol == 1e-5
    riemann = pgt.render(small_scene, integrator="riemann", samples=3)
    assert riemann.image.shape == (32, 48, 3)
    with pytest.raises(pgt.InputError, match="--tol must be a finite number > 0, got -1"):
        pgt.render(small_scene, tol=-1.0)
    with pytest.raises(pgt.InputError, match="--spp must be between 1 and 64, got 0"):
        pgt.render(small_scene, spp=0)
    with pytest.raises(pgt.InputError, match="integrator: expected 'adaptive' or 'riemann'"):
        pgt.render(small_scene, integrator="simpson")
    with pytest.raises(pgt.InputError, match="--samples must be at least 1"):
        pgt.render(small_scene, integrator="riemann", samples=0)


def test_opaque_mode_has_no_err_layer(tmp_path, example):
    scene = pgt.load_scene(example("disjoint_lit.toml"), size=(16, 16), mode="opaque")
    result = pgt.render(scene)
    assert result.err is None and result.max_error is None
    result.write(tmp_path / "o.exr")
    with pytest.raises(pgt.InputError, match="err"):
        pgt.read_image(tmp_path / "o.exr", layer="err")


def test_progress_callback_sees_every_tile(small_scene):
    seen = []
    pgt.render(small_scene, progress=lambda done, total: seen.append((done, total)))
    # 48x32 pixels are 3x2 tiles of 16x16; the last call reports all of them.
    assert seen and seen[-1] == (6, 6)
    assert all(total == 6 and 0 <= done <= 6 for done, total in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


def test_progress_true_and_bad_progress(small_scene, capsys):
    pgt.render(small_scene, progress=True)
    err = capsys.readouterr().err
    # tqdm's bar or the plain line, both on stderr and both end at 100 %.
    assert "100%" in err
    with pytest.raises(pgt.InputError, match="progress: expected None, True or a callable"):
        pgt.render(small_scene, progress="yes")


def test_progress_true_uses_tqdm_when_installed(small_scene, monkeypatch):
    """progress=True draws a tqdm.auto bar where tqdm is importable (a stand-in here)."""
    import sys
    import types

    bars = []

    class FakeTqdm:
        def __init__(self, total, unit, desc):
            self.total, self.n, self.closed = total, 0, False
            bars.append(self)

        def update(self, k):
            self.n += k

        def close(self):
            self.closed = True

    auto = types.ModuleType("tqdm.auto")
    auto.tqdm = FakeTqdm
    package = types.ModuleType("tqdm")
    package.auto = auto
    monkeypatch.setitem(sys.modules, "tqdm", package)
    monkeypatch.setitem(sys.modules, "tqdm.auto", auto)
    pgt.render(small_scene, progress=True)
    assert len(bars) == 1
    assert (bars[0].n, bars[0].total, bars[0].closed) == (6, 6, True)


def test_an_exception_in_the_progress_callback_stops_the_render(small_scene):
    class Stop(Exception):
        pass

    def callback(done, total):
        raise Stop

    with pytest.raises(Stop):
        pgt.render(small_scene, progress=callback)


def test_unconverged_pixels_warn(tmp_path):
    # A point light inside gas: the ray through it cannot converge (docs/design.md §3).
    path = tmp_path / "lamp.toml"
    path.write_text(
        "[camera]\nposition = [0, 0, -5]\nlook_at = [0, 0, 0]\nwidth = 9\nheight = 9\n"
        "[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = [1, 1, 1]\n"
        "[[particles]]\ncenter = [0, 0, 0]\nradius = 1.0\nopacity = 0.9\n"
    )
    scene = pgt.load_scene(path)
    with pytest.warns(pgt.PgtWarning, match=r"pixel\(s\) did not reach tol"):
        result = pgt.render(scene)
    assert result.unconverged >= 1
    x, y, e = result.worst_unconverged
    assert (x, y) == (4, 4) and e > scene.tol


def test_render_on_the_gpu_is_the_cli_s_and_within_both_errs_of_the_cpu(example, tmp_path, run_cli):
    """gpu=True is `pgt render --gpu` bit for bit (image and err), and within err_gpu + err_cpu
    of the CPU reference (docs/design.md §12)."""
    path = example("ellipsoids.toml")
    scene = pgt.load_scene(path, size=(24, 20), model="emission")
    try:
        gpu = pgt.render(scene, gpu=True)
    except pgt.NoAdapterError as e:
        if in_ci():
            pytest.fail(f"CI=true and no GPU adapter: {e}")
        pytest.skip(f"no GPU adapter ({e})")
    out = tmp_path / "gpu.exr"
    run_cli("render", "--gpu", path, "--size", "24x20", "--model", "emission", "-o", out)
    np.testing.assert_array_equal(bits(gpu.image), bits(pgt.read_image(out)))
    np.testing.assert_array_equal(bits(gpu.err), bits(pgt.read_image(out, layer="err")))
    cpu = pgt.render(scene)
    difference = np.abs(gpu.image.astype(np.float64) - cpu.image)
    assert (difference <= gpu.err.astype(np.float64) + cpu.err).all()


def test_render_on_the_gpu_renders_gaussians_within_both_errs_of_the_cpu(example):
    """Gaussian particles take the same path (docs/design.md §12)."""
    scene = pgt.load_scene(example("gaussians.toml"), size=(12, 10), model="emission")
    try:
        gpu = pgt.render(scene, gpu=True)
    except pgt.NoAdapterError as e:
        if in_ci():
            pytest.fail(f"CI=true and no GPU adapter: {e}")
        pytest.skip(f"no GPU adapter ({e})")
    cpu = pgt.render(scene)
    difference = np.abs(gpu.image.astype(np.float64) - cpu.image)
    assert (difference <= gpu.err.astype(np.float64) + cpu.err).all()
    assert gpu.unconverged == 0


def test_render_on_the_gpu_refuses_a_lit_scene_by_name(example):
    scene = pgt.load_scene(example("ellipsoids.toml"), size=(8, 8), model="lit")
    with pytest.raises(pgt.GpuError, match="lit"):
        pgt.render(scene, gpu=True)
