#!/usr/bin/env python3
"""Test vectors for pgt's 3D Gaussian splatting PLY reader (issue 34), computed with numpy alone:
the header is parsed here by hand and the vertices read with np.fromfile and a structured dtype,
so nothing is shared with the Rust reader but the documented mapping (docs/design.md §9,
"3D Gaussian splatting PLY").

Usage: python3 scripts/ply_vectors.py [SHARED_DATA] > tests/data/ply_vectors.json

SHARED_DATA defaults to ../shared/data beside the repository. For each file of splats/ the JSON
holds the vertex count, the SH degree, sums over all vertices (centres, semi-axes, α, DC colours)
and, for a few vertices (first, second, middle, last): the centre, the semi-axes with extent 3,
the normalised quaternion (w, x, y, z), α = sigmoid(opacity), the DC colour max(0, 0.5 + C0·f_dc)
and the view-dependent colour for the camera position CAMERA (the reference rasteriser's
computeColorFromSH, written out below from the real SH basis).
"""
import json
import math
import sys
from pathlib import Path

import numpy as np

root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared" / "data"
FILES = ["lod3_tile_0.ply", "fruit_drops_minimal.ply", "GSHairLoD_donut_fused.ply"]
EXTENT = 3.0
CAMERA = [2.0, 1.0, -5.0]
TYPES = {"float": "f4", "double": "f8", "uchar": "u1", "char": "i1", "int": "i4", "uint": "u4",
         "short": "i2", "ushort": "u2"}


def read(path):
    """The vertex element of a binary little-endian PLY as a structured array."""
    b = path.read_bytes()
    end = b.index(b"end_header\n") + len(b"end_header\n")
    lines = b[:end].decode("ascii").splitlines()
    assert lines[0] == "ply" and lines[1] == "format binary_little_endian 1.0", lines[:2]
    count, fields = None, []
    for line in lines[2:]:
        w = line.split()
        if w[0] == "element":
            assert w[1] == "vertex", line
            count = int(w[2])
        elif w[0] == "property":
            fields.append((w[2], "<" + TYPES[w[1]]))
    v = np.fromfile(path, dtype=np.dtype(fields), count=count, offset=end)
    assert len(v) == count
    return v


def sh_basis(d):
    """The real SH basis of degree 1-3 at unit direction d with the rasteriser's constants and
    signs: C1 = sqrt(3/pi)/2, C2 and C3 from their closed forms."""
    x, y, z = d
    c1 = 0.5 * math.sqrt(3 / math.pi)
    a = 0.5 * math.sqrt(15 / math.pi)
    c2 = [a, -a, 0.25 * math.sqrt(5 / math.pi), -a, 0.25 * math.sqrt(15 / math.pi)]
    p, q, r, s = (math.sqrt(35 / (2 * math.pi)), math.sqrt(105 / math.pi),
                  math.sqrt(21 / (2 * math.pi)), math.sqrt(7 / math.pi))
    c3 = [-0.25 * p, 0.5 * q, -0.25 * r, 0.25 * s, -0.25 * r, 0.25 * q, -0.25 * p]
    xx, yy, zz = x * x, y * y, z * z
    return [
        -c1 * y, c1 * z, -c1 * x,
        c2[0] * x * y, c2[1] * y * z, c2[2] * (2 * zz - xx - yy), c2[3] * x * z, c2[4] * (xx - yy),
        c3[0] * y * (3 * xx - yy), c3[1] * x * y * z, c3[2] * y * (4 * zz - xx - yy),
        c3[3] * z * (2 * zz - 3 * xx - 3 * yy), c3[4] * x * (4 * zz - xx - yy),
        c3[5] * z * (xx - yy), c3[6] * x * (xx - 3 * yy),
    ]


def derived(v, names):
    c0 = 0.5 * math.sqrt(1 / math.pi)
    f = lambda n: v[n].astype(np.float64)
    centre = np.stack([f("x"), f("y"), f("z")], axis=1)
    axes = EXTENT * np.exp(np.stack([f("scale_0"), f("scale_1"), f("scale_2")], axis=1))
    q = np.stack([f("rot_0"), f("rot_1"), f("rot_2"), f("rot_3")], axis=1)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    alpha = 1.0 / (1.0 + np.exp(-f("opacity")))
    dc = np.stack([f("f_dc_0"), f("f_dc_1"), f("f_dc_2")], axis=1)
    colour = np.maximum(0.5 + c0 * dc, 0.0)
    n_rest = sum(1 for n in names if n.startswith("f_rest_"))
    m = n_rest // 3
    rest = np.stack([f(f"f_rest_{k}") for k in range(n_rest)], axis=1) if n_rest else None
    return centre, axes, q, alpha, dc, colour, rest, m


def view_colour(centre, dc, rest, m):
    c0 = 0.5 * math.sqrt(1 / math.pi)
    d = centre - np.array(CAMERA)
    d = d / np.linalg.norm(d)
    basis = sh_basis(d)[:m]
    # Channel-major: coefficient j of channel c is f_rest_{c*m + j}.
    out = [c0 * dc[c] + sum(basis[j] * rest[c * m + j] for j in range(m)) + 0.5 for c in range(3)]
    return [max(v, 0.0) for v in out]


def vectors(path):
    v = read(path)
    names = v.dtype.names
    centre, axes, q, alpha, dc, colour, rest, m = derived(v, names)
    n = len(v)
    picks = sorted({0, 1, n // 2, n - 1})
    out = {
        "vertices": n,
        "sh_degree": {0: 0, 3: 1, 8: 2, 15: 3}[m],
        "sums": {
            "center": centre.sum(axis=0).tolist(),
            "semi_axes": axes.sum(axis=0).tolist(),
            "alpha": float(alpha.sum()),
            "dc_color": colour.sum(axis=0).tolist(),
        },
        "samples": [],
    }
    for i in picks:
        s = {
            "index": i,
            "center": centre[i].tolist(),
            "semi_axes": axes[i].tolist(),
            "rotation": q[i].tolist(),
            "alpha": float(alpha[i]),
            "dc_color": colour[i].tolist(),
        }
        if m:
            s["view_color"] = view_colour(centre[i], dc[i], rest[i], m)
        out["samples"].append(s)
    return out


print(json.dumps({
    "extent": EXTENT,
    "camera": CAMERA,
    "files": {name: vectors(root / "splats" / name) for name in FILES},
}, indent=1))
