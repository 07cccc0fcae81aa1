#!/usr/bin/env bash
# limit-reference.sh: an independent high-precision reference for the limit r -> 0 of theta_P
# (the cables' compression stiffness ratio), sample by sample, to check the Rust solver's
# one-sided members against. For each case of a job it writes the case's model file
# (`truss model prism ...`, or the job's model file) and its drawn inputs (`mc-shard
# inputs`), then runs scripts/limit_reference.py (python-flint, 96 digits): a continuation
# r = 1e-4 ... 1e-30 with theta_P at each r, whether it settles, and a direct solve at
# r = 1e-30 from u = 0. It does not use the Rust solver's code, only its binaries' model and
# input generation. See the header of scripts/limit_reference.py for the equations, the
# method and the output's fields.
#
# Usage: scripts/limit-reference.sh [--job JOB.json] [--out OUT.jsonl] [--work DIR]
#            [--jobs N] [--range A..B] [-- EXTRA limit_reference.py ARGS]
#   --job    the job (default: a 200-sample Fig. 16 job, backlash with clearances U(4, 17) um,
#            battens and longerons N(0, 6.7 um), diagonals U(-20.1, 0) um, written to WORK)
#   --out    the output JSON Lines (default WORK/<job name>-ref.jsonl), one line per sample,
#            every case of the job in index order
#   --work   where the model files and inputs go (default target/limit-reference)
#   --jobs   processes at a time (default 1; each uses one core)
#   --range  only the global sample indices A..B
# Environment: TRUSS, MC_SHARD (default target/release/truss and target/release/mc-shard
# of this repository; not built here), VENV (default target/ref-venv, made with pip
# install python-flint if missing), NICE (default 19: the solves run under nice -n NICE).
# Time: about 10 to 20 s of one core per sample for the backlash prism (the continuation
# 3-4 s, the direct solve the rest), less for the rigid one.
# Jobs with effects (gravity, thermal) are refused: the reference models neither.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
TRUSS="${TRUSS:-target/release/truss}"
MC_SHARD="${MC_SHARD:-target/release/mc-shard}"
VENV="${VENV:-target/ref-venv}"
NICE="${NICE:-19}"
JOB="" OUT="" WORK="target/limit-reference" JOBS=1 RANGE="" EXTRA=()
while [ $# -gt 0 ]; do
    case "$1" in
        --job) JOB="$2"; shift 2 ;;
        --out) OUT="$2"; shift 2 ;;
        --work) WORK="$2"; shift 2 ;;
        --jobs) JOBS="$2"; shift 2 ;;
        --range) RANGE="$2"; shift 2 ;;
        --) shift; EXTRA=("$@"); break ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "limit-reference.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
for bin in "$TRUSS" "$MC_SHARD"; do
    [ -x "$bin" ] || { echo "limit-reference.sh: $bin is not an executable (set TRUSS / MC_SHARD)" >&2; exit 2; }
done
mkdir -p "$WORK"
if [ -z "$JOB" ]; then
    JOB="$WORK/fig16-job.json"
    cat > "$JOB" <<'EOF'
{"model": {"prism": {"stages": 5, "backlash": true}}, "seed": 20210325, "cases": [{"name": "fig16", "samples": 200, "backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}}, "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}, "diagonal": {"uniform": {"low": -0.0201, "high": 0}}}}]}
EOF
fi
name="$(basename "$JOB" .json)"
OUT="${OUT:-$WORK/$name-ref.jsonl}"

if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c 'import flint' 2>/dev/null; then
    echo "limit-reference.sh: making $VENV (python-flint)" >&2
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install --quiet python-flint
fi
PY="$VENV/bin/python"

# Each case's model file: `truss model prism` with the job's prism values, or the job's file.
plan="$WORK/$name-cases.tsv"
"$PY" - "$JOB" "$WORK" "$TRUSS" > "$plan" <<'PY'
import json, os, subprocess, sys
job_path, work, truss = sys.argv[1:4]
job = json.load(open(job_path))
flags = {"stages": "--stages", "side": "--side", "height": "--height",
         "batten_area": "--batten-area", "batten_modulus": "--batten-modulus",
         "longeron_area": "--longeron-area", "longeron_modulus": "--longeron-modulus",
         "diagonal_area": "--diagonal-area", "diagonal_modulus": "--diagonal-modulus",
         "compression_ratio": "--compression-ratio"}
def model_file(model, tag):
    if isinstance(model, str):
        model = {"file": model}
    if "file" in model:
        return os.path.join(os.path.dirname(os.path.abspath(job_path)), model["file"])
    if set(model) != {"prism"}:
        sys.exit(f"limit-reference.sh: unknown model form {model}")
    args = [truss, "model", "prism"]
    for key, value in model["prism"].items():
        if key in flags:
            args += [flags[key], repr(value) if isinstance(value, float) else str(value)]
        elif key == "diagonal_length":
            args += ["--exact-diagonals"] if value == "exact" else ["--diagonal-length", str(value)]
        elif key == "backlash":
            if value is True:
                args += ["--backlash"]
            elif isinstance(value, dict):
                args += ["--backlash"]
                sub = {"clearance": "--clearance", "tension_factor": "--joint-tension-factor",
                       "compression_ratio": "--joint-compression-ratio"}
                for k, v in value.items():
                    if k not in sub:
                        sys.exit(f"limit-reference.sh: unknown backlash field {k}")
                    args += [sub[k], str(v)]
        else:
            sys.exit(f"limit-reference.sh: unknown prism field {key}")
    path = os.path.join(work, f"model-{tag}.json")
    with open(path, "w") as fh:
        subprocess.run(args, stdout=fh, check=True)
    return path
for case in job["cases"]:
    if case.get("effects"):
        sys.exit(f"limit-reference.sh: case {case['name']!r} has effects, which the reference does not model")
    model = case.get("model", job["model"])
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in case["name"])
    print(f"{case['name']}\t{safe}\t{model_file(model, safe)}")
PY

: > "$OUT.tmp"
while IFS=$'\t' read -r case safe model; do
    inputs="$WORK/$name-$safe-inputs.csv"
    range_args=()
    [ -n "$RANGE" ] && range_args=(--range "$RANGE")
    "$MC_SHARD" inputs --job "$JOB" --case "$case" ${range_args[@]+"${range_args[@]}"} --out "$inputs" >&2
    echo "limit-reference.sh: case $case: model $model, inputs $inputs" >&2
    nice -n "$NICE" "$PY" scripts/limit_reference.py --model "$model" --inputs "$inputs" \
        --out "$WORK/$name-$safe-ref.jsonl" --jobs "$JOBS" ${EXTRA[@]+"${EXTRA[@]}"}
    cat "$WORK/$name-$safe-ref.jsonl" >> "$OUT.tmp"
done < "$plan"
mv "$OUT.tmp" "$OUT"
"$PY" - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
settled = sum(r["settled"] for r in rows)
agree = sum(r.get("direct", {}).get("agrees", False) for r in rows)
print(f"limit-reference.sh: {len(rows)} samples, {settled} settled, direct solve agrees in {agree}; {sys.argv[1]}")
PY
