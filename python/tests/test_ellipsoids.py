"""Ellipsoids from arrays (docs/design.md §9): the same particles as an ellipsoid CSV that the CLI
reads, bit for bit; equal semi-axes are the sphere; bad arrays name their argument."""

from __future__ import annotations

import csv

import numpy as np
import pytest

import pgt
from conftest import bits, in_ci


def ellipsoids(n: int = 8, seed: int = 3):
    """Overlapping ellipsoids with axis ratios up to 1:4 and unnormalised random quaternions."""
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-1.5, 1.5, (n, 3))
    axes = rng.uniform(0.3, 1.2, (n, 3))
    quats = rng.normal(size=(n, 4)) * 3.0
    colors = rng.uniform(0.1, 1.0, (n, 3))
    opacity = rng.uniform(0.2, 0.9, n)
    return centers, axes, quats, colors, opacity


def write_csv(path, centers, axes, quats, colors, opacity):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y", "z", "sx", "sy", "sz", "qw", "qx", "qy", "qz", "red", "green", "blue", "opacity"])
        for row in zip(centers, axes, quats, colors, opacity):
            c, a, q, col, o = row
            w.writerow([repr(float(v)) for v in (*c, *a, *q, *col, o)])


def test_ellipsoids_from_arrays_are_the_clis_ellipsoid_csv(tmp_path, run_cli):
    centers, axes, quats, colors, opacity = ellipsoids()
    path = tmp_path / "e.csv"
    write_csv(path, centers, axes, quats, colors, opacity)
    scene = pgt.Scene.from_arrays(
        centers, None, colors, opacity, semi_axes=axes, rotations=quats, size=(24, 20), model="emission"
    )
    from_file = pgt.load_scene(path, size=(24, 20), model="emission")
    p, q = scene.particles(), from_file.particles()
    assert set(p) == {"center", "radius", "color", "opacity", "sigma", "semi_axes", "rotation"}
    for key in p:
        np.testing.assert_array_equal(p[key], q[key], err_msg=key)
    np.testing.assert_array_equal(p["semi_axes"], axes)
    # The rotations come back normalised, the same turn as given (q and -q are one turn).
    given = quats / np.linalg.norm(quats, axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.sum(p["rotation"] * given, axis=1)), 1.0, rtol=1e-12)
    # Θmax is along the shortest diameter: opacity = 1 - exp(-2 min(axes) sigma).
    np.testing.assert_allclose(p["opacity"], opacity, rtol=1e-12)
    np.testing.assert_allclose(-np.log1p(-opacity) / (2 * axes.min(axis=1)), p["sigma"], rtol=1e-12)
    result = pgt.render(scene)
    out = tmp_path / "cli.exr"
    run_cli("render", path, "--size", "24x20", "--model", "emission", "-o", out)
    np.testing.assert_array_equal(bits(result.image), bits(pgt.read_image(out)))
    np.testing.assert_array_equal(bits(result.err), bits(pgt.read_image(out, layer="err")))
    assert result.image.max() > 0.05



def test_gpu_methods_draw_ellipsoids_as_the_cli_does(tmp_path, run_cli):
    """pgt.approx on ellipsoids from arrays gives the bits `pgt approx` gives on the same CSV, and
    `ever`, exact on overlaps up to float32, stays near the reference where `sorted-blend` does not."""
    centers, axes, quats, colors, opacity = ellipsoids()
    path = tmp_path / "e.csv"
    write_csv(path, centers, axes, quats, colors, opacity)
    scene = pgt.Scene.from_arrays(
        centers, None, colors, opacity, semi_axes=axes, rotations=quats, size=(24, 20), model="emission"
    )
    try:
        ever = pgt.approx(scene, "ever", stop_below=0, max_batches=1 << 24)
    except pgt.NoAdapterError as e:
        if in_ci():
            pytest.fail(f"CI=true and no GPU adapter: {e}")
        pytest.skip(f"no GPU adapter ({e})")
    out = tmp_path / "ever.exr"
    run_cli(
        "approx", path, "--size", "24x20", "--model", "emission", "--method", "ever",
        "--param", "stop_below=0", "--param", "max_batches=16777216", "-o", out,
    )
    np.testing.assert_array_equal(bits(ever.image), bits(pgt.read_image(out)))
    reference = pgt.render(scene).image
    blend = pgt.approx(scene, "sorted-blend").image
    ever_error = np.abs(ever.image - reference).max()
    blend_error = np.abs(blend - reference).max()
    assert ever_error < 1e-4, ever_error
    assert blend_error > 10 * ever_error, (blend_error, ever_error)


def test_equal_semi_axes_are_the_sphere():
    centers, axes, _, colors, opacity = ellipsoids(6, seed=5)
    radii = axes[:, 0]
    spheres = pgt.Scene.from_arrays(centers, radii, colors, opacity, size=(20, 20), model="lit", tol=1e-4)
    equal = pgt.Scene.from_arrays(
        centers,
        None,
        colors,
        opacity,
        semi_axes=np.repeat(radii[:, None], 3, axis=1),
        rotations=np.tile([0.3, -0.2, 0.5, 0.8], (6, 1)),
        size=(20, 20),
        model="lit",
        tol=1e-4,
    )
    assert "semi_axes" not in equal.particles()
    a, b = pgt.render(spheres), pgt.render(equal)
    np.testing.assert_array_equal(bits(a.image), bits(b.image))
    np.testing.assert_array_equal(bits(a.err), bits(b.err))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"radii": [1.0, 1.0]}, "radii .*or semi_axes.*not both"),
        ({"radii": None, "semi_axes": None}, "give radii .*or semi_axes"),
        ({"radii": [1.0, 1.0], "semi_axes": None, "rotations": [[1, 0, 0, 0]] * 2}, "rotations .*semi_axes"),
        ({"radii": None, "semi_axes": [[1, 2], [1, 2]]}, "semi_axes"),
        ({"radii": None, "semi_axes": [[1, 2, 3], [1, 2, 3]], "rotations": [[1, 0, 0]] * 2}, "rotations"),
        ({"radii": None, "semi_axes": [[1, 2, 3], [1, np.nan, 3]]}, "semi_axes"),
        ({"radii": None, "semi_axes": [[1, 2, 3], [1, 0, 3]]}, "semi_axes"),
        ({"radii": None, "semi_axes": [[1, 2, 3], [1, 2, 3]], "rotations": [[1, 0, 0, 0], [0, 0, 0, 0]]}, "rotation"),
    ],
)
def test_bad_ellipsoid_arrays_name_their_argument(kwargs, message):
    args = {"semi_axes": [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]}
    args.update(kwargs)
    radii = args.pop("radii")
    with pytest.raises(pgt.InputError, match=message):
        pgt.Scene.from_arrays([[0, 0, 0], [1, 0, 0]], radii, **args)


def test_gaussians_from_arrays_show_the_opacity_along_the_shortest_axis():
    """defaults={"density": "gaussian"} makes the particles Gaussians (docs/design.md §9): seen along
    its shortest standard deviation, a Gaussian of opacity 0.6 shows 0.6 C + 0.4 L_bg at its centre;
    along its longest it is more opaque; the constant-density GPU methods refuse the scene."""
    quarter_turn_y = np.array([[np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0]])
    quarter_turn_x = np.array([[np.sqrt(0.5), np.sqrt(0.5), 0.0, 0.0]])
    color, background = np.array([[1.0, 0.5, 0.25]]), (0.2, 0.3, 0.4)

    def scene(rotation):
        return pgt.Scene.from_arrays(
            np.zeros((1, 3)), None, color, 0.6, semi_axes=np.array([[0.2, 0.9, 0.5]]),
            rotations=rotation, camera={"position": [0.0, 0.0, -10.0], "look_at": [0.0, 0.0, 0.0], "fov_y": 20.0},
            size=(9, 9), model="emission", background=background, tol=1e-9, defaults={"density": "gaussian"},
        )

    front = pgt.render(scene(quarter_turn_y))
    want = 0.6 * color[0] + 0.4 * np.array(background)
    assert np.abs(front.image[4, 4] - want).max() <= front.err[4, 4].max() + 1e-6, front.image[4, 4]
    assert front.err.max() <= 1e-7
    side = pgt.render(scene(quarter_turn_x))
    assert side.image[4, 4, 0] > want[0] + 0.1, side.image[4, 4]
    with pytest.raises(pgt.InputError, match="Gaussian particles"):
        pgt.approx(scene(quarter_turn_y), "emission")
