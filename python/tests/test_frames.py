"""pgt.load_frames: scenes over frames (particles that play frames, cameras that move), with
the frame facts `pgt info` prints."""

from __future__ import annotations

import json

import numpy as np
import pytest

import pgt
from conftest import bits


def write_xyz(path, frames):
    """A multi-frame XYZ file: one block per frame of (element, x, y, z) rows."""
    lines = []
    for t, atoms in enumerate(frames):
        lines += [str(len(atoms)), f"frame {t}"]
        lines += [f"C {x} {y} {z}" for x, y, z in atoms]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def moving(tmp_path):
    """Three frames of three carbon atoms moving along +y by 1.5 Å a frame."""
    base = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 3.0]])
    path = tmp_path / "moving.xyz"
    write_xyz(path, [base + [0.0, 1.5 * t, 0.0] for t in range(3)])
    return path


def test_a_multi_frame_file_plays_its_frames(moving, run_cli):
    frames = pgt.load_frames(moving, size=(16, 12))
    info = json.loads(run_cli("info", moving, "--json").stdout)
    assert frames.frame_count == len(frames) == info["frames"]["count"] == 3
    first = frames.frame(0).particles()["center"]
    # Frame 0 is load_scene's scene.
    np.testing.assert_array_equal(first, pgt.load_scene(moving, size=(16, 12)).particles()["center"])
    for t in (1, 2):
        scene = frames.frame(t)
        assert (scene.width, scene.height) == (16, 12)
        moved = scene.particles()["center"] - first
        # Every atom moved by the same amount along +y only, t times the step of frame 1.
        assert np.all(moved[:, [0, 2]] == 0) and np.all(moved[:, 1] > 0)
        np.testing.assert_allclose(moved[:, 1], moved[0, 1])
        if t == 2:
            np.testing.assert_allclose(moved[:, 1], 2 * step, rtol=1e-12)
        step = moved[0, 1]
    # The frames render (different images: the atoms moved in a fixed camera).
    a, b = pgt.render(frames.frame(0)).image, pgt.render(frames.frame(2)).image
    assert a.shape == b.shape == (12, 16, 3) and not np.array_equal(a, b)


def test_frame_errors_name_the_file_and_the_frame(moving):
    frames = pgt.load_frames(moving)
    with pytest.raises(pgt.InputError, match=r"moving.xyz.*frame 3 requested, but the scene has 3 frame\(s\)"):
        frames.frame(3)
    with pytest.raises(pgt.InputError, match="index: expected a frame number >= 0, got -1"):
        frames.frame(-1)
    with pytest.raises(pgt.FileError):
        pgt.load_frames(moving.parent / "missing.xyz")


def test_an_orbiting_camera_has_an_open_frame_count(tmp_path):
    scene = tmp_path / "orbit.toml"
    scene.write_text(
        "[camera]\nposition = [0.0, 0.0, -6.0]\nlook_at = [0.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n"
        "[camera.orbit]\naxis = [0.0, 1.0, 0.0]\ndegrees_per_frame = 90.0\n"
        "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n"
    )
    frames = pgt.load_frames(scene)
    assert frames.frame_count is None
    with pytest.raises(TypeError, match="frame count is open"):
        len(frames)
    eye = [frames.frame(t).camera_matrices()["eye"] for t in (0, 1, 2)]
    np.testing.assert_allclose(eye[0], [0, 0, -6], atol=1e-12)
    # A quarter turn about +y a frame: the camera stays 6 from the centre, half a turn is -eye.
    np.testing.assert_allclose(np.linalg.norm(eye[1]), 6.0)
    assert abs(eye[1][2]) < 1e-9 and abs(abs(eye[1][0]) - 6.0) < 1e-9
    np.testing.assert_allclose(eye[2], [0, 0, 6], atol=1e-9)
    assert len(frames.frame(1)) == 1


def test_each_frame_renders_as_pgt_render_frames_writes_it(moving, tmp_path, run_cli):
    """frames.frame(t) rendered from Python is the CLI's frame t (pgt render --frames), bit
    for bit, image and err layer."""
    out = tmp_path / "frames"
    run_cli("render", moving, "--size", "16x12", "--frames", "0..3", "-o", out / "f_%d.exr")
    frames = pgt.load_frames(moving, size=(16, 12))
    for t in range(3):
        result = pgt.render(frames.frame(t))
        cli = out / f"f_{t}.exr"
        np.testing.assert_array_equal(bits(result.image), bits(pgt.read_image(cli)))
        np.testing.assert_array_equal(bits(result.err), bits(pgt.read_image(cli, layer="err")))


def test_sh_colours_follow_each_frames_camera(tmp_path):
    """A Gaussian whose degree-1 SH has a strong z term, seen by a COLMAP sequence of two
    cameras on opposite sides: each frame's colour is 3DGS's computeColorFromSH for its own eye,
    written out here (0.5 + C1·z·coefficient, C1 = ½√(3/π))."""
    import math
    import struct

    names = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
    names += [f"f_rest_{k}" for k in range(9)]
    names += ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    # f_rest channel-major: red 1..3, green 1..3, blue 1..3; index 1 of each is the z term.
    row = [0.0] * 9 + [0.0, 0.75, 0.0, 0.0, -0.5, 0.0, 0.25, 0.0, 0.0]
    row += [0.0] + [math.log(0.5)] * 3 + [1.0, 0.0, 0.0, 0.0]
    head = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
    head += "".join(f"property float {n}\n" for n in names) + "end_header\n"
    (tmp_path / "g.ply").write_bytes(head.encode() + struct.pack(f"<{len(row)}f", *row))
    sparse = tmp_path / "sparse"
    sparse.mkdir()
    (sparse / "cameras.txt").write_text("1 PINHOLE 9 9 12 12 4.5 4.5\n")
    # a.jpg at (0, 0, -5) looking along +z; b.jpg (qvec (0, 0, 1, 0)) at (0, 0, 5) along -z.
    (sparse / "images.txt").write_text("1 1 0 0 0 0 0 5 1 a.jpg\n\n2 0 0 1 0 0 0 5 1 b.jpg\n\n")
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[camera]\nfrom = "sparse"\n[render]\nmodel = "emission"\n'
        '[[include]]\npath = "g.ply"\nsh = "view"\ndensity = "gaussian"\n'
    )
    frames = pgt.load_frames(scene)
    assert len(frames) == 2
    c1 = 0.5 * math.sqrt(3.0 / math.pi)
    for t, z in ((0, 1.0), (1, -1.0)):
        want = np.maximum(0.5 + c1 * z * np.array([0.75, -0.5, 0.0]), 0.0)
        np.testing.assert_allclose(frames.frame(t).particles()["color"][0], want, rtol=0, atol=1e-12)
