#!/usr/bin/env bash
# bench-opensees.sh: time per sample of mc-shard against OpenSeesPy on the same problem, in
# the same run, on the same core, and check that both give the same answer.
#
# The problem is the rigid case of bench-instructions.sh: the paper's 5-stage prism
# (`truss model prism --stages 5`), battens and longerons with length errors N(0, 0.0063²) mm,
# seed 20210325. OpenSeesPy (scripts/opensees_prism.py) solves the model file with
# corotational trusses, each member's length error as an initial strain, and the SAME
# drawn errors as mc-shard (`mc-shard inputs`); the cables' compression ratio
# is mc-shard's working ratio 1e-4 on both sides (see opensees_prism.py's header).
# Each run, interleaved, by the clock and in CPU time (user + system):
#   mc-shard       `mc-shard run --threads 1` of BASE and BASE + SAMPLES samples, whole
#                  process: (time of the larger − time of the smaller) / SAMPLES, so that
#                  start-up cancels; once with the default engine (samples solved side by
#                  side in lanes) and once with TRUSS_LANES=off (one sample at a time),
#                  whose shards must be byte-identical
#   OpenSeesPy     OPENSEES_SAMPLES samples in one Python process, timed from the first
#                  sample to the last (model built once before; per sample the changed
#                  materials' initial strains and moduli are set, the domain reset and
#                  Newton run)
# Prints each run, then the medians over RUNS runs and the ratios "mc-shard is X times
# faster per sample" (the median of the runs' own ratios; CPU time is the figure to quote
# on a machine shared with other work, whose waiting for a core inflates the clock), and
# the largest relative difference of θ_P between the two over the OpenSeesPy samples
# (exit 1 if it is not below 1e-6 or an OpenSeesPy solve failed). All processes are
# pinned to core CORE with taskset where present.
# Where valgrind is installed (and INSTRUCTIONS is not 0), the script then counts the
# instructions per sample of each, once (cachegrind --cache-sim=no; they repeat to a
# fraction of a percent):
# mc-shard's as bench-instructions.sh counts them (2,200 samples minus 200), OpenSeesPy's
# as the difference between OPENSEES_SAMPLES and a fifth of them in its Python process,
# and prints their ratios: machine-independent, unlike the times.
#
# Usage: scripts/bench-opensees.sh [RUNS]        (default 3)
#   MC_SHARD=path/to/mc-shard  TRUSS=path/to/truss   use these builds (default: cargo build
#                                                    --release -p mc-shard -p truss-cli)
#   SAMPLES=20000 BASE=1000 OPENSEES_SAMPLES=500 CORE=0   the sizes and the core
#   INSTRUCTIONS=0                                   skip the instruction counts (40 s)
# Needs python3 with venv and the network to PyPI the first time: OpenSeesPy (pinned below)
# is installed into target/opensees-venv, and its shared library needs the Debian packages
# libblas3 and liblapack3, installed here if missing (as root, or with sudo).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
RUNS="${1:-3}"
SAMPLES="${SAMPLES:-20000}"
BASE="${BASE:-1000}"
OPENSEES_SAMPLES="${OPENSEES_SAMPLES:-500}"
CORE="${CORE:-0}"
INSTRUCTIONS="${INSTRUCTIONS:-1}"
OPENSEESPY_VERSION=3.7.1.2
[[ "$OPENSEES_SAMPLES" =~ ^[0-9]+$ && "$OPENSEES_SAMPLES" -ge 5 ]] || { echo "bench-opensees: OPENSEES_SAMPLES must be at least 5, got $OPENSEES_SAMPLES" >&2; exit 2; }
[[ "$RUNS" =~ ^[1-9][0-9]*$ ]] || { echo "bench-opensees: RUNS must be a positive integer, got $RUNS" >&2; exit 2; }

if [[ -z "${MC_SHARD:-}" || -z "${TRUSS:-}" ]]; then
    cargo build --release --quiet -p mc-shard -p truss-cli
fi
MC_SHARD="${MC_SHARD:-$REPO/target/release/mc-shard}"
TRUSS="${TRUSS:-$REPO/target/release/truss}"

VENV="$REPO/target/opensees-venv"
if [[ ! -x "$VENV/bin/python" ]]; then
    python3 -m venv "$VENV" || { echo "bench-opensees: python3 cannot make a virtual environment (Debian: apt-get install python3-venv)" >&2; exit 1; }
fi
if ! "$VENV/bin/python" -m pip show --quiet openseespy 2>/dev/null; then
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "openseespy==$OPENSEESPY_VERSION"
fi
if ! "$VENV/bin/python" -c 'import openseespy.opensees' >/dev/null 2>&1; then
    echo "bench-opensees: OpenSeesPy needs libblas.so.3 and liblapack.so.3; installing libblas3 liblapack3" >&2
    SUDO=""
    [[ $(id -u) -eq 0 ]] || SUDO="sudo"
    $SUDO apt-get update -q
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends libblas3 liblapack3
    "$VENV/bin/python" -c 'import openseespy.opensees' >/dev/null
fi

PIN=()
command -v taskset >/dev/null && PIN=(taskset -c "$CORE")
WORK="$(mktemp -d /tmp/truss-mc-opensees.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT

"$TRUSS" model prism --stages 5 > "$WORK/model.json"
# job SAMPLES -> $WORK/job-SAMPLES.json, the rigid case of bench-instructions.sh
job() {
    cat > "$WORK/job-$1.json" <<JOB
{"model": {"prism": {"stages": 5}}, "seed": 20210325, "cases": [
  {"name": "rigid", "samples": $1,
   "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}]}
JOB
}
small=$BASE
large=$((BASE + SAMPLES))
job "$small"
job "$large"
"$MC_SHARD" inputs --job "$WORK/job-$large.json" --range "0..$OPENSEES_SAMPLES" --out "$WORK/inputs.csv" >/dev/null

# seconds LANES SAMPLES: "wall cpu", the seconds of one whole `mc-shard run` (LANES: on or
# off), by the clock and in CPU time (user + system, from the kernel's accounting of the
# process), which a machine shared with other work disturbs far less than the clock.
seconds() {
    local out="$WORK/out-$1-$2"
    rm -rf "$out"
    local lanes=()
    [[ "$1" == off ]] && lanes=(TRUSS_LANES=off)
    python3 - env "${lanes[@]}" "${PIN[@]}" "$MC_SHARD" run --job "$WORK/job-$2.json" --out "$out" --threads 1 --quiet <<'PY'
import os, subprocess, sys, time
start = time.perf_counter()
child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)
_, status, usage = os.wait4(child.pid, 0)
wall = time.perf_counter() - start
if status != 0:
    sys.exit("bench-opensees: %s failed (wait status %d)" % (" ".join(sys.argv[1:]), status))
print(wall, usage.ru_utime + usage.ru_stime)
PY
}

# per_sample SMALL LARGE: µs per sample, "wall cpu", from two `seconds` lines
per_sample() {
    python3 -c 'import sys
a, b = map(float, sys.argv[1].split()), map(float, sys.argv[2].split())
print(" ".join("%.4f" % ((y - x) / int(sys.argv[3]) * 1e6) for x, y in zip(a, b)))' "$1" "$2" "$SAMPLES"
}

# One line per run: lanes µs/sample (wall cpu), lanes-off (wall cpu), OpenSeesPy's summary.
: > "$WORK/runs"
echo "bench-opensees: 5-stage prism, rigid (σ = 0.0063 mm, seed 20210325); RUNS=$RUNS of" \
    "mc-shard $SAMPLES samples (minus $BASE) and OpenSeesPy $OPENSEES_SAMPLES samples, on core $CORE"
for ((run = 1; run <= RUNS; run++)); do
    per=()
    for lanes in on off; do
        a=$(seconds "$lanes" "$small")
        b=$(seconds "$lanes" "$large")
        per+=("$(per_sample "$a" "$b")")
    done
    cmp -s "$WORK/out-on-$large"/*.jsonl "$WORK/out-off-$large"/*.jsonl \
        || { echo "bench-opensees: the shard in lanes differs from TRUSS_LANES=off" >&2; exit 1; }
    opensees=$("${PIN[@]}" "$VENV/bin/python" "$REPO/scripts/opensees_prism.py" \
        --model "$WORK/model.json" --inputs "$WORK/inputs.csv" \
        --lines "$(echo "$WORK/out-on-$large"/*.jsonl)" --samples "$OPENSEES_SAMPLES" 2>"$WORK/opensees.err") \
        || { cat "$WORK/opensees.err" >&2; exit 1; }
    echo "${per[0]} ${per[1]} $opensees" >> "$WORK/runs"
    python3 - "$run" "${per[0]}" "${per[1]}" "$opensees" <<'PY'
import json, sys
run = int(sys.argv[1])
lanes, off = (list(map(float, a.split())) for a in sys.argv[2:4])
o = json.loads(sys.argv[4])
ops = [o["seconds"] / o["samples"] * 1e6, o["cpu_seconds"] / o["samples"] * 1e6]
print("run %d (µs per sample, wall/CPU): mc-shard %.1f/%.1f in lanes, %.1f/%.1f TRUSS_LANES=off; "
      "OpenSeesPy %.0f/%.0f (%.2f Newton iterations)"
      % (run, lanes[0], lanes[1], off[0], off[1], ops[0], ops[1], o["iterations"]))
PY
done

python3 - "$WORK/runs" "$OPENSEESPY_VERSION" <<'PY'
import json, statistics, sys
rows = [line.split(" ", 4) for line in open(sys.argv[1])]
o = [json.loads(r[4]) for r in rows]
m = statistics.median
times = {  # µs per sample, (wall, cpu) per run
    "lanes": [(float(r[0]), float(r[1])) for r in rows],
    "off": [(float(r[2]), float(r[3])) for r in rows],
    "opensees": [(x["seconds"] / x["samples"] * 1e6, x["cpu_seconds"] / x["samples"] * 1e6) for x in o],
}
def med(name, k):
    return m(t[k] for t in times[name])
def ratio(name, k):  # median over runs of the run's own ratio
    return m(a[k] / b[k] for a, b in zip(times["opensees"], times[name]))
print("medians of %d runs, µs per sample:            wall       CPU" % len(rows))
print("  mc-shard, lanes (the default)      %10.2f %9.2f" % (med("lanes", 0), med("lanes", 1)))
print("  mc-shard, TRUSS_LANES=off          %10.2f %9.2f" % (med("off", 0), med("off", 1)))
print("  OpenSeesPy %-23s %10.1f %9.1f  (%.2f Newton iterations, %s per sample)"
      % (sys.argv[2], med("opensees", 0), med("opensees", 1), m(x["iterations"] for x in o), o[0]["per_sample"]))
print("mc-shard is %.1f times faster per sample than OpenSeesPy in CPU time (%.1f by the clock);"
      % (ratio("lanes", 1), ratio("lanes", 0)))
print("  with TRUSS_LANES=off %.1f times (%.1f by the clock)" % (ratio("off", 1), ratio("off", 0)))
analyze = [x["analyze_cpu_seconds"] / x["samples"] * 1e6 for x in o]
print("  OpenSees's analyze alone (without the Python setting each sample's materials): %.1f µs CPU,"
      " %.1f times mc-shard's in lanes" % (m(analyze), m(a / b[1] for a, b in zip(analyze, times["lanes"]))))
failed = sum(x["failed"] for x in o)
worst = max(x["max_relative_difference"] for x in o)
compared = min(x["compared"] for x in o)
print("θ_P: largest relative difference OpenSeesPy vs mc-shard %.1e over %d samples%s"
      % (worst, compared, "; %d OpenSeesPy solves FAILED" % failed if failed else ""))
if failed or compared < o[0]["samples"] or not worst < 1e-6:
    sys.exit("bench-opensees: the two solvers do not agree")
PY

[[ "$INSTRUCTIONS" != 0 ]] && command -v valgrind >/dev/null || exit 0
# instructions LANES COMMAND...: the instructions one run of COMMAND executes, with
# TRUSS_LANES=LANES in its environment (on: the default engine)
instructions() {
    env "TRUSS_LANES=$1" valgrind --tool=cachegrind --cache-sim=no \
        --cachegrind-out-file="$WORK/cg.out" "${@:2}" >/dev/null 2>&1
    awk '/^summary:/ {print $2}' "$WORK/cg.out"
}
job 200
job 2200
counts=()
for lanes in on off; do
    for n in 200 2200; do
        rm -rf "$WORK/out-count"
        counts+=("$(instructions "$lanes" "$MC_SHARD" run --job "$WORK/job-$n.json" --out "$WORK/out-count" --threads 1 --quiet)")
    done
done
few=$((OPENSEES_SAMPLES / 5))
for n in "$few" "$OPENSEES_SAMPLES"; do
    counts+=("$(instructions on "$VENV/bin/python" "$REPO/scripts/opensees_prism.py" \
        --model "$WORK/model.json" --inputs "$WORK/inputs.csv" --samples "$n")")
done
python3 - "$few" "$OPENSEES_SAMPLES" "${counts[@]}" <<'PY'
import sys
few, many = int(sys.argv[1]), int(sys.argv[2])
c = list(map(int, sys.argv[3:]))
lanes, off = (c[1] - c[0]) / 2000, (c[3] - c[2]) / 2000
ops = (c[5] - c[4]) / (many - few)
print("instructions per sample: mc-shard %.0f in lanes, %.0f TRUSS_LANES=off; OpenSeesPy %.0f;"
      % (lanes, off, ops))
print("  OpenSeesPy executes %.1f times mc-shard's instructions (lanes), %.1f times (TRUSS_LANES=off)"
      % (ops / lanes, ops / off))
PY
