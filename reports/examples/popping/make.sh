#!/bin/sh
# Regenerates the popping example: the exact reference and sorted-blend of every frame of
# orbit.toml, and their comparison with the temporal error. Needs pgt on PATH (cargo build
# --release; export PATH=$PWD/target/release:$PATH) and ../shared/data beside the repository.
set -eu
cd "$(dirname "$0")"
pgt render orbit.toml --frames 0..64 -o frames/ref/f_%03d.exr
pgt approx orbit.toml --frames 0..64 --method sorted-blend -o frames/sorted-blend/f_%03d.exr
pgt compare frames/ref frames/sorted-blend --no-flip --json summary.json --report report
