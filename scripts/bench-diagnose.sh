#!/usr/bin/env bash
# bench-diagnose.sh: wall and CPU time of a three-effect diagnosis, with the release build.
#
# Data: `truss synth-measured` on section 4.2.3's truss (jobs/paper-4.2.3.json, case
# rigid-sigma-0.033: battens and longerons N(0, 0.033²) mm, diagonals U[−0.099, 0] mm),
# SPECIMENS specimens (default 200) with their members measured, 1 µm instrument noise,
# seed SEED (default 601), three effects hidden at once:
#   backlash             clearance 0.0105 mm, spread 0.0065 mm (the paper's U[0.004, 0.017])
#   diagonal_pretension  every diagonal 0.05 mm short
#   length_sigma         the diagonals scatter twice as widely (σ 0.0572 mm, stated 0.0286)
# `truss diagnose` runs on them RUNS times (default 1) under /usr/bin/time; each run prints
# its wall and CPU (user + sys) seconds, the named effects, the seconds of each stage
# (`timing.stages` in diagnosis.json: the baseline's simulation and comparison, each step's
# comparison, candidate fits, decision and update, the final fit and the confounding
# tests), and each final interval against the hidden value (holds / MISSES). The machine's
# load average is printed with each run: on a shared machine the CPU time says more than
# the wall time.
#
# Usage (from anywhere): scripts/bench-diagnose.sh [WORKDIR]
#   SPECIMENS=N, SEED=S, RUNS=R, THREADS=T (`truss diagnose --threads`; default all cores),
#   SAMPLES=N (`truss diagnose --samples`; default the diagnosis's own, 4,000 at 200 specimens),
#   TRUSS=PATH (a built `truss` binary instead of building the release one). Needs python3.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/truss-binary.sh" "$@"
N="${SPECIMENS:-200}"
SEED="${SEED:-601}"
RUNS="${RUNS:-1}"
threads=()
[[ -n "${THREADS:-}" ]] && threads=(--threads "$THREADS")
J="$REPO/jobs/paper-4.2.3.json"
C=rigid-sigma-0.033
"$T" synth-measured --job "$J" --case $C --specimens "$N" --seed "$SEED" \
  --effect "backlash:clearance=0.0105,spread=0.0065;diagonal_pretension:length_error=-0.05;length_sigma:sigma.diagonal=0.0572" \
  --measurement-sigma 0.001 --members-out "$WORK/members.csv" > "$WORK/nodes.csv"
for r in $(seq 1 "$RUNS"); do
  out="$WORK/run-$r"
  load=$(cut -d' ' -f1-3 /proc/loadavg)
  /usr/bin/time -v -o "$WORK/time-$r.txt" "$T" diagnose --job "$J" --case $C \
    --measured "$WORK/nodes.csv" --measured-members "$WORK/members.csv" \
    --measurement-sigma 0.001 "${threads[@]}" "${SAMPLES_OPTION[@]}" --out "$out" --no-plots \
    2> "$out.stderr" > /dev/null
  python3 - "$out/diagnosis.json" "$WORK/time-$r.txt" "$r" "$load" <<'PY'
import json, re, sys
path, timing, run, load = sys.argv[1:]
d = json.load(open(path))
t = open(timing).read()
def field(name):
    return re.search(re.escape(name) + r": (.*)", t).group(1).strip()
user, system = float(field("User time (seconds)")), float(field("System time (seconds)"))
wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss)")
parts = [float(x) for x in wall.split(":")]
wall_s = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
print(f"run {run}: wall {wall_s:.1f} s, CPU {user + system:.1f} s (user {user:.1f}, sys {system:.1f}), "
      f"load before {load}; named {', '.join(d['named_effects']) or '-'}")
stages = d["timing"].get("stages", [])
for stage in stages:
    print(f"    {stage['stage']:<44} {stage['seconds']:7.1f} s  ({stage['simulations']} simulations)")
if not stages:
    print("    steps " + " ".join(f"{s['seconds']:.0f}" for s in d["steps"]) + " s")
# The hidden values (the baseline's own σ for the bars' scatter): each final interval is
# marked by whether it holds its truth.
truth = {"backlash.clearance": 0.0105, "backlash.spread": 0.0065,
         "length_sigma.sigma.batten": 0.033, "length_sigma.sigma.longeron": 0.033,
         "length_sigma.sigma.diagonal": 0.0572, "diagonal_pretension.length_error": -0.05}
for e in d.get("final_fit", []):
    for p in e["parameters"]:
        i = p.get("joint_interval") or p["interval"]
        lo, hi = i.get("lower"), i.get("upper")
        name = f"{e['name']}.{p['name']}"
        held = ""
        if name in truth:
            held = ("holds" if lo is not None and hi is not None and lo <= truth[name] <= hi
                    else "MISSES") + f" the truth {truth[name]}"
        ends = "not found" if lo is None or hi is None else f"[{lo:.5g}, {hi:.5g}]"
        print(f"    {name} = {p['value']:.5g} {ends} ({i.get('method')}) {held}")
PY
done
