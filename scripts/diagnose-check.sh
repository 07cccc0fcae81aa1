#!/usr/bin/env bash
# diagnose-check.sh: the hidden-effect checks of `truss diagnose`'s forward selection
# (issues 7, 14 and 15), with the release build. Too slow for CI (tens of minutes): not part
# of scripts/test.sh, whose default and slow tiers run smaller versions of the key checks.
#
# Data: made by `truss synth-measured` from jobs/diagnose-baseline.json (the paper's 5-stage
# prism, σ = 6.3 µm on battens and longerons, section 3.1) or, for backlash, from section
# 4.2.3's truss (jobs/paper-4.2.3.json, σ = 0.033 mm), with 1 µm instrument noise, under
# seeds independent of the jobs' (fixed below, chosen before the results were seen).
#
# The checks, each marked PASSED or FAILED without stopping at the first failure:
# - null: no hidden effect, ≥ 10 seeds: no effect may be named (named_effects = []).
# - single: each of the six candidate effects hidden alone, ≥ 5 seeds each: exactly that
#   effect named, nothing after it.
# - pairs: two effects hidden at once, each pair mixing a mean shift with a change of
#   scatter (gravity + length_sigma; thermal_gradient + length_sigma; diagonal_pretension +
#   length_sigma): both named, in either order, nothing else.
# - backlash with members: the paper's clearances U[0.004, 0.017] mm (made by the job's
#   own backlash case), members measured one by one: backlash named.
# - backlash without members: node positions alone: backlash named, or listed as
#   indistinguishable from length_bias / diagonal_pretension (with that verdict the report
#   says to measure the member lengths).
# Each check prints the named effects, every fitted parameter against the truth with its
# 95 % profile interval, and the gap shrink (energy distance before -> after).
#
# Usage (from the repo root or anywhere): scripts/diagnose-check.sh [WORKDIR]
#   SPECIMENS=N (default 200), NULL_SEEDS="…", SINGLE_SEEDS="…", ONLY="null single pairs
#   backlash" (a subset of the groups). Needs python3.
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WORK="${1:-$(mktemp -d)}"
mkdir -p "$WORK"
cd "$REPO" || exit 4
cargo build --release -p truss-cli --quiet || exit 1
TARGET="${CARGO_TARGET_DIR:-$REPO/target}"
T="$TARGET/release/truss"
J="$REPO/jobs/diagnose-baseline.json"
P="$REPO/jobs/paper-4.2.3.json"
N="${SPECIMENS:-200}"
NULL_SEEDS="${NULL_SEEDS:-101 102 103 104 105 106 107 108 109 110}"
SINGLE_SEEDS="${SINGLE_SEEDS:-201 202 203 204 205}"
ONLY="${ONLY:-null single pairs backlash}"
passed=0
failed=0
failures=()

# check NAME EXPECT JOB CASE SYNTH_CASE MEMBERS EFFECT SEED [PARAM=TRUTH ...]
#   EXPECT: "-" for no effect, "a,b" for exactly these effects in any order, or
#   "backlash|indistinguishable" for backlash named or listed as indistinguishable from a
#   length effect.
check() {
  local name=$1 expect=$2 job=$3 case=$4 synth_case=$5 members=$6 effect=$7 seed=$8
  shift 8
  local synth_members=() diagnose_members=()
  if [[ $members == 1 ]]; then
    synth_members=(--members-out "$WORK/$name-members.csv")
    diagnose_members=(--measured-members "$WORK/$name-members.csv")
  fi
  local start end
  start=$(date +%s.%N)
  if ! "$T" synth-measured --job "$job" --case "$synth_case" --specimens "$N" --seed "$seed" \
      --effect "$effect" --measurement-sigma 0.001 "${synth_members[@]}" > "$WORK/$name.csv" \
    || ! "$T" diagnose --job "$job" --case "$case" --measured "$WORK/$name.csv" \
      --measurement-sigma 0.001 "${diagnose_members[@]}" --out "$WORK/$name" --quiet --no-plots \
      > /dev/null 2> "$WORK/$name.stderr"; then
    echo "$name: synth-measured or diagnose failed: $(tail -3 "$WORK/$name.stderr" 2>/dev/null)"
    echo "    FAILED"
    failed=$((failed + 1))
    failures+=("$name")
    return 0
  fi
  end=$(date +%s.%N)
  if python3 - "$WORK/$name/diagnosis.json" "$name" "$effect" "$expect" "$start" "$end" "$@" <<'PY'
import json, sys
path, name, effect, expect, start, end, *truth = sys.argv[1:]
d = json.load(open(path))
named = d["named_effects"]
before, after = d["discrepancy_before"], d["discrepancy_after"]
shrink = 100 * (1 - after / before) if before > 0 else 0.0
print(f"{name:<18} hidden {effect:<58} named {', '.join(named) or '-':<34} "
      f"gap {before:.4f} -> {after:.4f} ({shrink:.0f} % closed)  {float(end) - float(start):.0f} s, "
      "steps " + " ".join("%.0f" % s["seconds"] for s in d["steps"]) + " s")
if expect == "-":
    ok = named == []
elif expect == "backlash|indistinguishable":
    ind = {n for s in d["steps"] for n in s["indistinguishable"]}
    ok = "backlash" in named or (
        "backlash" in ind and bool(set(named) & {"length_bias", "diagonal_pretension"}))
else:
    ok = sorted(named) == sorted(expect.split(","))
for s in d["steps"]:
    if s["indistinguishable"]:
        print(f"    step {s['number']}: {s['named_effect']} indistinguishable from {', '.join(s['indistinguishable'])}")
params = {}
for s in d["steps"]:
    if s["kept"]:
        for p in s["parameters"]:
            params[p["name"]] = p
def f(x):
    return "?" if x is None else f"{x:.5g}"
for t in truth:
    k, v = t.split("=")
    v = float(v)
    if k not in params:
        print(f"    {k:<16} truth {v:<8g} not fitted")
        continue
    p = params[k]
    i = p["interval"]
    inside = i["lower"] is not None and i["upper"] is not None and i["lower"] <= v <= i["upper"]
    j = p.get("joint_interval") or {}
    jin = j.get("lower") is not None and j.get("upper") is not None and j["lower"] <= v <= j["upper"]
    print(f"    {k:<16} truth {v:<8g} fit {p['value']:<11.5g} 95 % {i['method']} [{f(i['lower'])}, {f(i['upper'])}] "
          f"{'holds' if inside else 'misses'} the truth; joint [{f(j.get('lower'))}, {f(j.get('upper'))}] {'holds' if jin else 'misses'} it")
print("    PASSED" if ok else "    FAILED")
sys.exit(0 if ok else 1)
PY
  then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    failures+=("$name")
  fi
}

run_group() { [[ " $ONLY " == *" $1 "* ]]; }

B="as-built"
if run_group null; then
  for s in $NULL_SEEDS; do
    check "null-$s" - "$J" $B $B 0 none "$s"
  done
fi
if run_group single; then
  for s in $SINGLE_SEEDS; do
    check "gravity-$s" gravity "$J" $B $B 0 "gravity:g_x=1" "$s" g_x=1 g_y=0 g_z=0
    check "thermal-$s" thermal_gradient "$J" $B $B 0 "thermal_gradient:gradient_x=0.002,offset=2" "$s" \
      gradient_x=0.002 gradient_y=0 gradient_z=0 offset=2
    check "bias-$s" length_bias "$J" $B $B 0 "length_bias:bias.longeron=0.003" "$s" \
      bias.longeron=0.003 bias.batten=0
    check "sigma-$s" length_sigma "$J" $B $B 0 "length_sigma:sigma.longeron=0.012" "$s" \
      sigma.longeron=0.012 sigma.batten=0.0063
    check "pretension-$s" diagonal_pretension "$J" $B $B 0 "diagonal_pretension:length_error=-0.05" "$s" \
      length_error=-0.05
    check "backlash-$s" backlash "$P" rigid-sigma-0.033 rigid-sigma-0.033 1 "backlash:clearance=0.0105" "$s" \
      clearance=0.0105
  done
fi
if run_group pairs; then
  check "pair-gravity-sigma" gravity,length_sigma "$J" $B $B 0 \
    "gravity:g_x=1;length_sigma:sigma.longeron=0.012" 301 g_x=1 g_y=0 g_z=0 sigma.longeron=0.012 sigma.batten=0.0063
  check "pair-thermal-sigma" thermal_gradient,length_sigma "$J" $B $B 0 \
    "thermal_gradient:gradient_x=0.002,offset=2;length_sigma:sigma.batten=0.015" 302 \
    gradient_x=0.002 gradient_y=0 gradient_z=0 offset=2 sigma.longeron=0.0063 sigma.batten=0.015
  check "pair-pretension-sigma" diagonal_pretension,length_sigma "$J" $B $B 0 \
    "diagonal_pretension:length_error=-0.05;length_sigma:sigma.batten=0.015" 303 \
    length_error=-0.05 sigma.longeron=0.0063 sigma.batten=0.015
fi
if run_group backlash; then
  # The paper's clearances scatter among the joints (U[0.004, 0.017] mm); the candidate's
  # one clearance stands for their mean, 0.0105 mm.
  check "paper-backlash+mm" backlash "$P" rigid-sigma-0.033 backlash-sigma-0.033 1 none 401 clearance=0.0105
  check "paper-backlash" "backlash|indistinguishable" "$P" rigid-sigma-0.033 backlash-sigma-0.033 0 none 401 \
    clearance=0.0105
fi
echo
echo "$passed passed, $failed failed${failures[*]:+: ${failures[*]}}; outputs in $WORK"
[[ $failed == 0 ]]
