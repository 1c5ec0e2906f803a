"""Shared fixtures of the pgt Python tests.

Data and tools the tests need but a bare checkout may lack follow the Rust tests' rule
(tests/support/mod.rs): absent under CI=true is a failure, elsewhere the test is skipped with a
message.

* shared data: $PGT_SHARED_DATA, else ../shared/data beside the repository;
* the pgt binary (for bit-identity with the CLI): $PGT_BIN, else target/release/pgt, else
  target/debug/pgt of the repository.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import pgt

REPO = Path(__file__).resolve().parents[2]


def in_ci() -> bool:
    return os.environ.get("CI") == "true"


def need(path: Path, what: str) -> Path:
    """``path``, or a skip (a failure under CI=true) naming what is missing."""
    if path.exists():
        return path
    message = f"{what} {path} is absent"
    if in_ci():
        pytest.fail(f"CI=true and {message}")
    pytest.skip(f"{message} (CI is not set)")


def shared_root() -> Path:
    env = os.environ.get("PGT_SHARED_DATA")
    return Path(env) if env else REPO.parent / "shared" / "data"


@pytest.fixture
def shared():
    """shared("pdb/1uun_opm_oriented.pdb") -> the path, or a skip (failure under CI)."""
    return lambda rel: need(shared_root() / rel, "the shared test data")


@pytest.fixture(scope="session")
def pgt_bin() -> Path:
    env = os.environ.get("PGT_BIN")
    if env:
        return need(Path(env), "PGT_BIN")
    for profile in ("release", "debug"):
        path = REPO / "target" / profile / "pgt"
        if path.exists():
            return path
    return need(REPO / "target" / "release" / "pgt", "the pgt binary (cargo build --release)")


@pytest.fixture(scope="session")
def run_cli(pgt_bin):
    """run_cli("render", ...) -> CompletedProcess; fails the test on a non-zero exit unless
    ``check=False``."""

    def run(*args, check: bool = True, env=None) -> subprocess.CompletedProcess:
        done = subprocess.run(
            [str(pgt_bin), *map(str, args)],
            capture_output=True,
            text=True,
            env=env,
        )
        if check and done.returncode != 0:
            raise AssertionError(f"pgt {' '.join(map(str, args))} exited {done.returncode}: {done.stderr}")
        return done

    return run


@pytest.fixture
def example():
    """example("disjoint_lit.toml") -> the path of a scene in the repository's examples/."""
    return lambda name: REPO / "examples" / name


def random_particles(n: int, seed: int = 7):
    """Centres, radii, colours and opacities of ``n`` random overlapping particles."""
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-1.0, 1.0, size=(n, 3))
    radii = rng.uniform(0.1, 0.35, size=n)
    colors = rng.uniform(0.2, 1.0, size=(n, 3))
    opacity = rng.uniform(0.3, 0.9, size=n)
    return centers, radii, colors, opacity


@pytest.fixture
def small_scene():
    """A small lit scene from arrays: 40 overlapping particles, 48x32 pixels."""
    centers, radii, colors, opacity = random_particles(40)
    return pgt.Scene.from_arrays(centers, radii, colors, opacity, size=(48, 32))


def bits(a: np.ndarray) -> np.ndarray:
    """The float32 values of ``a`` as their bit patterns (for bit-for-bit comparisons)."""
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)
