"""A 10,000-frame DCD of 100,000 atoms (12 GB) with its GRO topology, for the memory measurement of
docs/performance.md ("Sequences of frames"): pgt must not read a long trajectory whole.

    python3 scripts/big_dcd.py DIR     # writes DIR/sys.gro and DIR/traj.dcd (needs 12 GB free)

Every frame is the same random frame (CHARMM layout, Å; the GRO holds the same positions in nm).
"""
import os
import random
import struct
import sys
from array import array

out = sys.argv[1] if len(sys.argv) > 1 else "."
os.makedirs(out, exist_ok=True)
N, F = 100_000, 10_000
random.seed(1)
pos = [[round(random.uniform(0, 10.0), 3) for _ in range(3)] for _ in range(N)]  # nm, a 10 nm box
with open(os.path.join(out, 'sys.gro'), 'w') as g:
    g.write('synthetic 100,000 atoms\n%d\n' % N)
    for i in range(N):
        x, y, z = pos[i]
        g.write('%5d%-5s%5s%5d%8.3f%8.3f%8.3f\n' % ((i // 3 + 1) % 100000, 'SOL', 'OW' if i % 3 == 0 else 'HW1', (i + 1) % 100000, x, y, z))
    g.write('  10.00000  10.00000  10.00000\n')
def rec(f, payload):
    f.write(struct.pack('<I', len(payload))); f.write(payload); f.write(struct.pack('<I', len(payload)))
icntrl = [0] * 20
icntrl[0] = F; icntrl[2] = 1; icntrl[19] = 24
head = b'CORD' + b''.join(struct.pack('<f', 2.0) if k == 9 else struct.pack('<i', v) for k, v in enumerate(icntrl))
with open(os.path.join(out, 'traj.dcd'), 'wb') as f:
    rec(f, head)
    rec(f, struct.pack('<i', 1) + b' ' * 80)
    rec(f, struct.pack('<i', N))
    # GRO positions are rounded to 1e-3 nm; the DCD holds the same rounded values.
    frame = b''.join(struct.pack('<I', 4 * N) + array('f', [pos[i][a] * 10.0 for i in range(N)]).tobytes() + struct.pack('<I', 4 * N) for a in range(3))
    for _ in range(F):
        f.write(frame)
