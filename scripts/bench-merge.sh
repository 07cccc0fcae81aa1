#!/usr/bin/env bash
# Benchmarks mc-merge (release) on synthetic shards and prints medians.
#
#   scripts/bench-merge.sh            # 50,000 samples x B = 2000, RUNS times; then 10 million samples once
#   RUNS=7 BIG=0 scripts/bench-merge.sh   # skip the 10-million-sample run
#
# Measures wall time and peak resident memory (GNU time's "Maximum resident set size") of
#   mc-merge SHARD_DIR --no-plots          (defaults: B = 2000, 1000 goodness-of-fit null samples)
# The shards are written by the example `synth-shards` (valid files, Rayleigh angles) into a
# temporary directory that is removed at the end. The 10-million-sample job is one case (the
# worst case for memory: the whole sample is sorted and bootstrapped at once) in 16 shards,
# about 2.3 GB of JSON Lines.
set -euo pipefail
cd "$(dirname "$0")/.."

RUNS=${RUNS:-5}
BIG=${BIG:-10000000}
TARGET=${CARGO_TARGET_DIR:-target}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/bench-merge.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

cargo build --release -p mc-merge --bin mc-merge --example synth-shards
BIN="$TARGET/release/mc-merge"
SYNTH="$TARGET/release/examples/synth-shards"

# Prints "SECONDS KIB" for one run of mc-merge with the given arguments.
measure() {
    /usr/bin/time -f "%e %M" -o "$WORK/time" "$BIN" "$@" >/dev/null
    cat "$WORK/time"
}

median() { sort -g | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

"$SYNTH" "$WORK/50k" --samples 50000 --shards 4
: > "$WORK/runs"
for _ in $(seq "$RUNS"); do measure "$WORK/50k" --no-plots >> "$WORK/runs"; done
echo "50,000 samples, B = 2000, $RUNS runs:"
echo "  wall time  [s]: $(cut -d' ' -f1 "$WORK/runs" | tr '\n' ' ')-> median $(cut -d' ' -f1 "$WORK/runs" | median)"
echo "  peak RSS [KiB]: $(cut -d' ' -f2 "$WORK/runs" | tr '\n' ' ')-> median $(cut -d' ' -f2 "$WORK/runs" | median)"

if [ "$BIG" -gt 0 ]; then
    "$SYNTH" "$WORK/big" --samples "$BIG" --shards 16
    echo "$BIG samples (one case, 16 shards, $(du -sh "$WORK/big" | cut -f1)), B = 2000:"
    read -r secs kib < <(measure "$WORK/big" --no-plots)
    echo "  wall time $secs s, peak RSS $kib KiB ($((kib / 1024)) MiB, $((kib * 1024 / BIG)) bytes per sample)"
    rm -rf "$WORK/big"
fi
