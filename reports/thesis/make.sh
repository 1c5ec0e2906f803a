#!/bin/sh
# Regenerates reports/thesis/: the thesis's chapter 6 (Tables 6.1/6.2, Figures 6.2/6.3)
# reproduced with `pgt sweep`, against the exact reference and against the thesis's own GT,
# with the error attribution of N = 5 (see index.html).
#
#   reports/thesis/make.sh [SIDE]        # SIDE×SIDE pixels, default 96; the thesis used 512
#
# pgt comes from `cargo run --release` unless PGT names a binary (PGT=target/release/pgt).
# Needs: a wgpu adapter (on a machine without a GPU, Mesa's lavapipe: apt-get install
# mesa-vulkan-drivers libvulkan1), python3 (standard library only) for the combined page, and
# the 1UUN file below. Each sweep caches its reference in reports/thesis/*/cache/ (not
# committed); delete it to render the reference again.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
cd "$here"
side=${1:-96}
case "$side" in
    ''|*[!0-9]*) echo "make.sh: SIDE must be a whole number of pixels, got '$side'" >&2; exit 2 ;;
esac
if [ -n "${PGT:-}" ]; then
    pgt() { "$PGT" "$@"; }
else
    pgt() { cargo run --release --locked --quiet --manifest-path "$here/../../Cargo.toml" --bin pgt -- "$@"; }
fi

pdb=../../../shared/data/pdb/1uun_opm_oriented.pdb
if [ ! -f "$pdb" ]; then
    cat >&2 <<MSG
make.sh: 1UUN is missing: $here/$pdb
The thesis's first data set is chains A and B of 1UUN as oriented by OPM (2,758 atoms). It lives
in the project's shared data folder, ../shared beside the repository. Without it: download the
OPM-oriented entry 1uun (https://opm.phar.umich.edu, "Download coordinates") and save it as
../shared/data/pdb/1uun_opm_oriented.pdb relative to the repository root, then run this again.
MSG
    exit 2
fi

mkdir -p cache
if [ ! -f cache/random.csv ]; then
    # The thesis's random set: pgt gen random's defaults (73,642 particles, seed 1).
    pgt gen random -o cache/random.csv
fi
pgt info scenes/1uun.toml --json > cache/info_1uun.json
pgt info scenes/random.toml --json > cache/info_random.json
for set in 1uun random; do
    start=$(date +%s)
    pgt sweep "$set.toml" --size "${side}x${side}" --report "$set"
    echo "$(( $(date +%s) - start ))" > "cache/wall_$set.txt"
done
python3 assemble.py --side "$side"
echo "make.sh: open $here/index.html"
