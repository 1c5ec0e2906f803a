#!/bin/sh
# Regenerates the Gaussian splatting example: two of the splatting files of ../shared/data/splats
# (see its SOURCES.md) read as Gaussians (density = "gaussian", the scene files here, camera
# framed as for a bare particle file), emission model, 192x192, rendered exactly
# (NAME_reference.exr, with its err layer) and by the GPU methods splat, splat-pixel-sort and
# gauss-ray. Needs pgt on PATH (cargo build --release; export PATH=$PWD/target/release:$PATH)
# and ../shared/data beside the repository.
#
# Attribution (docs/design.md §5 "Sweeps and error attribution"): NAME_experiment.toml is a
# `pgt sweep` experiment with the three methods and the chain splat → splat-pixel-sort →
# gauss-ray → reference, one change a step (sorting, projection, model; the file says what
# each changes); its report NAME_sweep/ holds the table, the attribution's shares and the
# causes' error maps (they add up to splat − reference exactly). NAME_METHOD.json compares each
# method with the reference, and the report NAME_splat/ shows splat against it.
set -eu
cd "$(dirname "$0")"
for f in lod3_tile_0 fruit_drops_minimal; do
    pgt render "$f.toml" -o "${f}_reference.exr"
    for m in gauss-ray splat-pixel-sort splat; do
        pgt approx "$f.toml" --method "$m" -o "${f}_$m.exr"
        pgt compare "${f}_reference.exr" "${f}_$m.exr" --json "${f}_$m.json"
    done
    pgt compare "${f}_reference.exr" "${f}_splat.exr" --report "${f}_splat" > /dev/null
    rm -rf "${f}_sweep"
    pgt sweep "${f}_experiment.toml" --report "${f}_sweep"
done

# An orbit of lod3_tile_0 (lod3_orbit.toml: 12 frames, 6° a frame, 128x128), exactly and with
# splat and splat-pixel-sort: the sequence reports show where splatting pops (its global order
# changes with the view) and what a per-pixel order leaves of it. The frames are rendered anew
# (rm first: a frame whose render hash matches is skipped, and the hash does not see pgt's code).
mkdir -p orbit
rm -f orbit/*.exr
pgt render lod3_orbit.toml --frames 0..12 -o orbit/reference_%02d.exr
for m in splat splat-pixel-sort; do
    pgt approx lod3_orbit.toml --method "$m" --frames 0..12 -o "orbit/${m}_%02d.exr"
    pgt compare orbit/reference_%02d.exr "orbit/${m}_%02d.exr" --json "orbit_$m.json" --report "orbit_$m"
done
