#!/usr/bin/env python3
"""Checks that a reference render's `err` layer covers its actual error (issue 10).

    pip install OpenEXR numpy
    python3 scripts/err_coverage.py CANDIDATE.exr TRUTH.exr

TRUTH is the same scene rendered at a much tighter tol (1e-9), ideally by another version of
pgt, so that the check does not rest on the code under test. Prints the share of pixel channels
where |candidate - truth| > err(candidate) + err(truth) (the issue asks for at most 0.1 %), the
worst such pixel, and the largest actual error. Exit status 1 when the share is above 0.1 %.
"""
import sys

import numpy as np
import OpenEXR


def layers(path):
    ch = OpenEXR.File(path).channels()
    return ch["RGB"].pixels.astype(np.float64), ch["err"].pixels.astype(np.float64)


def main():
    (v, e), (t, et) = layers(sys.argv[1]), layers(sys.argv[2])
    actual = np.abs(v - t)
    over = actual > e + et
    share = over.mean()
    print(f"pixel channels: {actual.size}, err covers the actual error at "
          f"{100 * (1 - share):.3f} % ({over.sum()} not covered)")
    print(f"largest actual error {actual.max():.3e}, largest err {e.max():.3e}, "
          f"mean err {e.mean():.3e}")
    if over.any():
        ratio = np.where(over, actual / np.maximum(e + et, 1e-300), 0)
        y, x, c = np.unravel_index(np.argmax(ratio), ratio.shape)
        print(f"worst: pixel ({x}, {y}) channel {c}: actual {actual[y, x, c]:.3e}, "
              f"err {e[y, x, c]:.3e} + truth err {et[y, x, c]:.3e}")
    return 1 if share > 1e-3 else 0


if __name__ == "__main__":
    sys.exit(main())
