#!/usr/bin/env bash
# Times whole `pgt compare` commands of two pgt binaries on the same 4K pairs, alternately, REPS
# times each (issue 14 item 5), and prints wall and CPU (user + system) seconds per run and the
# ratio of the medians. The machine may be shared: compare ratios within one run.
#
#   scripts/compare_timing.sh OLD_PGT NEW_PGT [DIR] [REPS]
#
# DIR holds the pairs (written there first if missing, by `cargo bench --bench compare --
# --write-pairs DIR`, benches/compare.rs): ldr_ref.png/ldr_approx.png and hdr_ref.exr/hdr_approx.exr.
set -euo pipefail
old=$1
new=$2
dir=${3:-/tmp/pgt-compare-timing}
reps=${4:-3}
if [ ! -e "$dir/hdr_approx.exr" ]; then
    cargo bench --bench compare -- --write-pairs "$dir"
fi
declare -A wall cpu
for rep in $(seq "$reps"); do
    for pair in ldr:png hdr:exr; do
        name=${pair%%:*}
        ext=${pair##*:}
        for which in old new; do
            bin=$old
            [ "$which" = new ] && bin=$new
            rc=0
            /usr/bin/time -o "$dir/time" -f "%e %U %S" "$bin" compare "$dir/${name}_ref.$ext" \
                "$dir/${name}_approx.$ext" --json "$dir/${name}_$which.json" >/dev/null 2>&1 || rc=$?
            # Exit 1 is a failed gate (none is set here); 2 is an error, which makes no timing.
            if [ "$rc" -gt 1 ]; then
                echo "$bin compare failed on the $name pair (exit $rc)" >&2
                exit 2
            fi
            read -r e u s < <(tail -1 "$dir/time")
            c=$(echo "$u + $s" | bc)
            echo "run $rep $name $which: wall $e s, cpu $c s"
            wall[$name.$which]+="$e "
            cpu[$name.$which]+="$c "
        done
    done
done
median() { tr ' ' '\n' | grep . | sort -g | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }
for name in ldr hdr; do
    wo=$(echo "${wall[$name.old]}" | median); wn=$(echo "${wall[$name.new]}" | median)
    co=$(echo "${cpu[$name.old]}" | median); cn=$(echo "${cpu[$name.new]}" | median)
    printf '%s median: wall %s -> %s s (%.2fx), cpu %s -> %s s (%.2fx)\n' "$name" "$wo" "$wn" \
        "$(echo "$wo / $wn" | bc -l)" "$co" "$cn" "$(echo "$co / $cn" | bc -l)"
done
