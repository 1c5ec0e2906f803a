#!/usr/bin/env python3
"""Test vectors for pgt's frame readers (issue 32), computed with MDAnalysis (an independent
implementation of DCD, XTC, PSF, GRO, multi-model PDB and multi-frame XYZ) and, for MMPLD, a
plain struct reading of the file.

Usage: python3 scripts/trajectory_vectors.py [SHARED_DATA] > tests/data/trajectory_vectors.json

SHARED_DATA defaults to ../shared/data beside the repository. Needs MDAnalysis
(`python3 -m venv /tmp/mdaenv && /tmp/mdaenv/bin/pip install MDAnalysis`). For each source the
JSON holds the frame count, the atoms per frame, the time step (ps, where the format has one)
and the positions in Å of a few atoms (first, second, middle, last) in the first, second and
last frames.
"""
import json
import struct
import sys
from pathlib import Path

import MDAnalysis as mda

root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared" / "data"
traj = root / "trajectories"
xtc_cases = Path(__file__).resolve().parents[1] / "tests" / "data" / "xtc"


def sample(universe, timed=True):
    """Frames, atoms, time step (formats with times) and a few positions of a Universe."""
    n = universe.atoms.n_atoms
    nf = universe.trajectory.n_frames
    atoms = sorted({0, 1, n // 2, n - 1})
    frames = sorted({0, min(1, nf - 1), nf - 1})
    out = {
        "frames": nf,
        "atoms": n,
        "atom_indices": atoms,
        "frame_indices": frames,
        "positions": {},
    }
    out["time_step_ps"] = float(universe.trajectory.dt) if timed and nf > 1 else None
    for f in frames:
        universe.trajectory[f]
        pos = universe.atoms.positions
        out["positions"][str(f)] = [[float(v) for v in pos[a]] for a in atoms]
    return out


def mmpld_v100(path):
    """Frames of an MMPLD 1.0 file, read with struct (version 1.0: no timestamps)."""
    b = path.read_bytes()
    assert b[:6] == b"MMPLD\0"
    version, frames = struct.unpack_from("<HI", b, 6)
    table = struct.unpack_from("<%dQ" % (frames + 1), b, 60)
    vertex_bytes = {1: 12, 2: 16, 3: 6, 4: 24}
    colour_bytes = {0: 0, 1: 3, 2: 4, 3: 4, 4: 12, 5: 16, 6: 8, 7: 8}
    counts = []
    first = last = None
    for k in range(frames):
        at = table[k]
        (lists,) = struct.unpack_from("<i", b, at)
        at += 4
        centres = []
        for _ in range(lists):
            vt, ct = b[at], b[at + 1]
            at += 2
            if vt in (1, 3, 4):
                at += 4
            if ct == 0:
                at += 4
            if ct in (3, 7):
                at += 8
            (count,) = struct.unpack_from("<Q", b, at)
            at += 8
            stride = vertex_bytes.get(vt, 0) + colour_bytes[ct]
            for i in range(count):
                p = at + i * stride
                if vt in (1, 2):
                    centres.append(list(struct.unpack_from("<3f", b, p)))
                elif vt == 4:
                    centres.append(list(struct.unpack_from("<3d", b, p)))
                elif vt == 3:
                    centres.append([float(v) for v in struct.unpack_from("<3h", b, p)])
            at += count * stride
        counts.append(len(centres))
        if k == 0:
            first = centres
        last = centres
    pick = lambda c: [c[0], c[len(c) // 2], c[-1]]
    return {
        "version": version,
        "frames": frames,
        "particles_per_frame": counts,
        "first_frame": pick(first),
        "last_frame": pick(last),
    }


vectors = {
    "generator": "scripts/trajectory_vectors.py with MDAnalysis " + mda.__version__,
    "ala3_dcd": sample(mda.Universe(str(traj / "ala3.psf"), str(traj / "ala3.dcd"))),
    "tip125_dcd": sample(
        mda.Universe(str(traj / "tip125_tric_C36.psf"), str(traj / "tip125_tric_C36.dcd"))
    ),
    "ngl_md_xtc": sample(mda.Universe(str(traj / "ngl_md.gro"), str(traj / "ngl_md.xtc"))),
    "md_ascii_trj_pdb": sample(mda.Universe(str(traj / "md_ascii_trj.pdb")), timed=False),
    "1lvz_pdb": sample(mda.Universe(str(traj / "1LVZ.pdb")), timed=False),
    "1lvz_cif": sample(mda.Universe(str(traj / "1LVZ.cif")), timed=False),
    "ala3_pdb": sample(mda.Universe(str(traj / "ala3.pdb")), timed=False),
    "ngl_md_gro": sample(mda.Universe(str(traj / "ngl_md.gro")), timed=False),
    "2r9r_xyz": sample(mda.Universe(str(traj / "2r9r-1b.xyz")), timed=False),
    # Written by scripts/xtc_cases.py: the initial small-integer index 0.
    "xtc_smallidx0": sample(mda.Universe(str(xtc_cases / "smallidx0.xtc"))),
    "testspheres_mmpld": mmpld_v100(root / "mmpld" / "testspheres_old_v100.mmpld"),
}
json.dump(vectors, sys.stdout, indent=1)
print()
