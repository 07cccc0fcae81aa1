#!/usr/bin/env bash
# diagnose-check.sh: the full hidden-effect checks of `truss diagnose` (issue 7), with the
# release build, on 200 specimens with 1 µm instrument noise made by `truss synth-measured`
# from jobs/diagnose-baseline.json (the paper's 5-stage prism, σ = 6.3 µm on battens and
# longerons) under seeds independent of the job's. Each check prints the verdict, the
# recovered parameters against the truth with their 95 % intervals, the discrepancy before
# and after, and the wall time; the script fails if a check does not hold.
#
# Usage: scripts/diagnose-check.sh [WORKDIR]      (needs python3 for reading the JSON)
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WORK="${1:-$(mktemp -d)}"
mkdir -p "$WORK"
cd "$REPO"
cargo build --release -p truss-cli --quiet
TARGET="${CARGO_TARGET_DIR:-$REPO/target}"
T="$TARGET/release/truss"
J="$REPO/jobs/diagnose-baseline.json"
status=0

# check NAME EFFECT SEED SPECIMENS EXPECT [PARAM=TRUTH ...]
check() {
  local name=$1 effect=$2 seed=$3 n=$4 expect=$5
  shift 5
  "$T" synth-measured --job "$J" --case as-built --specimens "$n" --seed "$seed" \
    --effect "$effect" --measurement-sigma 0.001 > "$WORK/$name.csv"
  local start end
  start=$(date +%s.%N)
  "$T" diagnose --job "$J" --case as-built --measured "$WORK/$name.csv" \
    --measurement-sigma 0.001 --out "$WORK/$name" --quiet > /dev/null
  end=$(date +%s.%N)
  python3 - "$WORK/$name/diagnosis.json" "$name" "$effect" "$expect" \
    "$(echo "$end - $start" | bc)" "$@" <<'PY' || status=1
import json, sys
path, name, effect, expect, secs, *truth = sys.argv[1:]
d = json.load(open(path))
ok = True
line = f"{name:<11} hidden {effect:<48} n={d['data']['specimens_used']:<4} verdict {d['verdict']:<11} named {d['named_effect']:<19}"
line += f" disc {d['discrepancy_before']:.4f} -> {d['discrepancy_after']:.4f}  {float(secs):.1f} s"
print(line)
if expect in ("none", "cannot_tell", "unexplained"):
    ok &= d["verdict"] == expect
else:
    ok &= d["verdict"] == "named" and d["named_effect"] == expect
    ok &= d["discrepancy_after"] <= 0.5 * d["discrepancy_before"]
    if d["indistinguishable"]:
        print("    indistinguishable:", ", ".join(d["indistinguishable"]))
params = {p["name"]: p for p in d["parameters"]}
for t in truth:
    k, v = t.split("=")
    p = params[k]
    lo, hi = p["interval"]["lower"], p["interval"]["upper"]
    inside = lo is not None and lo <= float(v) <= hi
    ok &= inside
    print(f"    {k:<16} truth {float(v):<10g} fit {p['value']:<12.5g} 95 % CI [{lo:.5g}, {hi:.5g}] {'inside' if inside else 'OUTSIDE'}")
print("    ok" if ok else "    FAILED")
sys.exit(0 if ok else 1)
PY
}

check none        "none"                                           1  200 none
check thermal     "thermal_gradient:gradient_x=0.002,offset=2"     21 200 thermal_gradient gradient_x=0.002 gradient_y=0 gradient_z=0 offset=2
check bias        "length_bias:bias.longeron=0.003"                22 200 length_bias bias.longeron=0.003 bias.batten=0
check sigma       "length_sigma:sigma.longeron=0.012"              23 200 length_sigma sigma.longeron=0.012 sigma.batten=0.0063
check pretension  "diagonal_pretension:length_error=-0.05"         24 200 diagonal_pretension length_error=-0.05
check gravity     "gravity:g_x=1"                                  11 200 gravity g_x=1 g_y=0 g_z=0
check few         "thermal_gradient:gradient_x=0.0005"             25 12  cannot_tell
echo "outputs in $WORK"
exit $status
