"""pgt.compare of two sequences, pgt.sweep, pgt.merge and pgt.bench against the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import pgt

SIZE = (24, 20)


def without_seconds(value):
    """A JSON value with every "seconds" key left out (wall times differ between runs)."""
    if isinstance(value, dict):
        return {k: without_seconds(v) for k, v in value.items() if k != "seconds"}
    if isinstance(value, list):
        return [without_seconds(v) for v in value]
    return value


@pytest.fixture
def sequences(tmp_path, example):
    """Two sequences of three frames as printf patterns: renders of a scene with the light
    dimmed frame by frame, and a noisy copy of them."""
    scene = pgt.load_scene(example("disjoint_lit.toml"), size=SIZE)
    truth = pgt.render(scene).image
    rng = np.random.default_rng(5)
    (tmp_path / "ref").mkdir()
    (tmp_path / "app").mkdir()
    for k in range(3):
        frame = (truth * (1.0 - 0.1 * k)).astype(np.float32)
        noisy = np.clip(frame + rng.normal(0, 0.01, frame.shape), 0, None).astype(np.float32)
        pgt.write_image(tmp_path / "ref" / f"f_{k:04d}.exr", frame)
        pgt.write_image(tmp_path / "app" / f"f_{k:04d}.exr", noisy)
    return tmp_path / "ref" / "f_%04d.exr", tmp_path / "app" / "f_%04d.exr"


def test_sequences_compare_as_the_cli(sequences, tmp_path, run_cli):
    ref, app = sequences
    cli = run_cli(
        "compare", ref, app, "--json", "-", "--max-temporal-p99", "1e-9", "--report",
        tmp_path / "cli_report", check=False,
    )
    assert cli.returncode == 1, cli.stderr
    printed = json.loads(cli.stdout)
    mine = pgt.compare(ref, app, gate={"max_temporal_p99": 1e-9}, report=tmp_path / "py_report")
    assert isinstance(mine, pgt.SequenceComparison)
    assert mine.frames == 3
    assert mine.passed is False
    assert without_seconds(mine.summary()) == without_seconds(printed)
    assert printed["frames"][1]["temporal"] is not None
    assert mine.verdict == cli.stderr.strip().splitlines()[-1]
    assert mine.verdict.startswith("FAIL: 3 frames")
    assert mine.report_page == tmp_path / "py_report" / "index.html"
    cli_files = sorted(p.name for p in (tmp_path / "cli_report").iterdir())
    py_files = sorted(p.name for p in (tmp_path / "py_report").iterdir())
    assert cli_files == py_files and "index.html" in py_files
    for name in py_files:
        if name.endswith(".png"):
            assert (tmp_path / "cli_report" / name).read_bytes() == (
                tmp_path / "py_report" / name
            ).read_bytes(), name


def test_sequence_errors_are_the_clis(sequences, tmp_path, run_cli, example):
    ref, _ = sequences
    image = tmp_path / "one.exr"
    pgt.write_image(image, np.zeros((SIZE[1], SIZE[0], 3), np.float32))
    with pytest.raises(pgt.InputError):
        pgt.compare(ref, image)
    with pytest.raises(pgt.InputError, match="pop_threshold"):
        pgt.compare(ref, ref, pop_threshold=-1.0)
    with pytest.raises(pgt.InputError, match="sequences of frames"):
        pgt.compare(image, image, report=tmp_path / "r")
    # Frames missing from one side: the CLI's message.
    (tmp_path / "short").mkdir()
    pgt.write_image(tmp_path / "short" / "f_0000.exr", np.zeros((SIZE[1], SIZE[0], 3), np.float32))
    short = tmp_path / "short" / "f_%04d.exr"
    cli = run_cli("compare", ref, short, check=False)
    assert cli.returncode == 2
    with pytest.raises(pgt.InputError) as e:
        pgt.compare(ref, short)
    assert cli.stderr.strip() == f"error: {e.value}"


def test_sweep_is_the_clis(tmp_path, run_cli, example):
    exp = tmp_path / "exp.toml"
    exp.write_text(
        f'scene = "{example("shadows.toml")}"\nsize = [24, 16]\n[reference]\nspp = 1\n'
        '[[approximations]]\nmethod = "riemann"\nsamples = [2, 4]\n'
    )
    cli = run_cli("sweep", exp, "--report", tmp_path / "cli")
    runs, page = pgt.sweep(exp, tmp_path / "py")
    assert (runs, page) == (2, tmp_path / "py" / "index.html")
    assert cli.stdout == f"sweep: 2 runs, report {tmp_path / 'cli' / 'index.html'}\n"
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert cli_files == sorted(p.name for p in (tmp_path / "py").iterdir())
    images = [n for n in cli_files if n.endswith(".png") or n.endswith(".exr")]
    assert "reference.png" in images and len(images) >= 3
    for name in images:
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes(), name
    read = lambda d: without_seconds(json.loads((tmp_path / d / "sweep.json").read_text()))
    assert read("cli") == read("py")
    with pytest.raises(pgt.FileError):
        pgt.sweep(tmp_path / "missing.toml", tmp_path / "r2")


def test_merge_is_the_clis(tmp_path, run_cli, example):
    scene = example("disjoint_lit.toml")
    parts = [tmp_path / f"part_{i}.exr" for i in range(2)]
    for i, part in enumerate(parts):
        run_cli("render", scene, "--size", "24x20", "--part", f"{i}/2", "-o", part)
    run_cli("merge", *parts[::-1], "-o", tmp_path / "cli.exr")
    image, err = pgt.merge(parts[::-1], tmp_path / "py.exr")
    assert (tmp_path / "cli.exr").read_bytes() == (tmp_path / "py.exr").read_bytes()
    assert np.array_equal(image, pgt.read_image(tmp_path / "cli.exr"))
    assert np.array_equal(err, pgt.read_image(tmp_path / "cli.exr", layer="err"))
    # The whole render, bit for bit.
    whole = pgt.render(pgt.load_scene(scene, size=SIZE))
    assert np.array_equal(image, whole.image) and np.array_equal(err, whole.err)
    # A missing part: the CLI's message and exit 2, an InputError here.
    cli = run_cli("merge", parts[0], "-o", tmp_path / "x.exr", check=False)
    assert cli.returncode == 2
    with pytest.raises(pgt.InputError) as e:
        pgt.merge([parts[0]])
    assert cli.stderr.strip() == f"error: {e.value}"


def rows(table: str):
    """The rows of bench's table without its timings: workload, renderer, size, spheres,
    shadow rays per pixel, the ratios and the errors."""
    out = []
    for line in table.splitlines()[1:]:
        if line.startswith("warning") or line.startswith("peak"):
            continue
        fixed, rest = line[:53], line[53:].split()
        out.append((fixed, rest[2], rest[4:]))
    return out


def test_bench_is_the_clis(tmp_path, run_cli):
    # Where the 1UUN file is missing the bench uses its generated protein-sized set.
    args = dict(size=16, workloads=["1uun"], no_baselines=True, data=tmp_path)
    cli = run_cli("bench", "--size", "16", "--workloads", "1uun", "--no-baselines", "--data", tmp_path)
    mine = pgt.bench(**args)
    assert rows(mine) == rows(cli.stdout)
    assert len(rows(mine)) == 1 and "protein-like" in rows(mine)[0][0]
    assert mine.splitlines()[0] == cli.stdout.splitlines()[0]
    with pytest.raises(pgt.InputError, match="unknown workload 'nope'"):
        pgt.bench(workloads=["nope"])
    with pytest.raises(pgt.InputError, match="size"):
        pgt.bench(size=0)
