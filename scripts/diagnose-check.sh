#!/usr/bin/env bash
# diagnose-check.sh: the full hidden-effect checks of `truss diagnose` (issue 7), with the
# release build, on 200 specimens with 1 µm instrument noise made by `truss synth-measured`
# from jobs/diagnose-baseline.json (the paper's 5-stage prism, σ = 6.3 µm on battens and
# longerons) under seeds independent of the job's. Each check prints the verdict, the
# recovered parameters against the truth with their 95 % intervals, the discrepancy before
# and after, and the wall time; the script fails if a check does not hold. `sigma+mm` is the
# σ check with the members' length errors measured one by one as well (--measured-members).
#
# What a check asks of a named effect with k parameters: the effect named, the discrepancy
# at least halved, and the truth inside the joint 95 % profile-likelihood region's projection
# on every parameter (`joint_interval`: all k at once with 95 % confidence). Each
# parameter's own 95 % interval (`interval`) and its Wald interval are printed beside it, and
# whether the truth is inside, but do not decide: asking all k of them to hold at once would
# fail a calibrated method with probability 1 − 0.95^k (14 % for gravity's three, 19 % for
# the thermal gradient's four, 46 % for the twelve parameters checked here together).
#
# With --coverage, instead: a coverage study. The effect (default the length_bias check's,
# bias.longeron = 0.003 mm) is hidden in COVERAGE_SPECIMENS (default 50) specimens under each
# of COVERAGE_SEEDS (default 1001…1020, fixed in advance), each diagnosed with the default N;
# for each parameter it prints how often the truth is inside its own 95 % profile interval,
# the joint interval and the Wald interval, with a Clopper–Pearson 95 % interval for the
# coverage. It reports, it does not fail.
#
# Usage: scripts/diagnose-check.sh [--coverage] [WORKDIR]      (needs python3 and bc)
#        COVERAGE_EFFECT=NAME:P=V,… COVERAGE_TRUTH="P=V …" COVERAGE_SPECIMENS=N
#        COVERAGE_SEEDS="S …" scripts/diagnose-check.sh --coverage
#        COVERAGE_JOB=J COVERAGE_CASE=C COVERAGE_SYNTH_CASE=C2 MEMBERS=1 (another job; the
#        specimens made from C2 with the effect, diagnosed against C)
set -euo pipefail
coverage=0
if [[ "${1:-}" == "--coverage" ]]; then
  coverage=1
  shift
fi
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WORK="${1:-$(mktemp -d)}"
mkdir -p "$WORK"
cd "$REPO"
cargo build --release -p truss-cli --quiet
TARGET="${CARGO_TARGET_DIR:-$REPO/target}"
T="$TARGET/release/truss"
J="$REPO/jobs/diagnose-baseline.json"
status=0

# run NAME EFFECT SEED SPECIMENS: synthesises and diagnoses (with MEMBERS=1 also the member
# length errors, measured one by one); prints the wall time. JOB (default $J), CASE (default
# as-built) and SYNTH_CASE (default CASE: the case the specimens are made from) choose
# another job.
run() {
  local name=$1 effect=$2 seed=$3 n=$4
  local job=${JOB:-$J} case=${CASE:-as-built}
  local synth_case=${SYNTH_CASE:-$case}
  local synth_members=() diagnose_members=()
  if [[ "${MEMBERS:-0}" == 1 ]]; then
    synth_members=(--members-out "$WORK/$name-members.csv")
    diagnose_members=(--measured-members "$WORK/$name-members.csv")
  fi
  "$T" synth-measured --job "$job" --case "$synth_case" --specimens "$n" --seed "$seed" \
    --effect "$effect" --measurement-sigma 0.001 "${synth_members[@]}" > "$WORK/$name.csv"
  local start end
  start=$(date +%s.%N)
  "$T" diagnose --job "$job" --case "$case" --measured "$WORK/$name.csv" \
    --measurement-sigma 0.001 "${diagnose_members[@]}" --out "$WORK/$name" --quiet > /dev/null
  end=$(date +%s.%N)
  echo "$end - $start" | bc
}

# check NAME EFFECT SEED SPECIMENS EXPECT [PARAM=TRUTH ...]   (EXPECT "any": only reported)
check() {
  local name=$1 effect=$2 seed=$3 n=$4 expect=$5
  shift 5
  local secs
  if ! secs=$(run "$name" "$effect" "$seed" "$n"); then
    echo "$name: truss synth-measured or diagnose failed (see above)"
    echo "    FAILED"
    status=1
    return 0
  fi
  python3 - "$WORK/$name/diagnosis.json" "$name" "$effect" "$expect" "$secs" "$@" <<'PY' || status=1
import json, sys
path, name, effect, expect, secs, *truth = sys.argv[1:]
d = json.load(open(path))
ok = True
line = f"{name:<11} hidden {effect:<48} n={d['data']['specimens_used']:<4} verdict {d['verdict']:<11} named {d['named_effect']:<19}"
line += f" disc {d['discrepancy_before']:.4f} -> {d['discrepancy_after']:.4f}  {float(secs):.1f} s"
print(line)
if expect == "any":
    pass
elif expect in ("none", "cannot_tell", "unexplained"):
    ok &= d["verdict"] == expect
else:
    ok &= d["verdict"] == "named" and d["named_effect"] == expect
    ok &= d["discrepancy_after"] <= 0.5 * d["discrepancy_before"]
if d["indistinguishable"]:
    print("    indistinguishable:", ", ".join(d["indistinguishable"]))
params = {p["name"]: p for p in d["parameters"]}

def show(i, v):
    lo, hi = i["lower"], i["upper"]
    inside = lo is not None and hi is not None and lo <= v <= hi
    f = lambda x: "?" if x is None else f"{x:.5g}"
    cut = ("<" if i["lower_at_range_end"] else "") + (">" if i["upper_at_range_end"] else "")
    return inside, f"[{f(lo)}, {f(hi)}]{cut} {'in' if inside else 'OUT'}"

if expect == "any":
    truth = [t for t in truth if t.split("=")[0] in params]
for t in truth:
    k, v = t.split("=")
    v = float(v)
    if k not in params:
        ok = False
        print(f"    {k:<16} not fitted")
        continue
    p = params[k]
    joint = p.get("joint_interval") or {"lower": None, "upper": None,
                                        "lower_at_range_end": False, "upper_at_range_end": False}
    inside, jt = show(joint, v)
    ok &= inside and p["interval"]["method"] == "profile"
    _, own = show(p["interval"], v)
    _, wald = show(p["wald_interval"], v)
    print(f"    {k:<16} truth {v:<8g} fit {p['value']:<11.5g} joint {jt:<34} own {own:<34} Wald {wald}")
if expect == "any":
    print("    (reported, not checked)")
    sys.exit(0)
print("    ok" if ok else "    FAILED")
sys.exit(0 if ok else 1)
PY
}

if [[ $coverage == 1 ]]; then
  effect="${COVERAGE_EFFECT:-length_bias:bias.longeron=0.003}"
  truth="${COVERAGE_TRUTH:-bias.longeron=0.003 bias.batten=0}"
  n="${COVERAGE_SPECIMENS:-50}"
  seeds="${COVERAGE_SEEDS:-$(seq -s ' ' 1001 1020)}"
  name="${effect%%:*}"
  echo "coverage study: $effect hidden in $n specimens, seeds $seeds"
  for s in $seeds; do
    secs=$(JOB=${COVERAGE_JOB:-$J} CASE=${COVERAGE_CASE:-as-built} \
      SYNTH_CASE=${COVERAGE_SYNTH_CASE:-${COVERAGE_CASE:-as-built}} run "cov-$s" "$effect" "$s" "$n")
    echo "  seed $s: $(python3 -c "import json; d = json.load(open('$WORK/cov-$s/diagnosis.json')); print(d['verdict'], d['named_effect'])") in $secs s"
  done
  # shellcheck disable=SC2086
  python3 - "$WORK" "$name" "$seeds" $truth <<'PY'
import json, sys
work, name, seeds, *truth = sys.argv[1:]
seeds = seeds.split()

def clopper_pearson(k, n):
    from math import comb
    cdf = lambda p, m: sum(comb(n, i) * p**i * (1 - p)**(n - i) for i in range(m + 1))
    def solve(f):
        a, b = 0.0, 1.0
        for _ in range(60):
            c = 0.5 * (a + b)
            a, b = (c, b) if f(c) else (a, c)
        return 0.5 * (a + b)
    lo = 0.0 if k == 0 else solve(lambda p: 1 - cdf(p, k - 1) < 0.025)
    hi = 1.0 if k == n else solve(lambda p: cdf(p, k) > 0.025)
    return lo, hi

named = 0
counts = {t.split("=")[0]: {"own": 0, "joint": 0, "wald": 0} for t in truth}
all_own = all_joint = 0
for s in seeds:
    d = json.load(open(f"{work}/cov-{s}/diagnosis.json"))
    if d["named_effect"] != name:
        continue
    named += 1
    ps = {p["name"]: p for p in d["parameters"]}
    every = {"own": True, "joint": True}
    for t in truth:
        k, v = t.split("=")
        v = float(v)
        for kind, key in (("own", "interval"), ("joint", "joint_interval"), ("wald", "wald_interval")):
            i = ps[k].get(key) or {}
            inside = i.get("lower") is not None and i.get("upper") is not None and i["lower"] <= v <= i["upper"]
            counts[k][kind] += inside
            if kind in every:
                every[kind] &= inside
    all_own += every["own"]
    all_joint += every["joint"]
m = len(seeds)
print(f"{name} named in {named} of {m} data sets; coverage over all {m} (not named counts as not covered):")
for k, c in counts.items():
    for kind in ("own", "joint", "wald"):
        lo, hi = clopper_pearson(c[kind], m)
        print(f"    {k:<16} {kind:<6} {c[kind]:>3}/{m}  = {c[kind] / m:.2f}  (95 % CI {lo:.2f}–{hi:.2f})")
for kind, c in (("every parameter in its own interval", all_own), ("every parameter in its joint interval", all_joint)):
    lo, hi = clopper_pearson(c, m)
    print(f"    {kind:<40} {c:>3}/{m} = {c / m:.2f}  (95 % CI {lo:.2f}–{hi:.2f})")
PY
  echo "outputs in $WORK"
  exit 0
fi

check none        "none"                                           1  200 none
check thermal     "thermal_gradient:gradient_x=0.002,offset=2"     21 200 thermal_gradient gradient_x=0.002 gradient_y=0 gradient_z=0 offset=2
check bias        "length_bias:bias.longeron=0.003"                22 200 length_bias bias.longeron=0.003 bias.batten=0
check sigma       "length_sigma:sigma.longeron=0.012"              23 200 length_sigma sigma.longeron=0.012 sigma.batten=0.0063
MEMBERS=1 \
check sigma+mm    "length_sigma:sigma.longeron=0.012"              23 200 length_sigma sigma.longeron=0.012 sigma.batten=0.0063
check pretension  "diagonal_pretension:length_error=-0.05"         24 200 diagonal_pretension length_error=-0.05
check gravity     "gravity:g_x=1"                                  11 200 gravity g_x=1 g_y=0 g_z=0
check few         "thermal_gradient:gradient_x=0.0005"             25 12  cannot_tell
# Backlash (section 4.2.3's truss, σ = 0.033 mm, diagonals U[-0.099, 0] mm): a common
# clearance made through the candidate, and the paper's clearances U[0.004, 0.017] mm made
# by the job's own backlash case, diagnosed against the rigid case with the members measured
# one by one and, last, from the node positions alone (reported, not required: there a joint
# effect shortens the longerons much as a length error does). The paper's clearances scatter
# among the joints, which the one-parameter candidate cannot; the truth printed is their
# mean.
P="$REPO/jobs/paper-4.2.3.json"
JOB=$P CASE=rigid-sigma-0.033 MEMBERS=1 \
check backlash    "backlash:clearance=0.0105"                      31 200 backlash clearance=0.0105
JOB=$P CASE=rigid-sigma-0.033 SYNTH_CASE=backlash-sigma-0.033 MEMBERS=1 \
check paper-bl+mm "none"                                           31 200 backlash clearance=0.0105
JOB=$P CASE=rigid-sigma-0.033 SYNTH_CASE=backlash-sigma-0.033 \
check paper-bl    "none"                                           31 200 any clearance=0.0105
echo "outputs in $WORK"
exit $status
