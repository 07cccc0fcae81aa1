#!/usr/bin/env bash
# bench-shard.sh: throughput of mc-shard on the paper's 5-stage job at σ = 0.0063 mm,
# 50,000 samples: wall time (start-up and writing included), samples/s with 1 and 2
# threads, the ratio, and peak memory; medians of RUNS runs (default 5), since the machine
# is shared and noisy. Also the memory of a 5x longer run, to show it is flat in the sample
# count.
#
# Usage: scripts/bench-shard.sh [RUNS]
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${1:-5}"
cd "$REPO"
cargo build --release --quiet -p mc-shard
WORK="$(mktemp -d /tmp/truss-mc-bench.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
job() {
    cat > "$WORK/job-$1.json" <<JOB
{"model": {"prism": {"stages": 5}}, "seed": 20210325, "cases": [
  {"name": "sigma-0.0063", "samples": $1,
   "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}]}
JOB
}
job 50000
job 250000
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
measure() { # threads samples -> "seconds peak_kib"
    rm -rf "$WORK/out"
    /usr/bin/time -f "%e %M" target/release/mc-shard run --job "$WORK/job-$2.json" --out "$WORK/out" --threads "$1" --quiet 2>&1 >/dev/null | tail -1
}
for threads in 1 2; do
    : > "$WORK/t$threads"
    : > "$WORK/m$threads"
    for _ in $(seq "$RUNS"); do
        read -r s m < <(measure "$threads" 50000)
        echo "$s" >> "$WORK/t$threads"
        echo "$m" >> "$WORK/m$threads"
    done
    t=$(median < "$WORK/t$threads")
    m=$(median < "$WORK/m$threads")
    printf 'threads %d: median %.3f s for 50,000 samples = %.0f samples/s (runs: %s); peak RSS %s KiB\n' \
        "$threads" "$t" "$(echo "50000 / $t" | bc -l)" "$(tr '\n' ' ' < "$WORK/t$threads")" "$m"
done
t1=$(median < "$WORK/t1"); t2=$(median < "$WORK/t2")
printf '2 threads / 1 thread: %.2fx\n' "$(echo "$t1 / $t2" | bc -l)"
read -r s m < <(measure 2 250000)
printf 'memory flat in the sample count: 250,000 samples in %.2f s, peak RSS %s KiB (50,000: %s KiB)\n' "$s" "$m" "$(median < "$WORK/m2")"
