#!/usr/bin/env bash
# limit-check.sh: are the defaults the limit r → 0 of the cables' compression ratio? Runs
# every study of jobs/paper-*.json twice, at the defaults (slack cables carry nothing,
# solved as the limit) and with every prism whose cables have no explicit ratio given
# r = 1e-10, merges both, and compares every figure REPRODUCTION.md reads at the defaults:
# each case's percentiles of θ_P and its Rayleigh scale σ_t, and each sweep's slope and
# allowable σ. A figure agrees when the two values are within 0.3 % of each other or within
# a fifth of the default's 95 % interval, whichever is larger. Prints every case's worst
# figure and exits 1 if any disagrees. Cases whose cables have an explicit ratio are the
# same in both runs and are skipped. At 1e-10 (near the solver's force resolution) some
# samples fail (thousands of the tall rigid prisms of §3.4), and the samples that fail are
# not a random subset: so each case's percentiles and σ_t are compared over the samples
# that converged in both runs (paired, read from the shards; the default's interval still
# sets the allowance), and the number left out is printed. The sweeps' slopes and
# allowable σ are the merged reports', with every sample each run has.
#
# Usage: scripts/limit-check.sh [RUNS_DIR]     (default runs/limit-check; about 15 minutes
#        on 2 cores; reuses finished shards when run again)
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
RUNS="${1:-runs/limit-check}"
cargo build --release --quiet -p truss-mc -p mc-merge
mkdir -p "$RUNS/jobs"
for study in 3.1 3.3 3.4 4.2.3; do
    python3 - "jobs/paper-$study.json" "$RUNS/jobs/paper-$study.json" <<'PY'
import json, sys
job = json.load(open(sys.argv[1]))
def limit(model):
    if isinstance(model, dict) and "prism" in model and "compression_ratio" not in model["prism"]:
        model["prism"]["compression_ratio"] = 1e-10
limit(job["model"])
for case in job["cases"]:
    if "model" in case:
        limit(case["model"])
    else:
        case["model"] = json.loads(json.dumps(job["model"]))
json.dump(job, open(sys.argv[2], "w"), indent=1)
PY
    for kind in default limit; do
        job="jobs/paper-$study.json"
        [ "$kind" = limit ] && job="$RUNS/jobs/paper-$study.json"
        out="$RUNS/$kind/paper-$study"
        echo "limit-check: study $study, $kind" >&2
        target/release/truss-mc run-all --job "$job" --out "$out" --no-merge --quiet
        target/release/mc-merge "$out" --out "$out/report" --allow-failed --quiet
    done
done
python3 - "$RUNS" <<'PY'
import glob, json, math, sys
runs = sys.argv[1]
bad = 0
def samples(directory):
    """{(case, index): (theta_p, tan_theta_x, tan_theta_y)} of the converged samples."""
    out = {}
    for path in sorted(glob.glob(f"{directory}/shard-*.jsonl")):
        for line in open(path):
            r = json.loads(line)
            if r.get("record") == "sample" and r["status"] == "converged":
                out[(r["case"], r["index"])] = (r["theta_p"], r["tan_theta_x"], r["tan_theta_y"])
    return out
def quantile(sorted_values, p):
    # Hyndman & Fan definition 1, as the merge: x_(k), k the smallest rank with k >= p*n.
    n = len(sorted_values)
    return sorted_values[max(math.ceil(p * n), 1) - 1]
def paired_figures(report, values):
    """The case figures of `report`, recomputed from `values` (one run's samples)."""
    by_case = {}
    for (case, _), v in values.items():
        by_case.setdefault(case, []).append(v)
    out = {}
    for c in report["cases"]:
        rows = by_case.get(c["name"])
        if not rows:
            continue
        thetas = sorted(r[0] for r in rows)
        for p in c["percentiles"]:
            out[(c["name"], f"θ_P{p['percentile']:g}")] = quantile(thetas, p["percentile"] / 100)
        squares = sum(r[1] ** 2 + r[2] ** 2 for r in rows)
        out[(c["name"], "σ_t")] = math.sqrt(squares / (2 * len(rows)))
    return out
def figures(report):
    out = {}
    for c in report["cases"]:
        for p in c["percentiles"]:
            out[(c["name"], f"θ_P{p['percentile']:g}")] = (p["value"], p.get("bca") or p.get("percentile_interval"))
        st = c["rayleigh"]["sigma_t"]
        out[(c["name"], "σ_t")] = (st["value"], st)
    for kind in ("sigma_series", "stages_series"):
        for s in report["sweep"].get(kind, []):
            for fit in ("through_origin", "with_intercept"):
                f = s.get("fit", {}).get(fit) or s.get(fit)
                if isinstance(f, dict) and isinstance(f.get("slope"), dict):
                    out[(s["name"], f"slope {fit}")] = (f["slope"]["value"], f["slope"])
            a = s.get("allowable_sigma", {}).get("through_origin")
            if isinstance(a, dict):
                out[(s["name"], "allowable σ")] = (a["value"], a)
    return out
for study in ["3.1", "3.3", "3.4", "4.2.3"]:
    d = json.load(open(f"{runs}/default/paper-{study}/report/report.json"))
    l = json.load(open(f"{runs}/limit/paper-{study}/report/report.json"))
    fd, fl = figures(d), figures(l)
    failed = sum(c["failed"]["count"] for c in l["cases"])
    sd = samples(f"{runs}/default/paper-{study}")
    sl = samples(f"{runs}/limit/paper-{study}")
    both = {k: v for k, v in sd.items() if k in sl}
    pd = paired_figures(d, both)
    pl = paired_figures(l, {k: sl[k] for k in both})
    print(f"study {study}: {failed} failed samples at 1e-10; case figures over the "
          f"{len(both)} samples converged in both runs ({len(sd) - len(both)} left out)")
    worst = {}
    for key, (vd, interval) in fd.items():
        if key not in fl or vd is None or fl[key][0] is None:
            continue
        if "ratio" in key[0]:
            continue  # explicit ratios: the same case in both runs
        vl = fl[key][0]
        if key in pd and key in pl:
            vd, vl = pd[key], pl[key]
        half = 0.0
        if isinstance(interval, dict) and interval.get("lower") is not None and interval.get("upper") is not None:
            half = (interval["upper"] - interval["lower"]) / 2
        allowed = max(0.003 * abs(vd), 0.2 * half)
        off = abs(vd - vl) / allowed if allowed > 0 else (0.0 if vd == vl else float("inf"))
        if key[0] not in worst or off > worst[key[0]][0]:
            worst[key[0]] = (off, key[1], vd, vl)
        bad += off > 1
    for name, (off, what, vd, vl) in sorted(worst.items()):
        mark = "ok " if off <= 1 else "OFF"
        print(f"  {mark} {name}: worst {what} {vd:.4e} vs {vl:.4e} ({off:.2f} of the allowance)")
print("limit-check:", "every figure agrees" if bad == 0 else f"{bad} figures disagree")
sys.exit(1 if bad else 0)
PY
