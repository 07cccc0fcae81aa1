#!/usr/bin/env bash
# submit.sh: submit a truss-mc job to Slurm as a job array of shards plus a
# merge job that runs only after every shard task succeeded.
#
# Usage: scripts/slurm/submit.sh JOB.json --shards K --out DIR [--only-missing] [-- SBATCH_OPTION...]
#
#   JOB.json        the Monte Carlo job description
#   --shards K      number of shards (array indices 0..K-1)
#   --out DIR       output directory (created); task logs go to DIR/logs/,
#                   the merged report to DIR/report
#   --only-missing  submit only the shards that `mc-shard status --missing`
#                   reports as not complete (after a failure or a stop); when
#                   none is missing, submit only the merge
#   -- ...          extra sbatch options, passed to both the array and the
#                   merge (e.g. -- --partition=big --time=2:00:00); they come
#                   last so they override ours, but do not pass --array,
#                   --dependency or --output
#
# Each array task runs
#   $MC_SHARD run --job JOB --out DIR --shard ${SLURM_ARRAY_TASK_ID}/K
# (the shard is passed explicitly because for a partial array such as
# --array=2,5 Slurm sets SLURM_ARRAY_TASK_COUNT=2, not K), with --requeue so
# a pre-empted or node-failed task is run again (mc-shard resumes it). The
# merge job first audits 32 seeded random lines (`$MC_SHARD audit --job JOB DIR
# --samples 32`: re-solved and compared byte for byte; a mismatch fails the job
# with exit 6 and DIR/audit.json), then runs `$MC_MERGE DIR --out DIR/report` with
# --dependency=afterok:<array job> --kill-on-invalid-dep=yes, so it is
# cancelled, not left pending forever, when a task fails.
#
# Output (stdout, machine-readable; messages go to stderr):
#   array_job=<id>        empty when --only-missing found nothing to run
#   array_indices=<list>  the array indices submitted (empty likewise)
#   merge_job=<id>
#   jobs=<id>,<id>        the ids to give to wait-jobs.sh (comma-separated)
# Every line is also valid shell: eval "$(submit.sh ...)" sets the variables.
#
# It refuses to submit while jobs it submitted earlier for the same DIR are
# still queued or running (two tasks writing one shard at once would race):
# wait for them (wait-jobs.sh) or scancel them first.
#
# Environment:
#   MC_SHARD  path of mc-shard (default <repo>/target/release/mc-shard)
#   MC_MERGE  path of mc-merge (default <repo>/target/release/mc-merge)
#   SLURM_CONF  which cluster; defaults to the local cluster's conf when
#             start-local-cluster.sh has written one (see _common.sh)
#
# Exit status: 0 submitted; 2 bad arguments/environment; 1 sbatch or
# mc-shard status failed.
set -euo pipefail

# shellcheck source-path=SCRIPTDIR source=_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; }

MC_SHARD="${MC_SHARD:-$REPO/target/release/mc-shard}"
MC_MERGE="${MC_MERGE:-$REPO/target/release/mc-merge}"

JOB="" SHARDS="" OUT="" ONLY_MISSING=0
EXTRA=()
while [[ $# -gt 0 ]]; do
    case "$1" in
        --shards) [[ $# -ge 2 ]] || die "--shards needs a value"; SHARDS="$2"; shift 2 ;;
        --shards=*) SHARDS="${1#*=}"; shift ;;
        --out) [[ $# -ge 2 ]] || die "--out needs a value"; OUT="$2"; shift 2 ;;
        --out=*) OUT="${1#*=}"; shift ;;
        --only-missing) ONLY_MISSING=1; shift ;;
        -h|--help) usage; exit 0 ;;
        --) shift; EXTRA=("$@"); break ;;
        -*) die "unknown option: $1 (extra sbatch options go after --; see --help)" ;;
        *) [[ -z "$JOB" ]] || die "more than one job file given: '$JOB' and '$1'"
           JOB="$1"; shift ;;
    esac
done

[[ -n "$JOB" ]] || die "no job file given (usage: submit.sh JOB.json --shards K --out DIR [--only-missing] [-- sbatch options])"
[[ -f "$JOB" && -r "$JOB" ]] || die "job file '$JOB' does not exist or is not readable"
[[ -n "$SHARDS" ]] || die "--shards K is required"
[[ "$SHARDS" =~ ^[1-9][0-9]*$ ]] || die "--shards must be a positive integer, got '$SHARDS'"
[[ -n "$OUT" ]] || die "--out DIR is required"
for extra in "${EXTRA[@]}"; do
    case "$extra" in
        -a|--array|--array=*|-d|--dependency|--dependency=*|-o|--output|--output=*|--parsable)
            die "do not pass '$extra' through: submit.sh sets it" ;;
    esac
done
for var in MC_SHARD MC_MERGE; do
    path="${!var}"
    [[ -f "$path" && -x "$path" ]] \
        || die "$var: '$path' is not an executable file (build with 'cargo build --release' or set $var)"
    [[ "$path" == /* ]] || printf -v "$var" '%s/%s' "$(cd "$(dirname "$path")" && pwd -P)" "${path##*/}"
done
command -v sbatch > /dev/null || die "sbatch not found (install Slurm, e.g. scripts/slurm/start-local-cluster.sh)"

# The logs directory is created under --out: never a planted link (Slurm would write the
# task logs wherever it points).
[[ -L "$OUT/logs" ]] && die "'$OUT/logs' is a symbolic link; task logs are never written through a link (remove it)" 5
mkdir -p "$OUT/logs" || die "cannot create '$OUT/logs'"
OUT="$(cd "$OUT" && pwd -P)"
JOB="$(cd "$(dirname "$JOB")" && pwd -P)/${JOB##*/}"
LAST=$(( SHARDS - 1 ))

# ---------------------------------------- nothing of ours still running?
# Our jobs carry the output directory in their comment.
COMMENT="truss-mc:$OUT"
queued="$(squeue -h --me -o '%A|%k')" \
    || die "squeue failed: is the cluster up? (scripts/slurm/start-local-cluster.sh)" 1
busy="$(awk -F'|' -v c="$COMMENT" 'substr($0, index($0, "|") + 1) == c { print $1 }' <<< "$queued" \
        | sort -un | paste -sd, -)"
[[ -z "$busy" ]] || die "jobs $busy for $OUT are still queued or running; wait for them (scripts/slurm/wait-jobs.sh $busy) or scancel them, then submit again" 1

# ------------------------------------------------------- which indices
if [[ $ONLY_MISSING -eq 1 ]]; then
    INDICES="$("$MC_SHARD" status --job "$JOB" --out "$OUT" --shards "$SHARDS" --missing)" \
        || die "'$MC_SHARD status ... --missing' failed" 1
    INDICES="${INDICES//[[:space:]]/}"
    if [[ -n "$INDICES" ]]; then
        [[ "$INDICES" =~ ^[0-9]+(-[0-9]+)?(,[0-9]+(-[0-9]+)?)*$ ]] \
            || die "mc-shard status printed '$INDICES', not an index list like 2,5 or 0-3" 1
        IFS=,- read -r -a nums <<< "$INDICES"
        for n in "${nums[@]}"; do
            (( 10#$n <= LAST )) || die "mc-shard status reported index $n but --shards is $SHARDS" 1
        done
    fi
    log "missing shards: ${INDICES:-none}"
else
    INDICES="0-$LAST"
fi

# --------------------------------------------------------------- submit
q() { printf '%q' "$1"; }
parse_id() {  # sbatch --parsable prints "jobid" or "jobid;cluster"
    local id="${1%%;*}"
    [[ "$id" =~ ^[0-9]+$ ]] || return 1
    printf '%s\n' "$id"
}

ARRAY_JOB=""
if [[ -n "$INDICES" ]]; then
    task_script="#!/bin/bash
# truss-mc shard task, generated by scripts/slurm/submit.sh
set -eu
exec $(q "$MC_SHARD") run --job $(q "$JOB") --out $(q "$OUT") --shard \"\${SLURM_ARRAY_TASK_ID}/$SHARDS\"
"
    out="$(sbatch --parsable --array="$INDICES" --requeue --job-name=truss-mc-shard --comment="$COMMENT" \
               --output="$OUT/logs/shard-%A_%a.out" "${EXTRA[@]}" <<< "$task_script")" \
        || die "sbatch of the shard array failed" 1
    ARRAY_JOB="$(parse_id "$out")" || die "unexpected sbatch output: '$out'" 1
    log "submitted shard array job $ARRAY_JOB (indices $INDICES of 0-$LAST)"
fi
printf 'array_job=%s\n' "$ARRAY_JOB"
printf 'array_indices=%s\n' "$INDICES"

merge_script="#!/bin/bash
# truss-mc merge, generated by scripts/slurm/submit.sh
set -eu
$(q "$MC_SHARD") audit --job $(q "$JOB") $(q "$OUT") --samples 32
exec $(q "$MC_MERGE") $(q "$OUT") --out $(q "$OUT/report")
"
dep=()
[[ -n "$ARRAY_JOB" ]] && dep=(--dependency="afterok:$ARRAY_JOB")
out="$(sbatch --parsable "${dep[@]}" --kill-on-invalid-dep=yes --job-name=truss-mc-merge --comment="$COMMENT" \
           --output="$OUT/logs/merge-%j.out" "${EXTRA[@]}" <<< "$merge_script")" \
    || die "sbatch of the merge job failed${ARRAY_JOB:+ (shard array $ARRAY_JOB was submitted and keeps running)}" 1
MERGE_JOB="$(parse_id "$out")" || die "unexpected sbatch output: '$out'" 1
log "submitted merge job $MERGE_JOB${ARRAY_JOB:+ (runs after array $ARRAY_JOB succeeds)}; logs in $OUT/logs/"
printf 'merge_job=%s\n' "$MERGE_JOB"
printf 'jobs=%s\n' "${ARRAY_JOB:+$ARRAY_JOB,}$MERGE_JOB"
