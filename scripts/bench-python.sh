#!/usr/bin/env bash
# bench-python.sh: samples per second through the Python package against the CLI, on
# bench-shard.sh's job (the paper's 5-stage truss at σ = 0.0063 mm, 50,000 samples), with 1
# and 2 threads, in the same run and interleaved (CLI, Python, CLI, Python, …) so both see
# the same machine load; medians of RUNS runs (default 5).
#
# - CLI: the wall time of `mc-shard run` (start-up, solving and writing the shard file).
# - Python: the time of `Job.run()` in a running interpreter (solving, and turning every
#   record into the NumPy columns); the interpreter's start and imports, timed apart, are
#   printed once.
#
# Usage: scripts/bench-python.sh [RUNS]   (needs target/py-venv: scripts/setup.sh)
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RUNS="${1:-5}"
cd "$REPO"
[[ -x target/py-venv/bin/maturin ]] || scripts/setup.sh
cargo build --release --quiet -p mc-shard
# shellcheck disable=SC1091
. target/py-venv/bin/activate
maturin develop --release --quiet
WORK="$(mktemp -d /tmp/truss-mc-bench-py.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
cat > "$WORK/job.json" <<'JOB'
{"model": {"prism": {"stages": 5}}, "seed": 20210325, "cases": [
  {"name": "sigma-0.0063", "samples": 50000,
   "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}]}
JOB
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
cli() { # threads -> seconds
    rm -rf "$WORK/out"
    local start end
    start=$(date +%s.%N)
    target/release/mc-shard run --job "$WORK/job.json" --out "$WORK/out" --threads "$1" --quiet >/dev/null
    end=$(date +%s.%N)
    echo "$end - $start" | bc -l
}
py() { # threads -> seconds of Job.run
    python - "$WORK/job.json" "$1" <<'PY'
import sys, time
import truss_mc
job = truss_mc.Job.from_file(sys.argv[1])
t = time.perf_counter()
samples = job.run(threads=int(sys.argv[2]))
print(time.perf_counter() - t)
assert len(samples) == 50000
PY
}
start=$(date +%s.%N)
python -c "import truss_mc"
printf 'python start-up and import truss_mc (with numpy): %.2f s\n' "$(echo "$(date +%s.%N) - $start" | bc -l)"
for threads in 1 2; do
    : > "$WORK/cli$threads"
    : > "$WORK/py$threads"
    for _ in $(seq "$RUNS"); do
        cli "$threads" >> "$WORK/cli$threads"
        py "$threads" >> "$WORK/py$threads"
    done
    c=$(median < "$WORK/cli$threads")
    p=$(median < "$WORK/py$threads")
    printf 'threads %d: CLI %.0f samples/s (median %.3f s; runs %s), Python %.0f samples/s (median %.3f s; runs %s); Python / CLI %.2f\n' \
        "$threads" "$(echo "50000 / $c" | bc -l)" "$c" "$(tr '\n' ' ' < "$WORK/cli$threads")" \
        "$(echo "50000 / $p" | bc -l)" "$p" "$(tr '\n' ' ' < "$WORK/py$threads")" "$(echo "$c / $p" | bc -l)"
done
