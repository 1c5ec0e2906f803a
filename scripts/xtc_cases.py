#!/usr/bin/env python3
"""Small XTC files for the decoder's edge cases (issue 44), written bit by bit from the layout in
src/formats/xtc.rs's module doc (the layout of GROMACS's libxdrfile).

Usage: python3 scripts/xtc_cases.py [OUT_DIR]   (default tests/data/xtc)

Every frame stores its atoms as "large" integer triples packed in one mixed-radix number,
each followed by a clear run flag (no small atoms), which any XTC decoder reads:
- smallidx0.xtc: 10 atoms, 2 frames, the initial small-integer index 0 (some writers store it;
  libxdrfile only clamps it for one table look-up). MDAnalysis reads it; its positions are
  tests/data/trajectory_vectors.json's "xtc_smallidx0" (scripts/trajectory_vectors.py).
- run_at_smallidx0.xtc: as above, but atom 1's flag starts a run of small atoms at index 0,
  which libxdrfile cannot unpack (it divides by the radix 0): pgt refuses it.
- over_block.xtc: the header says 13 atoms, the block holds 12 (its last byte's spare bits
  and the padding do not make a 13th).
- lying_count.xtc: the header says 2^31 - 1 atoms over a block of 8 bytes.
"""
import struct
import sys
from pathlib import Path

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "tests" / "data" / "xtc"
out.mkdir(parents=True, exist_ok=True)

PRECISION = 1000.0
MININT = (-500, 0, 250)
MAXINT = (1547, 1023, 1273)  # sizes 2048, 1024, 1024: the product is 2^31, packed in 32 bits


class Bits:
    """Bits written most significant first, as libxdrfile's decodebits reads them."""

    def __init__(self):
        self.bits = []

    def put(self, value, n):
        self.bits += [(value >> (n - 1 - i)) & 1 for i in range(n)]

    def packed(self, triple, sizes):
        """Three integers as one number (x*s1 + y)*s2 + z, its bytes least significant first,
        each byte 8 bits (the last one only the bits that remain)."""
        v = (triple[0] * sizes[1] + triple[1]) * sizes[2] + triple[2]
        total = sizes[0] * sizes[1] * sizes[2]
        nbits = total.bit_length() if total > 0 else 0
        while nbits > 8:
            self.put(v & 0xFF, 8)
            v >>= 8
            nbits -= 8
        if nbits > 0:
            self.put(v & ((1 << nbits) - 1), nbits)

    def bytes(self):
        b = self.bits + [0] * (-len(self.bits) % 8)
        return bytes(int("".join(map(str, b[i : i + 8])), 2) for i in range(0, len(b), 8))


def positions(frame, n):
    """Integer positions (units of 1/PRECISION nm) inside [MININT, MAXINT]."""
    return [
        (MININT[0] + (37 * k + 11 * frame) % 2048, MININT[1] + (101 * k + 3 * frame) % 1024, MININT[2] + (59 * k + 7) % 1024)
        for k in range(n)
    ]


def frame_bytes(step, time, declared, ints, smallidx=0, run_at=None, block_len=None):
    sizes = [MAXINT[c] - MININT[c] + 1 for c in range(3)]
    bits = Bits()
    for k, p in enumerate(ints):
        bits.packed([p[c] - MININT[c] for c in range(3)], sizes)
        if run_at == k:
            bits.put(1, 1)
            bits.put(3, 5)  # run 3: one small atom, the index unchanged
            bits.put(0, 0)
        else:
            bits.put(0, 1)
    block = bits.bytes()
    if block_len is not None:
        block = block[:block_len]
    head = struct.pack(">iiif", 1995, declared, step, time)
    head += struct.pack(">9f", 5.0, 0, 0, 0, 5.0, 0, 0, 0, 5.0)
    head += struct.pack(">i", declared)
    head += struct.pack(">f", PRECISION)
    head += struct.pack(">3i", *MININT) + struct.pack(">3i", *MAXINT)
    head += struct.pack(">i", smallidx)
    head += struct.pack(">I", len(block))
    return head + block + b"\0" * (-len(block) % 4)


(out / "smallidx0.xtc").write_bytes(
    frame_bytes(0, 0.0, 10, positions(0, 10)) + frame_bytes(100, 2.5, 10, positions(1, 10))
)
(out / "run_at_smallidx0.xtc").write_bytes(frame_bytes(0, 0.0, 10, positions(0, 10), run_at=1))
# 12 atoms of 33 bits (32 for the triple, one flag) fill 396 bits, 50 bytes with 4 spare bits:
# a 13th atom needs 33 more.
(out / "over_block.xtc").write_bytes(frame_bytes(0, 0.0, 13, positions(0, 12)))
(out / "lying_count.xtc").write_bytes(frame_bytes(0, 0.0, 2**31 - 1, positions(0, 2), block_len=8))
