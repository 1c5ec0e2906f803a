"""How far m*², the squared Mahalanobis distance of a Gaussian's centre from a ray, computed in
f64 as pgt computes it (src/optics/gaussian.rs `GaussianAlongRay::new`, and
shaders/reference_gaussian.wgsl `gauss_profile`: u0 = M(o − c), v̂ = M·d/|M·d|,
across = u0 − (u0·v̂)v̂, m*² = |across|²), lies from the same quantity computed with mpmath at
60 digits on the same f64 inputs (docs/performance.md "Batches of windows").

Usage: python3 scripts/m2_rounding.py SPLATS.ply [GAUSSIANS] [RAYS_EACH]
(needs numpy and mpmath; reads a 3D Gaussian splatting PLY's x y z, rot_0..3, scale_0..2).
"""
import sys

import mpmath as mp
import numpy as np

mp.mp.dps = 60


def read_ply(path):
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        lines = header.split(b"\n")
        props = [l.split()[-1].decode() for l in lines if l.startswith(b"property")]
        n = int([l for l in lines if l.startswith(b"element vertex")][0].split()[-1])
        data = np.frombuffer(f.read(4 * len(props) * n), dtype="<f4").reshape(n, len(props))
    return props, data.astype(np.float64)


def rotation(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def main():
    path = sys.argv[1]
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 400
    rays = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    props, a = read_ply(path)
    col = lambda k: a[:, props.index(k)]
    centres = np.stack([col("x"), col("y"), col("z")], 1)
    quats = np.stack([col(f"rot_{i}") for i in range(4)], 1)
    quats /= np.linalg.norm(quats, axis=1)[:, None]
    stds = np.exp(np.stack([col(f"scale_{i}") for i in range(3)], 1))
    rng = np.random.default_rng(1)
    eye = centres.mean(0) + np.array([0.0, 0.0, -12.0])
    found = []
    for i in rng.choice(len(centres), min(count, len(centres)), replace=False):
        m = np.diag(1.0 / stds[i]) @ rotation(quats[i]).T
        for _ in range(rays):
            d = centres[i] + rng.normal(size=3) * stds[i] * 2.0 - eye
            d /= np.linalg.norm(d)
            f = eye - centres[i]
            u0, v = m @ f, m @ d
            v_hat = v / np.linalg.norm(v)
            across = u0 - (u0 @ v_hat) * v_hat
            m2 = across @ across
            mm, fm, dm = mp.matrix(m.tolist()), mp.matrix(f.tolist()), mp.matrix(d.tolist())
            u0e, ve = mm * fm, mm * dm
            along = sum(u0e[j] * ve[j] for j in range(3)) / mp.sqrt(sum(x * x for x in ve))
            exact = sum(u0e[j] ** 2 for j in range(3)) - along * along
            if exact < 49:
                found.append((abs(m2 - float(exact)), float(exact), stds[i].min(), i))
    found.sort(reverse=True)
    for e, m2, smallest, i in found[:8]:
        print(f"|Δm*²| {e:.3e} at m*² {m2:.3f}, smallest std {smallest:.2e}, Gaussian {i}")
    print(f"pairs {len(found)}, median |Δm*²| {np.median([f[0] for f in found]):.3e}")


if __name__ == "__main__":
    main()
