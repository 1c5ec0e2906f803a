#!/bin/sh
# Regenerates reports/thesis/: the thesis's chapter 6 (Tables 6.1/6.2, Figures 6.2/6.3) on its
# two data sets (1UUN chains A+B, "cool random"), see index.html:
#   1. the tables at the thesis's 512×512 with its scheme in f64 on the CPU (cpu_*.toml),
#      against the exact reference and against the thesis's GT;
#   2. the parameter study over what the thesis leaves open (study/*.toml, and the conventions
#      and rest_model runs of cpu_*.toml);
#   3. the GPU method `thesis` with its timings (Figures 6.2/6.3) and the error attribution
#      (1uun.toml, cool_random.toml) at GPU_SIDE×GPU_SIDE pixels;
#   4. assemble.py: tables.json and index.html.
#
#   reports/thesis/make.sh [GPU_SIDE]     # default 64: what lavapipe manages; 512 on a real GPU
#
# pgt comes from `cargo run --release` unless PGT names a binary (PGT=target/release/pgt).
# Needs: a wgpu adapter (on a machine without a GPU, Mesa's lavapipe: apt-get install
# mesa-vulkan-drivers libvulkan1), python3 (standard library only), and the two data files
# below. Steps 1 and 2 write their sweeps under reports/thesis/cache/ (not committed; each
# caches its reference there: delete cache/ to render everything again).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
cd "$here"
gpu_side=${1:-64}
case "$gpu_side" in
    ''|*[!0-9]*) echo "make.sh: GPU_SIDE must be a whole number of pixels, got '$gpu_side'" >&2; exit 2 ;;
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

mmpld=../../../shared/data/mmpld/cool_random.mmpld
if [ ! -f "$mmpld" ]; then
    cat >&2 <<MSG
make.sh: "cool random" is missing: $here/$mmpld
The thesis's second data set (Table 6.2, 73,642 particles) is public as MegaMol's sample
cool_random.mmpld; ../shared/data/SOURCES.md beside the repository says where it comes from.
MSG
    exit 2
fi

mkdir -p cache/study
begin=$(date +%s)
for set in 1uun cool_random; do
    pgt info "scenes/$set.toml" --json > "cache/info_$set.json"
    start=$(date +%s)
    pgt sweep "cpu_$set.toml" --report "cache/cpu_$set"
    echo "$(( $(date +%s) - start ))" > "cache/wall_cpu_$set.txt"
done
for experiment in study/*.toml; do
    pgt sweep "$experiment" --report "cache/study/$(basename "$experiment" .toml)"
done
for set in 1uun cool_random; do
    start=$(date +%s)
    pgt sweep "$set.toml" --size "${gpu_side}x${gpu_side}" --report "$set"
    echo "$(( $(date +%s) - start ))" > "cache/wall_$set.txt"
done
echo "$(( $(date +%s) - begin ))" > cache/wall_total.txt
python3 assemble.py --gpu-side "$gpu_side"
echo "make.sh: open $here/index.html"
