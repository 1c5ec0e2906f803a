"""pgt.Scene.from_gaussians (3DGS's tensors) against a 3DGS PLY of the same values, and
pgt.camera_from_K (K and a world-to-camera matrix)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import pgt
from conftest import bits

SIZE = (24, 18)
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "measure_rasteriser.py"


def gaussian_arrays(n: int, degree: int, seed: int = 11):
    """3DGS's tensors of ``n`` random Gaussians as float32 (what a PLY stores): means, log
    scales, w-x-y-z quaternions, logit opacities, SH (n, (degree+1)², 3)."""
    rng = np.random.default_rng(seed)
    f = np.float32
    return (
        rng.uniform(-1, 1, (n, 3)).astype(f),
        np.log(rng.uniform(0.05, 0.3, (n, 3))).astype(f),
        rng.normal(size=(n, 4)).astype(f),
        rng.uniform(-2, 3, n).astype(f),
        rng.normal(0, 0.6, (n, (degree + 1) ** 2, 3)).astype(f),
    )


def write_3dgs_ply(path: Path, means, scales, quats, opacities, sh) -> Path:
    """A binary little-endian PLY in the layout of the 3DGS reference implementation: x y z
    nx ny nz f_dc_0..2 f_rest_* (channel-major) opacity scale_0..2 rot_0..3, all float."""
    n, k, _ = sh.shape
    rest = sh[:, 1:, :].transpose(0, 2, 1).reshape(n, -1)  # red coefficients, then green, blue
    names = (
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
        + [f"f_rest_{i}" for i in range(rest.shape[1])]
        + ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    )
    columns = np.concatenate(
        [means, np.zeros((n, 3)), sh[:, 0, :], rest, opacities[:, None], scales, quats], axis=1
    ).astype("<f4")
    header = "ply\nformat binary_little_endian 1.0\n" + f"element vertex {n}\n"
    header += "".join(f"property float {name}\n" for name in names) + "end_header\n"
    path.write_bytes(header.encode() + columns.tobytes())
    return path


def same_particles(a: pgt.Scene, b: pgt.Scene) -> None:
    pa, pb = a.particles(), b.particles()
    assert sorted(pa) == sorted(pb)
    for key in pa:
        assert pa[key].tobytes() == pb[key].tobytes(), key


@pytest.mark.parametrize("degree", [0, 3])
def test_from_gaussians_is_the_ply_bit_for_bit(tmp_path, degree):
    arrays = gaussian_arrays(25, degree)
    from_file = pgt.load_scene(write_3dgs_ply(tmp_path / "g.ply", *arrays), size=SIZE)
    from_arrays = pgt.Scene.from_gaussians(*arrays, size=SIZE)
    assert from_file.model == from_arrays.model == "emission"
    same_particles(from_file, from_arrays)
    cam_a, cam_b = from_file.camera_matrices(), from_arrays.camera_matrices()
    for key in ("view", "projection", "eye"):
        assert cam_a[key].tobytes() == cam_b[key].tobytes(), key
    # The SH of degree 3 is seen from the eye: the colours are not the DC term's.
    dc = pgt.Scene.from_gaussians(*arrays, sh="dc", size=SIZE).particles()["color"]
    colour = from_arrays.particles()["color"]
    assert np.array_equal(dc, colour) == (degree == 0)
    ra, rb = pgt.render(from_file, tol=1e-3), pgt.render(from_arrays, tol=1e-3)
    assert np.array_equal(bits(ra.image), bits(rb.image))
    assert np.array_equal(bits(ra.err), bits(rb.err))
    assert ra.image.max() > 0.05  # something was drawn


def test_activated_tensors_are_the_same_particles():
    means, scales, quats, opacities, sh = gaussian_arrays(12, 1)
    logits = pgt.Scene.from_gaussians(means, scales, quats, opacities, sh, size=SIZE)
    p = logits.particles()
    activated = pgt.Scene.from_gaussians(
        means, p["semi_axes"], quats, p["opacity"], sh, activated=True, size=SIZE
    )
    same_particles(logits, activated)
    # Plain colours are taken as they are.
    colours = np.linspace(0.1, 0.9, 36).reshape(12, 3)
    plain = pgt.Scene.from_gaussians(means, scales, quats, opacities, colours, size=SIZE)
    assert np.array_equal(plain.particles()["color"], colours)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"scales": np.zeros((5, 2))}, r"scales: expected an array of shape \(5, 3\)"),
        ({"quats": np.zeros((5, 4))}, "quats: row 0"),
        ({"opacities": np.full(5, np.nan)}, "opacities: non-finite value"),
        ({"opacities": np.full(5, 40.0)}, r"opacities: index 0: the opacity sigmoid\(40"),
        ({"sh_or_colours": np.zeros((5, 2, 3))}, "K = 1, 4, 9 or 16"),
        ({"sh_or_colours": np.zeros(5)}, "sh_or_colours: expected"),
        ({"means": [[0, 0, float("nan")]] * 5}, "means: non-finite value"),
        ({"scales": np.full((5, 3), 800.0)}, "scales: row 0, column 0"),
    ],
)
def test_bad_tensors_name_the_argument(change, match):
    args = dict(
        means=np.zeros((5, 3)),
        scales=np.full((5, 3), -2.0),
        quats=np.tile([1.0, 0, 0, 0], (5, 1)),
        opacities=np.zeros(5),
        sh_or_colours=np.zeros((5, 1, 3)),
    )
    args.update(change)
    with pytest.raises(pgt.InputError, match=match):
        pgt.Scene.from_gaussians(**args, size=SIZE)


def test_camera_from_K_projects_as_K_says():
    """A small bright Gaussian at a world point lands on the pixel K·(R·x + t) says, pixel
    centres at +0.5, y down."""
    width, height = 40, 30
    K = np.array([[50.0, 0, 17.3], [0, 45.0, 12.1], [0, 0, 1]])
    angle = 0.4
    R = np.array([[np.cos(angle), 0, -np.sin(angle)], [0, 1, 0], [np.sin(angle), 0, np.cos(angle)]])
    viewmat = np.eye(4)
    viewmat[:3, :3], viewmat[:3, 3] = R, [0.1, -0.2, 4.0]
    point = np.array([0.3, 0.25, 0.2])
    x = K @ (R @ point + viewmat[:3, 3])
    u, v = x[0] / x[2], x[1] / x[2]
    camera = pgt.camera_from_K(K, viewmat, width, height)
    scene = pgt.Scene.from_gaussians(
        [point], np.log([[0.01] * 3]), [[1.0, 0, 0, 0]], [2.0], [[1.0, 1.0, 1.0]], camera=camera
    )
    assert (scene.width, scene.height) == (width, height)
    cam = scene.camera_matrices()
    assert np.allclose(cam["eye"], -R.T @ viewmat[:3, 3], atol=1e-12)
    image = pgt.render(scene, tol=1e-4).image.sum(axis=2)
    row, col = np.unravel_index(np.argmax(image), image.shape)
    assert (col, row) == (int(u), int(v)), (u, v)


def test_camera_from_K_refuses_bad_matrices():
    K = np.array([[50.0, 0, 20], [0, 50, 15], [0, 0, 1]])
    with pytest.raises(pgt.InputError, match="K: expected an array of shape"):
        pgt.camera_from_K(K[:2], np.eye(4), 40, 30)
    with pytest.raises(pgt.InputError, match="no skew"):
        pgt.camera_from_K(K + [[0, 1, 0], [0, 0, 0], [0, 0, 0]], np.eye(4), 40, 30)
    with pytest.raises(pgt.InputError, match="viewmat: non-finite"):
        pgt.camera_from_K(K, np.full((4, 4), np.nan), 40, 30)
    with pytest.raises(pgt.InputError, match="camera.R"):
        pgt.Scene.from_gaussians(
            np.zeros((1, 3)), np.zeros((1, 3)) - 2, [[1.0, 0, 0, 0]], [0.0], [[1.0, 1.0, 1.0]],
            camera=pgt.camera_from_K(K, np.diag([2.0, 1, 1, 1]), 40, 30),
        )


def colmap_image(folder: Path, name: str):
    """(R, t) of image ``name`` in a COLMAP images.txt, and (w, h, f, cx, cy) of its
    SIMPLE_PINHOLE camera."""
    lines = [l for l in (folder / "images.txt").read_text().splitlines() if l and not l.startswith("#")]
    for line in lines[::2]:
        fields = line.split()
        if fields[9] == name:
            w, x, y, z = np.array(fields[1:5], float) / np.linalg.norm(np.array(fields[1:5], float))
            R = np.array(
                [
                    [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                    [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
                ]
            )
            camera = next(l for l in (folder / "cameras.txt").read_text().splitlines() if not l.startswith("#"))
            return R, np.array(fields[5:8], float), [float(v) for v in camera.split()[2:7]]
    raise AssertionError(f"{name} not in {folder}")


def test_a_dataset_camera_is_camera_from_K_of_its_pose(shared):
    folder = shared("cameras/colmap/kapture_maupertuis_txt")
    R, t, (w, h, f, cx, cy) = colmap_image(folder, "03.jpg")
    eye = -R.T @ t
    means = eye + np.array([[0.0, 0.0, 5.0], [0.5, 0.2, 6.0]]) @ R  # in front of the camera
    arrays = (means, np.full((2, 3), -1.5), np.tile([1.0, 0, 0, 0], (2, 1)), [1.0, 2.0], np.ones((2, 1, 3)))
    dataset = pgt.Scene.from_gaussians(*arrays, camera={"from": str(folder), "image": "03.jpg"})
    viewmat = np.eye(4)
    viewmat[:3, :3], viewmat[:3, 3] = R, t
    K = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1]])
    mine = pgt.Scene.from_gaussians(*arrays, camera=pgt.camera_from_K(K, viewmat, int(w), int(h)))
    assert (dataset.width, dataset.height) == (mine.width, mine.height) == (1919, 1079)
    a, b = dataset.camera_matrices(), mine.camera_matrices()
    assert np.allclose(a["eye"], eye, atol=1e-9)
    assert np.allclose(a["view"], b["view"], atol=1e-12)
    assert np.allclose(a["projection"], b["projection"], rtol=1e-12, atol=1e-12)


def test_dataset_cameras_are_the_colmap_models_poses(shared):
    folder = shared("cameras/colmap/kapture_maupertuis_txt")
    cameras = pgt.dataset_cameras(folder)
    assert [c["name"] for c in cameras] == ["00.jpg", "01.jpg", "02.jpg", "03.jpg"]
    binary = pgt.dataset_cameras(shared("cameras/colmap/kapture_maupertuis_bin_pycolmap"))
    for c, b in zip(cameras, binary):
        R, t, (w, h, f, cx, cy) = colmap_image(folder, c["name"])
        assert (c["width"], c["height"]) == (w, h)
        assert np.allclose(c["K"], [[f, 0, cx], [0, f, cy], [0, 0, 1]], rtol=1e-12, atol=0)
        assert np.allclose(c["R"], R, atol=1e-12) and np.allclose(c["t"], t, atol=1e-9)
        assert np.allclose(c["viewmat"][:3, :3], R, atol=1e-12) and np.allclose(c["viewmat"][:3, 3], t, atol=1e-9)
        assert np.array_equal(c["viewmat"][3], [0, 0, 0, 1])
        assert np.allclose(c["eye"], -R.T @ t, atol=1e-9)
        assert np.allclose(c["camera_to_world"][:3, 3], c["eye"], atol=0)
        assert np.allclose(b["viewmat"], c["viewmat"], atol=1e-6) and np.allclose(b["K"], c["K"], atol=1e-6)
    with pytest.raises(pgt.FileError, match="not-a-model"):
        pgt.dataset_cameras(folder / "not-a-model")


def test_a_file_that_is_no_camera_file_is_refused_by_name(tmp_path):
    bad = tmp_path / "cams.json"
    bad.write_text("hello")
    with pytest.raises(pgt.Error, match="cams.json: not a camera file"):
        pgt.dataset_cameras(bad)
    bad.write_text('{"frames": [{"transform_matrix": [[1, 0]]}]}')
    with pytest.raises(pgt.Error, match="cams.json"):
        pgt.dataset_cameras(bad)


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("measure_rasteriser", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_example_measures_a_numpy_rasteriser(example, tmp_path, capsys):
    cmp = example.main(str(tmp_path / "out"), "40", "3")
    summary = cmp.summary()
    assert cmp.frames == 3 and len(summary["frames"]) == 3
    for frame in summary["frames"]:
        # The rasteriser approximates the volume: close, not equal.
        assert 0.5 < frame["ssim"] < 0.9999, frame
        assert 0 < frame["rmse"] < 0.2, frame
    assert summary["frames"][0]["temporal"] is None
    for frame in summary["frames"][1:]:
        assert frame["temporal"] is not None and frame["temporal"]["p99"]["mean"] > 0, frame
    assert cmp.report_page == tmp_path / "out" / "report" / "index.html" and cmp.report_page.is_file()
    for k in range(3):
        ref = pgt.read_image(tmp_path / "out" / "reference" / f"f_{k:04d}.exr")
        err = pgt.read_image(tmp_path / "out" / "reference" / f"f_{k:04d}.exr", layer="err")
        assert ref.shape == (30, 40, 3) and ref.max() > 0.05 and err.max() < 1e-3
    printed = capsys.readouterr().out
    assert "frame 2:" in printed and "temporal p99" in printed and "report:" in printed


def test_the_example_measures_along_a_colmap_models_cameras(example, shared, tmp_path):
    folder = shared("cameras/colmap/kapture_maupertuis_txt")
    cmp = example.main(str(tmp_path / "out"), "48", str(folder))
    summary = cmp.summary()
    assert cmp.frames == 4 and len(summary["frames"]) == 4
    for frame in summary["frames"]:
        assert 0.3 < frame["ssim"] < 0.9999 and 0 < frame["rmse"] < 0.3, frame
    ref = pgt.read_image(tmp_path / "out" / "reference" / "f_0000.exr")
    # 1919x1079 scaled to 48 wide; the sparse cloud lies in front of every camera.
    assert ref.shape == (27, 48, 3) and ref.max() > 0.02


def test_the_example_rasteriser_puts_a_gaussian_where_pgt_does(example):
    """One small round Gaussian off the axis: the splat and the volume put it at the same place
    in the image (their centroids agree to 0.05 px), so the example's camera conventions (K,
    viewmat, pixel centres) are pgt's."""
    g = {
        "means": np.array([[0.3, -0.2, 0.1]]),
        "scales": np.log([[0.06, 0.06, 0.06]]),
        "quats": np.array([[1.0, 0, 0, 0]]),
        "opacities": np.array([0.5]),
        "sh_or_colours": np.full((1, 1, 3), 1.0),
    }
    width, height = 32, 24
    viewmat, K = example.orbit(1, width, height)[0]
    truth = pgt.render(pgt.Scene.from_gaussians(**g, camera=pgt.camera_from_K(K, viewmat, width, height)), tol=1e-5)
    mine = example.numpy_rasteriser(g)(viewmat, K, width, height)
    def centroid(image):
        weight = image.sum(2)
        rows, cols = np.indices(weight.shape)
        return np.array([(weight * cols).sum(), (weight * rows).sum()]) / weight.sum()

    assert truth.image.max() > 0.1
    assert np.abs(centroid(truth.image) - centroid(mine)).max() < 0.05, (centroid(truth.image), centroid(mine))
