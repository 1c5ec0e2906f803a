"""pgt.compare: the CLI's metrics, gates and report, from arrays or files."""

from __future__ import annotations

import json

import numpy as np
import pytest

import pgt


@pytest.fixture
def pair(tmp_path, example):
    """A reference (with its err layer) and a perturbed copy, as arrays and as EXR files."""
    scene = pgt.load_scene(example("disjoint_lit.toml"), size=(48, 40))
    truth = pgt.render(scene)
    rng = np.random.default_rng(4)
    approx = np.clip(truth.image + rng.normal(0, 0.01, truth.image.shape), 0, None).astype(np.float32)
    ref_path, approx_path = tmp_path / "ref.exr", tmp_path / "approx.exr"
    truth.write(ref_path)
    pgt.write_image(approx_path, approx)
    return truth, approx, ref_path, approx_path


def without_run_facts(summary):
    """The summary without what differs between two runs (wall time, input labels)."""
    return {k: v for k, v in summary.items() if k not in ("seconds", "reference", "approximation")}


def test_metrics_match_the_cli_from_files_and_from_arrays(pair, run_cli):
    truth, approx, ref_path, approx_path = pair
    printed = json.loads(run_cli("compare", ref_path, approx_path, "--json", "-").stdout)
    from_files = pgt.compare(ref_path, approx_path)
    from_arrays = pgt.compare(truth, approx)
    assert from_files.summary() == {**printed, "seconds": from_files.summary()["seconds"]}
    assert without_run_facts(from_arrays.summary()) == without_run_facts(printed)
    assert from_arrays.summary()["reference"] == "array"
    # The attributes are the summary's numbers.
    s = printed
    assert from_arrays.ssim.as_dict() == s["ssim"]
    assert from_arrays.rmse.as_dict() == s["rmse"]
    assert from_arrays.psnr.mean == s["psnr"]["mean"]
    assert from_arrays.mean_abs.r == s["mean_abs"]["R"]
    assert from_arrays.mean_rel.b == s["mean_rel"]["B"]
    assert from_arrays.flip == s["flip"]
    assert [(c, v, list(p)) for c, v, p in from_arrays.max_abs] == [
        (m["channel"], m["value"], m["pixel"]) for m in s["max_abs"]
    ]
    assert from_arrays.data_range == s["data_range"] == 1.0
    assert from_arrays.data_range_source == s["data_range_source"] == "default"
    # The err layer of the reference file, or the RenderResult's err, is its uncertainty.
    assert from_arrays.reference_uncertainty == s["reference_uncertainty"]
    assert pgt.compare(truth.image, approx).reference_uncertainty is None
    assert from_arrays.verdict() == run_cli("compare", ref_path, approx_path).stdout.strip()


def test_maps(pair):
    truth, approx, _, _ = pair
    cmp = pgt.compare(truth, approx)
    abs_error = cmp.abs_error
    assert abs_error.shape == (40, 48, 3) and abs_error.dtype == np.float32
    np.testing.assert_array_equal(abs_error, np.abs(approx - truth.image))
    assert cmp.abs_error is abs_error, "maps are computed once"
    assert not abs_error.flags.writeable
    rel = cmp.rel_error
    np.testing.assert_allclose(rel, np.abs(approx - truth.image) / (np.abs(truth.image) + 0.01), rtol=1e-5)
    assert cmp.ssim_map.shape == (40, 48, 3)
    assert cmp.flip_map.shape == (40, 48)
    assert abs(float(cmp.flip_map.astype(np.float64).mean()) - cmp.flip) < 1e-6
    no_flip = pgt.compare(truth, approx, flip=False)
    assert no_flip.flip is None and no_flip.flip_map is None and "not requested" in no_flip.flip_note


def test_gates_as_the_cli_evaluates_them(pair, tmp_path, run_cli):
    truth, approx, ref_path, approx_path = pair
    cmp = pgt.compare(truth, approx)
    loose = {"min_ssim": 0.5, "max_rmse": 0.1, "channels": {"max_abs": [1, 1, 1]}}
    tight = {"min_ssim": 0.999999, "percentiles": [{"map": "abs", "percentile": 99.0, "max": 1e-6}]}
    assert cmp.gate(loose) and cmp.gate(loose).passed is True
    result = cmp.gate(tight)
    assert not result and result.passed is False
    assert [c.name for c in result.failed] == ["min_ssim", "p99(abs) <= max"]
    assert result.verdict.startswith("FAIL")
    gate_file = tmp_path / "gate.toml"
    gate_file.write_text('min_ssim = 0.999999\n[[percentiles]]\nmap = "abs"\npercentile = 99.0\nmax = 1e-6\n')
    from_file = cmp.gate(gate_file)
    assert [(c.name, c.value, c.threshold, c.passed) for c in from_file.checks] == [
        (c.name, c.value, c.threshold, c.passed) for c in result.checks
    ]
    cli = run_cli("compare", ref_path, approx_path, "--gate", gate_file, check=False)
    assert cli.returncode == 1
    assert cli.stdout.strip() == pgt.compare(ref_path, approx_path).gate(gate_file).verdict
    assert cmp.summary(tight)["passed"] is False and cmp.summary()["passed"] is None


def test_the_readme_assert_pattern_names_the_failed_gate(pair):
    truth, approx, _, _ = pair
    cmp = pgt.compare(truth, approx)
    with pytest.raises(AssertionError) as failed:
        assert (gate := cmp.gate({"min_ssim": 0.999999})), gate.verdict
    assert str(failed.value).startswith("FAIL") and "min_ssim = " in str(failed.value)
    # The result prints as its verdict, so a bare `assert cmp.gate(...)` shows it too.
    assert str(cmp.gate({"min_ssim": 0.999999})) == cmp.gate({"min_ssim": 0.999999}).verdict


def test_gate_errors(pair, tmp_path):
    truth, approx, _, _ = pair
    cmp = pgt.compare(truth, approx)
    with pytest.raises(pgt.InputError, match="unknown field `min_sim`"):
        cmp.gate({"min_sim": 0.9})
    with pytest.raises(pgt.InputError, match="^gate: min_ssim must be a finite number, got NaN"):
        cmp.gate({"min_ssim": float("nan")})
    with pytest.raises(pgt.InputError, match="percentile must be in"):
        cmp.gate({"percentiles": [{"map": "abs", "percentile": 0, "max": 1}]})
    with pytest.raises(pgt.FileError):
        cmp.gate(tmp_path / "missing.toml")
    with pytest.raises(pgt.InputError, match="gate: expected a dict of thresholds or the path"):
        cmp.gate(3)
    with pytest.raises(pgt.InputError, match="gate: max_temporal_p99 gates the temporal error of a sequence"):
        cmp.gate({"max_temporal_p99": 0.1})


def test_report_is_the_clis(pair, tmp_path, run_cli):
    truth, approx, ref_path, approx_path = pair
    gate = {"min_ssim": 0.5}
    gate_file = tmp_path / "gate.toml"
    gate_file.write_text("min_ssim = 0.5\n")
    run_cli("compare", ref_path, approx_path, "--report", tmp_path / "cli", "--gate", gate_file)
    page = pgt.compare(ref_path, approx_path).write_report(tmp_path / "py", gate=gate)
    assert str(page) == str(tmp_path / "py" / "index.html")
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    py_files = sorted(p.name for p in (tmp_path / "py").iterdir())
    assert py_files == cli_files and "index.html" in py_files
    for name in cli_files:
        if name.endswith((".png", ".exr")):
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    summary = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert summary["passed"] is True and summary["gates"][0]["name"] == "min_ssim"
    with pytest.raises(pgt.InputError, match="--error-scale must be a finite number > 0"):
        pgt.compare(truth, approx).write_report(tmp_path / "bad", error_scale=0.0)
    assert not (tmp_path / "bad").exists()


def test_compare_errors_and_options(pair, tmp_path):
    truth, approx, ref_path, _ = pair
    with pytest.raises(pgt.InputError, match="images differ in size: reference 48x40, approximation 47x40"):
        pgt.compare(truth, approx[:, :47])
    with pytest.raises(pgt.InputError, match="--data-range must be a finite number > 0"):
        pgt.compare(truth, approx, data_range=-1.0)
    with pytest.raises(pgt.InputError, match="--ppd must be a finite number > 0"):
        pgt.compare(truth, approx, ppd=0.0)
    with pytest.raises(pgt.FileError):
        pgt.compare(tmp_path / "nothing.exr", approx)
    hdr = pgt.compare(truth.image * 4, approx * 4, data_range=4.0)
    assert hdr.data_range_source == "given" and hdr.data_range == 4.0
    derived = pgt.compare(truth.image * 4, approx * 4)
    assert derived.data_range_source == "derived"
    # Mixed: a file and an array, and layers of EXR files.
    mixed = pgt.compare(ref_path, approx)
    assert mixed.reference_uncertainty is not None
    err_vs_err = pgt.compare(ref_path, ref_path, layer="err")
    assert err_vs_err.rmse.mean == 0.0
