#!/usr/bin/env bash
# bench-instructions.sh: machine-independent cost of a sample, in instructions, counted by
# valgrind's cachegrind (--cache-sim=no) around a whole `mc-shard run` on one thread:
# (instructions of N + 200 samples − instructions of 200 samples) / N, so that start-up,
# the model's compilation and writing the header cancel. Unlike times on a shared machine,
# the counts repeat exactly. Cases (each a job of its own, seed 20210325):
#   rigid     the paper's 5-stage prism, battens and longerons N(0, 0.0063²) mm (§3.1)
#   backlash  Fig. 16 at σ = 0.0067 mm: 5 stages with pin joints, diagonals U[−3σ, 0],
#             clearances U[0.004, 0.017] mm (§4.2.3)
#   tall      the 300-stage prism at σ = 0.0063 mm
#   tall-backlash  the 300-stage prism with pin joints, as backlash
# Prints one line per case: instructions per sample, and the mean Newton iterations read
# from the shard.
#
# Usage: scripts/bench-instructions.sh [CASE ...]    (default: rigid backlash tall)
#        MC_SHARD=path/to/mc-shard scripts/bench-instructions.sh   (another build, to compare)
#        TRUSS_LANES=off scripts/bench-instructions.sh   (one sample at a time instead of four
#        side by side in lanes: the same bytes; see the README's Speed section)
# Needs valgrind (Debian package valgrind).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
command -v valgrind >/dev/null || { echo "bench-instructions: needs valgrind (apt-get install valgrind)" >&2; exit 1; }
if [ -z "${MC_SHARD:-}" ]; then
    cargo build --release --quiet -p mc-shard
    MC_SHARD="$REPO/target/release/mc-shard"
fi
WORK="$(mktemp -d /tmp/truss-mc-instructions.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(rigid backlash tall)

# job NAME SAMPLES -> writes $WORK/NAME-SAMPLES.json
job() {
    local errors model
    case "$1" in
        rigid) model='{"prism": {"stages": 5}}'
               errors='"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}' ;;
        backlash) model='{"prism": {"stages": 5, "backlash": true}}'
               errors='"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}, "diagonal": {"uniform": {"low": -0.0201, "high": 0}}' ;;
        tall) model='{"prism": {"stages": 300}}'
               errors='"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}' ;;
        tall-backlash) model='{"prism": {"stages": 300, "backlash": true}}'
               errors='"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}, "diagonal": {"uniform": {"low": -0.0189, "high": 0}}' ;;
        *) echo "bench-instructions: unknown case $1" >&2; exit 2 ;;
    esac
    local clearance=''
    case "$1" in *backlash) clearance='"backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}},' ;; esac
    cat > "$WORK/$1-$2.json" <<JOB
{"model": $model, "seed": 20210325, "cases": [
  {"name": "$1", "samples": $2, $clearance "length_errors": {$errors}}]}
JOB
}

# instructions NAME SAMPLES -> total instructions of one run
instructions() {
    rm -rf "$WORK/out"
    if ! valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file="$WORK/cg.out" \
        "$MC_SHARD" run --job "$WORK/$1-$2.json" --out "$WORK/out" --threads 1 --quiet \
        >/dev/null 2>"$WORK/valgrind.log"; then
        # Most often an instruction valgrind cannot decode (valgrind 3.19: the VEX `vmovq
        # xmm, xmm` store form, which LLVM may emit in a kernel after an unrelated change).
        echo "bench-instructions: $1 ($2 samples) failed under valgrind:" >&2
        grep -E "unhandled instruction|Illegal opcode|Process terminating|at 0x" "$WORK/valgrind.log" | head -6 >&2
        return 1
    fi
    awk '/^summary:/ {print $2}' "$WORK/cg.out"
}

for name in "${cases[@]}"; do
    case "$name" in tall*) n=200 ;; *) n=2000 ;; esac
    base=200
    job "$name" "$base"
    job "$name" "$((n + base))"
    small=$(instructions "$name" "$base") || exit 1
    large=$(instructions "$name" "$((n + base))") || exit 1
    iterations=$(python3 -c '
import json, sys, glob
rows = [json.loads(l) for f in glob.glob(sys.argv[1] + "/*.jsonl") for l in open(f)]
rows = [r for r in rows if r.get("record") == "sample"]
failed = sum(r["status"] != "converged" for r in rows)
mean = sum(r["iterations"] for r in rows) / len(rows)
print("%.2f iterations per sample, %d of %d failed" % (mean, failed, len(rows)))
' "$WORK/out")
    printf '%-14s %10.0f instructions per sample (%d samples); %s\n' \
        "$name" "$(echo "($large - $small) / $n" | bc -l)" "$n" "$iterations"
done
