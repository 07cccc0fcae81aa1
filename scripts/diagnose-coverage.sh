#!/usr/bin/env bash
# diagnose-coverage.sh: how often `truss diagnose`'s 95 % intervals cover the truth, with the
# release build. Too slow for CI (about 12 minutes by default on 2 shared cores: 3.5 s a run of
# the bias case, 12 s of thermal, 1.6 s of pretension): not part of scripts/test.sh.
#
# Data: made by `truss synth-measured` from jobs/diagnose-baseline.json (the paper's 5-stage
# prism, σ = 6.3 µm on battens and longerons, section 3.1), case as-built, SPECIMENS
# specimens (default 100), 1 µm instrument noise, one data set per seed; the seeds 1001–1040
# were fixed here before any result was seen, independent of diagnose-check.sh's (101–520).
#
# The cases, one effect hidden alone each (the three whose key intervals missed the truth in
# diagnose-check.sh's matrix), and the parameters whose interval is checked against the
# value hidden (the candidate parametrises the effect exactly as synth-measured applies it:
# the same candidate code):
# - bias:       length_bias:bias.longeron=0.003         bias.longeron 0.003 mm, bias.batten 0 mm
# - thermal:    thermal_gradient:gradient_x=0.002,offset=2
#                                                        gradient_x 0.002 K/mm, offset 2 K
#               (gradient_y and gradient_z, truth 0 K/mm, are reported, not checked)
# - pretension: diagonal_pretension:length_error=-0.05  length_error −0.05 mm
#
# The interval checked is the one the report gives as the answer: diagnosis.json's
# final_fit[].parameters[].interval (for a model of one effect, its step's profile
# interval). Its Wald interval (wald_interval) is reported beside it, not checked. A run
# in which the hidden effect is not named, in which the parameter or an end of its interval
# is missing, or in which synth-measured or diagnose fails, counts as not covering, and is
# listed as such.
#
# Candidates (CANDIDATES): `true` (the default) fits the hidden effect's candidate only
# (`--candidates NAME`): it tests the interval method given the right model, 1.5–12 s a
# run; `all` fits every candidate (the full stepwise diagnosis, 20–60 s a run on 2 shared
# cores: about an hour for the default 3 × 40 runs), where an effect not named, or another
# named in its place, counts as not covering; or a comma-separated list passed to
# --candidates as is. Where the full diagnosis names the hidden effect alone, its final fit
# is that effect's step fit, the same fit and interval as `true` gives (seed 1001 of all
# three cases: the same intervals to the last digit).
#
# Simulation seed (SIM_SEED): `vary` (the default) diagnoses each data set with a copy of
# the job whose seed is 20210325 + the data seed (written to WORKDIR/job-SEED.json): each
# run is then an independent repetition of the whole experiment, new specimens and a new
# simulation, which is what a 95 % interval's coverage is a claim about (the intervals'
# inflation c = 1 + n/N treats the simulation's Monte-Carlo error in μ and Σ as random)
# and what makes the runs independent, as the binomial interval assumes. `job` diagnoses
# every data set with the job's own seed: every run then shares one realisation of that
# error, which shifts every estimate alike, so the coverage measured is conditional on it
# and the runs are not independent trials. Measured (100 specimens, N = 2000, 40 seeds,
# true candidate only): with `job`, bias.longeron and length_error cover 35/40 with mean
# z +0.41 and +0.37 (this job's seed sits about 0.5 standard errors off for these
# parameters: 24 other job seeds on one data set spread its estimate by 0.30 SE, as
# c = 1 + n/N allows); with `vary` every key parameter covers 38–39/40, and
# length_error 119/120 over 120 seeds. A default chosen after that run (it was `job`
# first): the check was not loosened, its trials were made independent. `job` stays
# available for the conditional question (one user's seed; --samples 10000 brings it
# to 36–38/40 at 3.7 times the time).
#
# The rule, fixed before the results were seen: a parameter PASSES if its coverage point
# estimate, covered / runs, is at least 0.90 (the issue's target; at 40 runs, 36 covered);
# otherwise it FAILS. Each line also gives the 95 % Clopper–Pearson interval of the
# coverage. With intervals of exactly 95 % coverage, a parameter fails this rule by chance
# with probability P(Bin(40, 0.95) ≤ 35) = 0.048; at 85 % coverage it passes with
# probability 0.26 (more seeds sharpen both).
# Per parameter the line gives: covered / runs, the coverage and its interval, the median
# interval width, the mean of fitted − truth ± its standard error over the runs, the same
# in units of the interval's own standard error s = width / 3.92 (z = (fit − truth)/s: its
# mean is the estimate's bias, its standard deviation ≈ 1 if the width is right), the
# Wald interval's coverage, the case's wall time, and the runs not covering (seed: why).
#
# Usage (from the repo root or anywhere): scripts/diagnose-coverage.sh [WORKDIR]
#   SEEDS="1001 … 1040", SPECIMENS=N (default 100), CASES="bias thermal pretension" (a
#   subset), CANDIDATES=true|all|LIST (above), SAMPLES=N (diagnose's --samples; default its
#   own), SIM_SEED=vary|job (above), TRUSS=PATH (a built `truss` binary to check, instead
#   of building the release one).
#   Every run's data (CASE-SEED.csv), its diagnosis (CASE-SEED/diagnosis.json) and stderr
#   stay in WORKDIR (default a mktemp dir); runs.tsv there has one line per run and
#   parameter. Exit status 0 if every parameter PASSED, 1 if any FAILED. Needs python3.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/truss-binary.sh" "$@"
J="$REPO/jobs/diagnose-baseline.json"
N="${SPECIMENS:-100}"
SEEDS="${SEEDS:-$(seq -s ' ' 1001 1040)}"
CASES="${CASES:-bias thermal pretension}"
CANDIDATES="${CANDIDATES:-true}"
SIM_SEED="${SIM_SEED:-vary}"
[[ $SIM_SEED == job || $SIM_SEED == vary ]] || { echo "SIM_SEED is job or vary" >&2; exit 4; }
SAMPLES="${SAMPLES:-}"
B="as-built"

# case NAME -> "EFFECT CANDIDATE CHECKED=TRUTH … [+REPORTED=TRUTH …]"
case_spec() {
  case $1 in
    bias) echo "length_bias:bias.longeron=0.003 length_bias bias.longeron=0.003 bias.batten=0" ;;
    thermal) echo "thermal_gradient:gradient_x=0.002,offset=2 thermal_gradient gradient_x=0.002 offset=2 +gradient_y=0 +gradient_z=0" ;;
    pretension) echo "diagonal_pretension:length_error=-0.05 diagonal_pretension length_error=-0.05" ;;
    *) echo "unknown case $1 (bias, thermal, pretension)" >&2; return 1 ;;
  esac
}

: > "$WORK/runs.tsv"
echo "CANDIDATES=$CANDIDATES SIM_SEED=$SIM_SEED SPECIMENS=$N SAMPLES=${SAMPLES:-default} seeds: $SEEDS" | tee "$WORK/settings.txt"
for c in $CASES; do
  spec=$(case_spec "$c") || exit 4
  read -r effect cand params <<< "$spec"
  case $CANDIDATES in
    true) copt=(--candidates "$cand") ;;
    all) copt=() ;;
    *) copt=(--candidates "$CANDIDATES") ;;
  esac
  start=$(date +%s.%N)
  for s in $SEEDS; do
    name="$c-$s"
    status=ok
    job="$J"
    if [[ $SIM_SEED == vary ]]; then
      job="$WORK/job-$s.json"
      python3 -c 'import json, sys
j = json.load(open(sys.argv[1]))
j["seed"] = 20210325 + int(sys.argv[2])
json.dump(j, open(sys.argv[3], "w"), indent=1)' "$J" "$s" "$job" || exit 4
    fi
    if ! "$T" synth-measured --job "$J" --case $B --specimens "$N" --seed "$s" --effect "$effect" \
        --measurement-sigma 0.001 > "$WORK/$name.csv" 2> "$WORK/$name.synth.stderr" \
      || ! "$T" diagnose --job "$job" --case $B --measured "$WORK/$name.csv" --measurement-sigma 0.001 \
        "${copt[@]}" "${SAMPLES_OPTION[@]}" --out "$WORK/$name" --quiet --no-plots > /dev/null 2> "$WORK/$name.stderr"; then
      status=failed
    fi
    # One line per parameter: case seed cand param truth checked status value lower upper
    # wald_lower wald_upper method (a missing value: "nan").
    python3 - "$WORK/$name/diagnosis.json" "$c" "$s" "$cand" "$status" $params >> "$WORK/runs.tsv" <<'PY'
import json, sys
path, case, seed, cand, status, *params = sys.argv[1:]
d = None
if status == "ok":
    try:
        d = json.load(open(path))
    except (OSError, ValueError):
        status = "no_report"
found = {}
if d is not None:
    if cand not in d["named_effects"]:
        status = "not_named:" + (",".join(d["named_effects"]) or "none")
    else:
        for e in d["final_fit"]:
            if e["name"] == cand:
                for p in e["parameters"]:
                    found[p["name"]] = p
def num(x):
    return "nan" if x is None else repr(float(x))
for t in params:
    checked = not t.startswith("+")
    k, v = t.lstrip("+").split("=")
    p = found.get(k)
    st = status
    if st == "ok" and p is None:
        st = "parameter_missing"
    i = (p or {}).get("interval") or {}
    w = (p or {}).get("wald_interval") or {}
    print("\t".join([case, seed, cand, k, v, "1" if checked else "0", st,
                     num((p or {}).get("value")), num(i.get("lower")), num(i.get("upper")),
                     num(w.get("lower")), num(w.get("upper")), i.get("method") or "-"]))
PY
  done
  end=$(date +%s.%N)
  echo -e "$c\t$(python3 -c "print(f'{$end - $start:.0f}')")" >> "$WORK/walltime.tsv"
done

python3 - "$WORK/runs.tsv" "$WORK/walltime.tsv" <<'PY'
import math, statistics, sys
from collections import OrderedDict
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
wall = dict(l.split() for l in open(sys.argv[2]) if l.strip())

def binom_cdf(k, n, p):
    if k < 0:
        return 0.0
    if k >= n:
        return 1.0
    return sum(math.comb(n, i) * p**i * (1 - p)**(n - i) for i in range(k + 1))

def bisect(f, lo=0.0, hi=1.0):
    # f increasing in p, root in [lo, hi]
    for _ in range(200):
        m = (lo + hi) / 2
        if f(m) < 0:
            lo = m
        else:
            hi = m
    return (lo + hi) / 2

def clopper_pearson(x, n, a=0.05):
    # lower: P(X ≥ x | p) = a/2; upper: P(X ≤ x | p) = a/2 (both monotone in p)
    lo = 0.0 if x == 0 else bisect(lambda p: (1 - binom_cdf(x - 1, n, p)) - a / 2)
    hi = 1.0 if x == n else bisect(lambda p: a / 2 - binom_cdf(x, n, p))
    return lo, hi

groups = OrderedDict()
for r in rows:
    groups.setdefault((r[0], r[3]), []).append(r)
failed = []
print()
print(f"{'case':<11} {'parameter':<14} {'truth':>7} {'covered':>7} {'coverage':>8} {'95 % CP':>14} "
      f"{'med width':>9} {'mean fit − truth':>18} {'z mean':>6} {'z sd':>5} {'Wald':>5} {'wall':>6}")
for (case, k), rs in groups.items():
    truth = float(rs[0][4])
    checked = rs[0][5] == "1"
    n = len(rs)
    cov = 0
    wcov = 0
    widths, errs, zs, misses = [], [], [], []
    for r in rs:
        seed, st = r[1], r[6]
        val, lo, hi, wlo, whi = (float(x) for x in r[7:12])
        if st != "ok":
            misses.append(f"{seed}: {st}")
            continue
        if math.isnan(lo) or math.isnan(hi):
            misses.append(f"{seed}: interval end missing")
        elif lo <= truth <= hi:
            cov += 1
        else:
            misses.append(f"{seed}: [{lo:.5g}, {hi:.5g}] {'above' if lo > truth else 'below'}")
        if not (math.isnan(lo) or math.isnan(hi)):
            widths.append(hi - lo)
            if not math.isnan(val) and hi > lo:
                zs.append((val - truth) / ((hi - lo) / 3.92))
        if not (math.isnan(wlo) or math.isnan(whi)) and wlo <= truth <= whi:
            wcov += 1
        if not math.isnan(val):
            errs.append(val - truth)
    lo, hi = clopper_pearson(cov, n)
    nan = float("nan")
    med = statistics.median(widths) if widths else nan
    me = statistics.mean(errs) if errs else nan
    se = statistics.stdev(errs) / math.sqrt(len(errs)) if len(errs) > 1 else nan
    zm = statistics.mean(zs) if zs else nan
    zsd = statistics.stdev(zs) if len(zs) > 1 else nan
    print(f"{case:<11} {k:<14} {truth:>7g} {cov:>3}/{n:<3} {cov / n:>8.3f} [{lo:.3f}, {hi:.3f}] "
          f"{med:>9.3g} {me:>+9.2g} ± {se:<6.2g} {zm:>+6.2f} {zsd:>5.2f} {wcov / n:>5.3f} {wall.get(case, '?'):>4} s")
    if misses:
        print("    not covering: " + "; ".join(misses))
    if checked:
        ok = cov / n >= 0.90
        print("    PASSED" if ok else "    FAILED")
        if not ok:
            failed.append(f"{case}/{k}")
    else:
        print("    (reported, not checked)")
print()
print(f"{len(failed)} failed{': ' + ' '.join(failed) if failed else ''}; outputs in {sys.argv[1].rsplit('/', 1)[0]}")
sys.exit(1 if failed else 0)
PY
