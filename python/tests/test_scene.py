"""Scenes: load_scene, Scene.from_arrays, particles() and camera_matrices() against the CLI."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest

import pgt
from conftest import random_particles


def test_load_scene_reads_the_file_and_applies_overrides(example):
    scene = pgt.load_scene(example("disjoint_lit.toml"))
    assert (scene.width, scene.height) == (512, 512)
    assert (scene.mode, scene.model, scene.tol) == ("volume", "lit", 1e-5)
    assert len(scene) == 5
    assert [l["type"] for l in scene.lights] == ["directional", "point"]
    assert scene.lights[1]["falloff"] == "inverse-square"
    small = pgt.load_scene(
        example("disjoint_lit.toml"), size=(20, 10), mode="opaque", model="emission", tol=1e-3
    )
    assert (small.width, small.height, small.mode, small.model, small.tol) == (
        20,
        10,
        "opaque",
        "emission",
        1e-3,
    )
    assert "disjoint_lit.toml" in repr(small)
    assert small.source == example("disjoint_lit.toml")
    assert pgt.load_scene(example("disjoint_lit.toml"), size=[8, 4]).width == 8
    with pytest.raises(pgt.InputError, match=r"size: expected \(width, height\), got \(1, 2, 3\)"):
        pgt.load_scene(example("disjoint_lit.toml"), size=(1, 2, 3))


def test_load_scene_errors_carry_the_cli_messages(tmp_path, run_cli):
    bad = tmp_path / "bad.toml"
    bad.write_text("[[particles]]\ncenter = [0, 0, 0]\nradius = -1.0\n")
    with pytest.raises(pgt.InputError) as e:
        pgt.load_scene(bad)
    assert isinstance(e.value, ValueError) and isinstance(e.value, pgt.Error)
    cli = run_cli("render", bad, "-o", tmp_path / "x.exr", check=False)
    assert cli.returncode == 2
    assert cli.stderr.strip().splitlines()[-1] == f"error: {e.value}"
    assert "bad.toml:1: particles[0].radius must be > 0" in str(e.value)

    with pytest.raises(pgt.FileError) as e:
        pgt.load_scene(tmp_path / "missing.toml")
    assert isinstance(e.value, OSError) and e.value.errno == 2
    assert "missing.toml" in str(e.value)

    with pytest.raises(pgt.InputError, match="mode: unknown variant `solid`"):
        pgt.load_scene(bad, mode="solid")
    with pytest.raises(pgt.InputError, match="unknown optical model `glow`"):
        pgt.load_scene(bad, model="glow")
    with pytest.raises(pgt.InputError, match="size: image size must be between"):
        pgt.load_scene(bad, size=(0, 10))
    with pytest.raises(pgt.InputError, match="--tol must be a finite number > 0"):
        pgt.load_scene(pgt_example_ok(tmp_path), tol=-1.0)


def pgt_example_ok(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text("[[particles]]\ncenter = [0, 0, 0]\nradius = 1.0\n")
    return path


def test_an_empty_scene_warns(tmp_path):
    path = tmp_path / "empty.toml"
    path.write_text("")
    with pytest.warns(pgt.PgtWarning, match="no particles"):
        scene = pgt.load_scene(path)
    assert scene.warnings and len(scene) == 0


def write_csv(path, centers, radii, colors, opacity):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y", "z", "radius", "red", "green", "blue", "opacity"])
        for c, r, col, o in zip(centers, radii, colors, opacity):
            w.writerow([repr(float(v)) for v in (*c, r, *col, o)])


def test_from_arrays_has_the_defaults_of_a_bare_particle_file(tmp_path):
    centers, radii, colors, opacity = random_particles(25)
    path = tmp_path / "p.csv"
    write_csv(path, centers, radii, colors, opacity)
    from_file = pgt.load_scene(path)
    from_arrays = pgt.Scene.from_arrays(centers, radii, colors, opacity)
    assert (from_arrays.width, from_arrays.height) == (512, 512)
    assert from_arrays.source is None and from_file.source == path
    assert from_arrays.lights == from_file.lights
    assert [l["irradiance"] for l in from_arrays.lights] == [(0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    for api in ("opengl", "vulkan", "webgpu", "direct3d"):
        a, f = from_arrays.camera_matrices(api), from_file.camera_matrices(api)
        for key in ("view", "projection", "eye", "forward", "near", "far"):
            np.testing.assert_array_equal(a[key], f[key])
    pa, pf = from_arrays.particles(), from_file.particles()
    for key in ("center", "radius", "color", "opacity", "sigma"):
        np.testing.assert_array_equal(pa[key], pf[key])
    np.testing.assert_array_equal(pa["center"], centers)
    np.testing.assert_array_equal(pa["radius"], radii)


def test_from_arrays_settings(tmp_path):
    centers, radii, colors, _ = random_particles(10)
    scene = pgt.Scene.from_arrays(
        centers.astype(np.float32),
        list(radii),
        colors,
        kappa=2.0,
        lights=[pgt.point_light([0, 3, 0], [5, 5, 5], falloff="none")],
        camera={"position": [0, 0, -6], "look_at": [0, 0, 0], "fov_y": 30},
        size=(64, 48),
        mode="volume",
        model="single-scatter",
        background=[0.1, 0.2, 0.3],
        tol=1e-4,
        lambda_=0.5,
        emission_weight=0.25,
    )
    assert (scene.width, scene.height, scene.model, scene.tol) == (64, 48, "single-scatter", 1e-4)
    assert scene.background == (0.1, 0.2, 0.3)
    assert scene.lights == [
        {"type": "point", "position": (0.0, 3.0, 0.0), "intensity": (5.0, 5.0, 5.0), "falloff": "none"}
    ]
    # kappa 2 with lambda 0.5: sigma = 1 for every particle.
    np.testing.assert_array_equal(scene.particles()["sigma"], np.ones(10))
    cam = scene.camera_matrices("webgpu")
    np.testing.assert_array_equal(cam["eye"], [0.0, 0.0, -6.0])
    assert cam["fov_y_deg"] == pytest.approx(30.0, abs=1e-12)
    assert pgt.Scene.from_arrays(centers, radii, lights=[]).lights == []


def test_particles_are_what_pgt_export_writes(tmp_path, example, run_cli):
    scene_path = example("disjoint_lit.toml")
    out = tmp_path / "p.csv"
    run_cli("export", scene_path, "-o", out)
    rows = list(csv.DictReader(open(out)))
    p = pgt.load_scene(scene_path).particles()
    assert p["center"].shape == (5, 3) and p["center"].dtype == np.float64
    col = lambda name: np.array([float(r[name]) for r in rows])
    np.testing.assert_array_equal(p["center"], np.stack([col("x"), col("y"), col("z")], axis=1))
    np.testing.assert_array_equal(p["radius"], col("radius"))
    np.testing.assert_array_equal(p["color"], np.stack([col("red"), col("green"), col("blue")], axis=1))
    np.testing.assert_array_equal(p["opacity"], col("opacity"))
    np.testing.assert_array_equal(p["sigma"], col("sigma"))


def test_camera_matrices_are_what_pgt_camera_prints(example, run_cli):
    scene_path = example("disjoint_lit.toml")
    printed = json.loads(run_cli("camera", scene_path, "--size", "64x48", "--json").stdout)
    scene = pgt.load_scene(scene_path, size=(64, 48))
    for api, want in printed["projection"].items():
        cam = scene.camera_matrices(api)
        assert cam["api"] == api
        np.testing.assert_array_equal(cam["projection"], np.array(want["matrix"]["row_major"]))
        np.testing.assert_array_equal(cam["view"], np.array(printed["view"]["row_major"]))
        assert cam["depth_range"] == tuple(want["depth_range"])
        assert cam["convention"] == want["convention"]
        for key in ("eye", "eye_plus_forward", "forward", "right", "up", "background"):
            np.testing.assert_array_equal(cam[key], printed[key])
        for key in ("fov_y_deg", "fov_x_deg", "tan_half_fov_y", "width", "height", "aspect", "near", "far"):
            assert cam[key] == printed[key], key
    # The matrices do what they say: a point on the axis lands in the image's centre.
    cam = scene.camera_matrices("opengl")
    point = np.append(cam["eye"] + 5.0 * cam["forward"], 1.0)
    clip = cam["projection"] @ cam["view"] @ point
    np.testing.assert_allclose(clip[:2] / clip[3], [0.0, 0.0], atol=1e-12)
    with pytest.raises(pgt.InputError, match="unknown graphics API 'metal'"):
        scene.camera_matrices("metal")


def test_from_arrays_refuses_bad_values_with_the_scene_files_messages():
    centers, radii, colors, opacity = random_particles(5)
    bad_radii = radii.copy()
    bad_radii[3] = -0.5
    with pytest.raises(pgt.InputError, match=r"particles\[3\]\.radius must be > 0, got -0.5"):
        pgt.Scene.from_arrays(centers, bad_radii)
    with pytest.raises(pgt.InputError, match=r"particles\[0\]\.opacity must be in \[0, 1\]"):
        pgt.Scene.from_arrays(centers, radii, opacity=1.5)
    with pytest.raises(pgt.InputError, match="give opacity or kappa, not both"):
        pgt.Scene.from_arrays(centers, radii, opacity=opacity, kappa=1.0)
    with pytest.raises(pgt.InputError, match="camera.fov_y must be in"):
        pgt.Scene.from_arrays(centers, radii, camera={"position": [0, 0, -5], "look_at": [0, 0, 0], "fov_y": 200})
    with pytest.raises(pgt.InputError, match="unknown field `fovy`"):
        pgt.Scene.from_arrays(centers, radii, camera={"fovy": 20})
    with pytest.raises(pgt.InputError, match="lights\\[0\\].direction must be a non-zero vector"):
        pgt.Scene.from_arrays(centers, radii, lights=[pgt.directional_light([0, 0, 0], [1, 1, 1])])
    with pytest.raises(pgt.InputError, match="unknown optical model `glow`"):
        pgt.Scene.from_arrays(centers, radii, model="glow")
    with pytest.raises(pgt.InputError, match="render.tol must be > 0"):
        pgt.Scene.from_arrays(centers, radii, tol=0.0)
    with pytest.raises(pgt.InputError, match="^Scene.from_arrays: "):
        pgt.Scene.from_arrays(centers, radii, background=[-1, 0, 0])


def test_from_arrays_with_no_particles_warns():
    with pytest.warns(pgt.PgtWarning, match="no particles"):
        scene = pgt.Scene.from_arrays(np.zeros((0, 3)), np.zeros(0))
    assert len(scene) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pgt.Scene.from_arrays(np.zeros((1, 3)), np.ones(1))


def test_load_scene_format_reads_a_file_whatever_its_extension(tmp_path):
    """format= is --format: a CSV named .dat loads as CSV; without it the extension decides."""
    data = tmp_path / "particles.dat"
    data.write_text("x,y,z,radius\n0,0,0,1.0\n2,0,0,0.5\n")
    scene = pgt.load_scene(data, format="csv", size=(8, 8))
    np.testing.assert_array_equal(scene.particles()["radius"], [1.0, 0.5])
    with pytest.raises(pgt.InputError, match="particles.dat"):
        pgt.load_scene(data, size=(8, 8))
    with pytest.raises(pgt.InputError, match="format: unknown format 'tiff'; expected one of .*pdb"):
        pgt.load_scene(data, format="tiff")
    with pytest.raises(pgt.InputError, match="--format csv applies to a bare particle file"):
        pgt.load_scene(tmp_path / "scene.toml", format="csv")
