"""The worked case of examples/splat.py: a numpy splatting renderer gated against pgt's truth."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pgt

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "splat.py"


@pytest.fixture(scope="module")
def splat():
    spec = importlib.util.spec_from_file_location("splat_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def measured(splat):
    scene = splat.make_scene()
    return scene, pgt.render(scene)


def test_the_splatting_renderer_passes_its_gate(splat, measured):
    scene, truth = measured
    cmp = pgt.compare(truth, splat.splat(scene))
    result = cmp.gate(splat.GATE)
    assert result, result.verdict
    # Not identical, though: the overlaps are wrong, and the metrics see it.
    assert 0 < cmp.rmse.mean and cmp.ssim.mean < 1


def test_the_gate_fails_a_renderer_that_sorts_the_wrong_way(splat, measured):
    scene, truth = measured
    wrong = pgt.compare(truth, splat.splat(scene, order="front-to-back")).gate(splat.GATE)
    assert not wrong, wrong.verdict
    assert wrong.verdict.startswith("FAIL")
    assert [c.name for c in wrong.failed] == ["min_ssim", "max_rmse", "p99(abs) <= max"]


def test_a_single_particle_is_exact(splat):
    """Without overlaps, splatting is the emission closed form: it agrees with pgt to float32
    rounding, so the differences above come from the overlaps, not from a broken camera."""
    scene = pgt.Scene.from_arrays([[0.1, -0.2, 0.3]], [0.6], [[0.9, 0.5, 0.2]], 0.7, model="emission", size=(64, 48))
    cmp = pgt.compare(pgt.render(scene), splat.splat(scene))
    assert cmp.max_abs[0][1] < 1e-5 and cmp.max_abs[1][1] < 1e-5, cmp.max_abs


def test_the_script_writes_its_report(tmp_path):
    report = tmp_path / "report"
    done = subprocess.run([sys.executable, str(EXAMPLE), str(report)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.startswith("PASS")
    assert (report / "index.html").is_file() and (report / "abs_error.png").is_file()
    assert np.isfinite(pgt.read_image(report / "maps.exr")).all()
