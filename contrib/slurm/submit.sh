#!/usr/bin/env bash
# Submits a pgt cluster render to Slurm: an array job of N parts and a merge job that runs when
# all of them have succeeded (and is cancelled, not left pending, when one fails).
#
#   contrib/slurm/submit.sh SCENE N OUT [pgt render options...]
#
# Parts go to OUT.parts/; extra sbatch options (partition, time, account) in SBATCH_OPTS.
# Prints the two job ids. PGT names the pgt binary if it is not on PATH (the jobs inherit it).
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 SCENE N OUT [pgt render options...]" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$1 parts=$2 out=$3
shift 3
if ! [[ $parts =~ ^[1-9][0-9]*$ ]]; then
    echo "$0: N must be a positive integer, got '$parts'" >&2
    exit 2
fi
dir="$out.parts"
# shellcheck disable=SC2086 # SBATCH_OPTS is a list of options
array=$(sbatch --parsable ${SBATCH_OPTS:-} --array=0-$((parts - 1)) \
    "$here/render.sbatch" "$scene" "$parts" "$dir" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_OPTS:-} --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
    "$here/merge.sbatch" "$dir" "$parts" "$out")
merge=${merge%%;*}
echo "render array job $array ($parts parts into $dir), merge job $merge (into $out)"
