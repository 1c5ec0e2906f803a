#!/bin/sh
# Regenerates the ellipsoid example: examples/ellipsoids.toml (a 1:20 needle, a 1:10 disc, a
# turned 1:4 cigar and a sphere, overlapping) in the emission model at 192x144, rendered exactly
# (reference.exr, with its err layer) and with two GPU methods, and compared. Needs pgt on PATH
# (cargo build --release; export PATH=$PWD/target/release:$PATH).
#   ever/          EVER's algorithm with EVER's cut-offs (16 events a batch, stop at T < 0.004,
#                  400 batches); ever_uncut.json: the same without the cut-offs (float32 alone)
#   sorted-blend/  centre-sorted whole-particle blending, as rasterisers do
set -eu
cd "$(dirname "$0")"
SCENE=../../../examples/ellipsoids.toml
pgt render "$SCENE" --model emission --size 192x144 -o reference.exr
pgt approx "$SCENE" --model emission --size 192x144 --method ever -o ever.exr
pgt approx "$SCENE" --model emission --size 192x144 --method ever \
    --param stop_below=0 --param max_batches=16777216 -o ever_uncut.exr
pgt approx "$SCENE" --model emission --size 192x144 --method sorted-blend -o sorted_blend.exr
pgt compare reference.exr ever.exr --json ever.json --report ever
pgt compare reference.exr ever_uncut.exr --json ever_uncut.json
pgt compare reference.exr sorted_blend.exr --json sorted_blend.json --report sorted-blend
