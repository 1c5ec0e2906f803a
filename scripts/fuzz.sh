#!/usr/bin/env bash
# Runs one cargo-fuzz target for a while: scripts/fuzz.sh TARGET SECONDS [LIBFUZZER ARGS...]
#
# TARGET is a file stem of fuzz/fuzz_targets/ (pdb, mmcif, vrml, mmpld, xyz, csv, gro, psf, dcd,
# xtc, ply, frames (the frame sources of pdb, xyz, mmpld, mmcif), colmap, transforms, dataparser,
# cameras_json, scene, gate,
# experiment). The corpus (fuzz/corpus/TARGET, not committed) is seeded with the files in
# tests/data and ../shared/data (when present), the examples and fuzz/seeds/TARGET. A crash is
# minimised into fuzz/artifacts/TARGET/minimized-*; commit it under tests/data/fuzz/TARGET with
# a regression test. One fuzzing process (libFuzzer's default; `-jobs=N` would fork N and log to
# files), niced (PGT_FUZZ_NICE, default 10: the machine is shared; 0 to fuzz at full speed).
#
# Needs a nightly toolchain (`rustup toolchain install nightly`); installs cargo-fuzz when it is
# missing. CARGO_TARGET_DIR is honoured (the fuzz build is separate from the normal one).
set -euo pipefail

if [[ $# -lt 2 ]]; then
    echo "usage: $0 TARGET SECONDS [LIBFUZZER ARGS...]" >&2
    exit 2
fi
target=$1
seconds=$2
shift 2

root=$(cd "$(dirname "$0")/.." && pwd)
fuzz="$root/fuzz"
if [[ ! -f "$fuzz/fuzz_targets/$target.rs" ]]; then
    echo "$0: no fuzz target '$target'; the targets are:" \
        $(cd "$fuzz/fuzz_targets" && ls ./*.rs | sed 's|^\./||; s|\.rs$||') >&2
    exit 2
fi
if ! [[ $seconds =~ ^[0-9]+$ ]]; then
    echo "$0: SECONDS must be a whole number, got '$seconds'" >&2
    exit 2
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi

# The seed corpus: every file of the data folders (libFuzzer cuts them at -max_len), the TOML
# examples for the TOML targets, and the target's own seeds. Copies, named by content, so that
# reruns do not duplicate them.
corpus="$fuzz/corpus/$target"
mkdir -p "$corpus"
seed_dirs=("$root/tests/data" "$fuzz/seeds/$target")
[[ -d "$root/../shared/data" ]] && seed_dirs+=("$root/../shared/data")
case $target in
scene) seed_dirs+=("$root/examples") ;;
gate | experiment) seed_dirs+=("$root/reports/examples") ;;
esac
for dir in "${seed_dirs[@]}"; do
    [[ -d $dir ]] || continue
    find "$dir" -type f -size -1024k -print0 | while IFS= read -r -d '' f; do
        cp "$f" "$corpus/seed-$(sha1sum <"$f" | cut -c1-16)"
    done
done

cd "$fuzz"
exec nice -n "${PGT_FUZZ_NICE:-10}" cargo +nightly fuzz run "$target" "$corpus" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 "$@"
