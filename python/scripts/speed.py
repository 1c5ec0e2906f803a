"""What the Python package costs on top of the CLI (issue 33): the same 1UUN lit render (256² by
default, --size to change it)
through `pgt render` and through `pgt.load_scene` + `pgt.render` + `RenderResult.write`, and a
4K comparison from arrays against `pgt compare` on files. Runs alternate, so both see the same
machine; the figures are medians and their ratio: wall time of the whole call, the render as the
library timed it, and CPU time (user + system, the least sensitive to other load).

    python python/scripts/speed.py [--pgt target/release/pgt] [--runs 5] [--size 256]
        [--shared ../shared/data] [--skip-render] [--skip-compare]
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import pgt

REPO = Path(__file__).resolve().parents[2]


def timed(f):
    start = time.perf_counter()
    value = f()
    return time.perf_counter() - start, value


def cpu_seconds(who: int) -> float:
    """User + system CPU time of this process (RUSAGE_SELF) or of its finished children."""
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def render_figures(pgt_bin: Path, pdb: Path, runs: int, size: int, out: Path) -> None:
    cli_wall, cli_render, py_wall, py_render = [], [], [], []
    cli_cpu, py_cpu = [], []
    for _ in range(runs):
        before = cpu_seconds(resource.RUSAGE_CHILDREN)
        seconds, done = timed(
            lambda: subprocess.run(
                [str(pgt_bin), "render", str(pdb), "--size", f"{size}x{size}", "-o", str(out / "cli.exr")],
                capture_output=True,
                text=True,
                check=True,
            )
        )
        cli_cpu.append(cpu_seconds(resource.RUSAGE_CHILDREN) - before)
        cli_wall.append(seconds)
        # "rendered ... in 12.34 s: ..." (the render itself, as the library timed it).
        cli_render.append(float(done.stderr.split(" in ")[1].split(" s")[0]))

        def python_call():
            scene = pgt.load_scene(pdb, size=(size, size))
            result = pgt.render(scene)
            result.write(out / "py.exr")
            return result

        before = cpu_seconds(resource.RUSAGE_SELF)
        seconds, result = timed(python_call)
        py_cpu.append(cpu_seconds(resource.RUSAGE_SELF) - before)
        py_wall.append(seconds)
        py_render.append(result.seconds)
    same = (out / "cli.exr").read_bytes() == (out / "py.exr").read_bytes()
    print(f"1UUN {size}x{size} lit, {runs} runs each, alternating (same EXR bytes: {same})")
    figures = (
        ("whole call", cli_wall, py_wall),
        ("render alone", cli_render, py_render),
        ("CPU time", cli_cpu, py_cpu),
    )
    for name, cli, py in figures:
        c, p = statistics.median(cli), statistics.median(py)
        print(f"  {name:13s} CLI median {c:8.3f} s  Python median {p:8.3f} s  ratio {p / c:.4f}")
        print(f"  {'':13s} CLI runs {' '.join(f'{v:.3f}' for v in cli)}")
        print(f"  {'':13s} Py  runs {' '.join(f'{v:.3f}' for v in py)}")


def compare_figures(pgt_bin: Path, runs: int, out: Path) -> None:
    h, w = 2160, 3840
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    base = 0.5 + 0.4 * np.sin(x[..., None] / 300 + np.arange(3)) * np.cos(y[..., None] / 200)
    ref = base.astype(np.float32)
    approx = np.clip(ref + rng.normal(0, 0.02, ref.shape), 0, 1).astype(np.float32)
    pgt.write_image(out / "ref.exr", ref)
    pgt.write_image(out / "approx.exr", approx)
    cli, arrays, files = [], [], []
    cli_cpu, arrays_cpu, files_cpu = [], [], []

    def cpu_and_wall(f, who):
        before = cpu_seconds(who)
        wall = timed(f)[0]
        return wall, cpu_seconds(who) - before

    for _ in range(runs):
        wall, cpu = cpu_and_wall(
            lambda: subprocess.run(
                [str(pgt_bin), "compare", str(out / "ref.exr"), str(out / "approx.exr")],
                capture_output=True,
                check=True,
            ),
            resource.RUSAGE_CHILDREN,
        )
        cli.append(wall)
        cli_cpu.append(cpu)
        wall, cpu = cpu_and_wall(lambda: pgt.compare(ref, approx), resource.RUSAGE_SELF)
        arrays.append(wall)
        arrays_cpu.append(cpu)
        wall, cpu = cpu_and_wall(lambda: pgt.compare(out / "ref.exr", out / "approx.exr"), resource.RUSAGE_SELF)
        files.append(wall)
        files_cpu.append(cpu)
    print(f"4K compare ({w}x{h}), {runs} runs each, alternating")
    for what, c_values, rows in (
        ("wall", cli, (("Python from arrays", arrays), ("Python on files", files))),
        ("CPU", cli_cpu, (("Python from arrays", arrays_cpu), ("Python on files", files_cpu))),
    ):
        c = statistics.median(c_values)
        print(f"  {what:4s} CLI on files           median {c:.3f} s  runs {' '.join(f'{v:.3f}' for v in c_values)}")
        for name, values in rows:
            m = statistics.median(values)
            print(f"  {what:4s} {name:22s} median {m:.3f} s  ratio to CLI {m / c:.4f}  runs {' '.join(f'{v:.3f}' for v in values)}")
    # The one copy of an array in: what a 4K float32 image costs to copy on this machine.
    copy = statistics.median(timed(lambda: ref.copy())[0] for _ in range(runs))
    print(f"  one copy of one 4K float32 image (numpy): {copy * 1e3:.1f} ms")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--pgt", default=str(REPO / "target" / "release" / "pgt"))
    parser.add_argument("--shared", default=str(REPO.parent / "shared" / "data"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--skip-render", action="store_true")
    parser.add_argument("--skip-compare", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        if not args.skip_render:
            pdb = Path(args.shared) / "pdb" / "1uun_opm_oriented.pdb"
            render_figures(Path(args.pgt), pdb, args.runs, args.size, out)
        if not args.skip_compare:
            compare_figures(Path(args.pgt), args.runs, out)


if __name__ == "__main__":
    main()
