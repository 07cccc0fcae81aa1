#!/usr/bin/env bash
# bench-backlash.sh: throughput of the Fig. 16 study (jobs/paper-4.2.3.json, section 4.2.3)
# with backlash against the same cases without, on 2 threads: samples/s of each (wall time,
# start-up and writing included) and their ratio, medians of RUNS runs (default 5) since
# the machine is shared and noisy. The target: with backlash at least 0.3 of the throughput
# without.
#
# Usage: scripts/bench-backlash.sh [RUNS]
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${1:-5}"
cd "$REPO"
cargo build --release --quiet -p mc-shard
WORK="$(mktemp -d /tmp/truss-mc-bench-backlash.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
# The study's six σ, with or without backlash, as two jobs of 60,000 samples each.
python3 - "$WORK" <<'PY'
import json, sys
job = json.load(open("jobs/paper-4.2.3.json"))
for kind in ("backlash", "rigid"):
    cases = [c for c in job["cases"] if c["name"].startswith(kind + "-sigma-")]
    assert len(cases) == 6, kind
    json.dump({"model": job["model"], "seed": job["seed"], "cases": cases},
              open(f"{sys.argv[1]}/{kind}.json", "w"))
PY
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
for kind in backlash rigid; do
    : > "$WORK/t-$kind"
    for _ in $(seq "$RUNS"); do
        rm -rf "$WORK/out"
        /usr/bin/time -f "%e" target/release/mc-shard run --job "$WORK/$kind.json" --out "$WORK/out" \
            --threads 2 --quiet 2>&1 >/dev/null | tail -1 >> "$WORK/t-$kind"
    done
    t=$(median < "$WORK/t-$kind")
    printf '%-8s: median %.3f s for 60,000 samples = %.0f samples/s on 2 threads (runs: %s)\n' \
        "$kind" "$t" "$(echo "60000 / $t" | bc -l)" "$(tr '\n' ' ' < "$WORK/t-$kind")"
done
tb=$(median < "$WORK/t-backlash"); tr_=$(median < "$WORK/t-rigid")
printf 'backlash / no backlash throughput: %.2f (target ≥ 0.3)\n' "$(echo "$tr_ / $tb" | bc -l)"
