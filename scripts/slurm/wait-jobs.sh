#!/usr/bin/env bash
# wait-jobs.sh: wait until Slurm jobs (and every task of job arrays) have left
# the queue, then report each one's final state from the jobcomp/filetxt file.
#
# Usage: scripts/slurm/wait-jobs.sh JOBID... [--timeout SECONDS] [--poll SECONDS]
#
#   JOBID        a job id or an array's job id (as printed by submit.sh:
#                array_job=ID, merge_job=ID, or its jobs=ID,ID list); an
#                array id covers all its tasks
#   --timeout S  wall-clock limit for the wait (default 3600, env WAIT_JOBS_TIMEOUT)
#   --poll S     squeue polling interval, may be fractional (default 0.5)
#
# It polls `squeue --me` (jobs of the calling user) on a wall-clock deadline
# (not `sbatch --wait`, which backs off to 2, 8, 32 s between polls).
# Once none of the jobs is
# pending/running/completing it reads the file named by JobCompLoc in
# `scontrol show config` (JobCompType=jobcomp/filetxt; the local cluster of
# start-local-cluster.sh has it; sacct would need slurmdbd). When a job was
# requeued its last record wins.
#
# Output, on stdout, one line per job / array task:
#   job=<id> task=<array index or -> jobid=<id> state=<STATE> exit=<code:signal> [reason=<last reason seen in squeue>]
# and on stderr a summary naming the ones that did not complete.
#
# Exit status: 0 all COMPLETED; 1 some job/task did not complete (FAILED,
# CANCELLED, TIMEOUT, NODE_FAIL, ... or no record found); 2 usage error or
# Slurm not usable; 124 timeout (jobs still in the queue are listed).
set -euo pipefail

# shellcheck source-path=SCRIPTDIR source=_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; }

TIMEOUT="${WAIT_JOBS_TIMEOUT:-3600}"
POLL=0.5
JOBS=()
while [[ $# -gt 0 ]]; do
    case "$1" in
        --timeout) [[ $# -ge 2 ]] || die "--timeout needs a value"; TIMEOUT="$2"; shift 2 ;;
        --timeout=*) TIMEOUT="${1#*=}"; shift ;;
        --poll) [[ $# -ge 2 ]] || die "--poll needs a value"; POLL="$2"; shift 2 ;;
        --poll=*) POLL="${1#*=}"; shift ;;
        -h|--help) usage; exit 0 ;;
        -*) die "unknown option: $1 (see --help)" ;;
        *) [[ "$1" =~ ^[0-9]+(,[0-9]+)*$ ]] || die "not a job id: '$1' (expected a number, or numbers separated by commas)"
           IFS=, read -r -a more <<< "$1"
           JOBS+=("${more[@]}"); shift ;;
    esac
done
[[ ${#JOBS[@]} -gt 0 ]] || die "no job ids given (usage: wait-jobs.sh JOBID... [--timeout SECONDS])"
[[ "$TIMEOUT" =~ ^[0-9]+$ ]] || die "--timeout must be a whole number of seconds, got '$TIMEOUT'"
[[ "$POLL" =~ ^[0-9]*\.?[0-9]+$ ]] || die "--poll must be a number of seconds, got '$POLL'"
command -v squeue > /dev/null || die "squeue not found (is Slurm installed? see start-local-cluster.sh)"

ids=" ${JOBS[*]} "
deadline=$(( $(now) + TIMEOUT ))
declare -A reason=()   # last pending/running reason seen per "arrayjob_task" or job id

# ------------------------------------------------------------- poll squeue
# Default squeue states are the active ones (pending, running, completing,
# configuring, suspended, ...); finished jobs drop out of the listing.
squeue_failed_since=""
while :; do
    if out="$(timeout 20 squeue -h --me -o '%A|%F|%K|%T|%r' 2>&1)"; then
        squeue_failed_since=""
        active=()
        while IFS='|' read -r jid ajid task st rs; do
            [[ -n "$jid" ]] || continue
            if [[ "$ids" == *" $jid "* || "$ids" == *" $ajid "* ]]; then
                active+=("$jid|$ajid|$task|$st|$rs")
                # Tasks still pending as a group show up as e.g. "2-7": their
                # reason is remembered for the whole array.
                if [[ "$task" == N/A ]]; then key="$jid"
                elif [[ "$task" =~ ^[0-9]+$ ]]; then key="${ajid}_${task}"
                else key="$ajid"; fi
                reason[$key]="$rs"
            fi
        done <<< "$out"
        [[ ${#active[@]} -eq 0 ]] && break
    else
        # slurmctld may be restarting: keep trying until the deadline.
        if [[ -z "$squeue_failed_since" ]]; then
            squeue_failed_since=$(now)
            log "squeue failed (will retry): ${out//$'\n'/ }"
        fi
    fi
    if (( $(now) >= deadline )); then
        printf 'wait-jobs: timeout after %s s; still in the queue:\n' "$TIMEOUT" >&2
        if [[ -n "$squeue_failed_since" ]]; then
            printf '  (squeue has been failing since %s s ago)\n' "$(( $(now) - squeue_failed_since ))" >&2
        else
            printf '  %s\n' "${active[@]}" | sed 's/|/ /g' >&2
        fi
        exit 124
    fi
    sleep "$POLL"
done

# --------------------------------------------------------- read outcomes
jobcomp=""
if conf="$(timeout 20 scontrol show config 2>/dev/null)"; then
    comptype="$(sed -n 's/^JobCompType *= *//p' <<< "$conf")"
    jobcomp="$(sed -n 's/^JobCompLoc *= *//p' <<< "$conf")"
    [[ "$comptype" == jobcomp/filetxt ]] \
        || die "JobCompType is '$comptype', not jobcomp/filetxt: cannot read job outcomes"
fi
[[ -n "$jobcomp" ]] || jobcomp="$JOBCOMP_LOG"

# Print "key jobid arrayjob task state exit" for every record of our jobs,
# the last record per job/task only (requeued tasks have several).
read_outcomes() {
    [[ -r "$jobcomp" ]] || return 0
    awk -v ids="$ids" '
        {
            jid = ""; ajid = ""; task = "-"; st = "?"; ec = "?"
            for (i = 1; i <= NF; i++) {
                split($i, kv, "=")
                if (kv[1] == "JobId") jid = kv[2]
                else if (kv[1] == "ArrayJobId") ajid = kv[2]
                else if (kv[1] == "ArrayTaskId") task = substr($i, 13)
                else if (kv[1] == "JobState") st = kv[2]
                else if (kv[1] == "ExitCode") ec = kv[2]
            }
            if (jid == "") next
            if (index(ids, " " jid " ") == 0 && (ajid == "" || index(ids, " " ajid " ") == 0)) next
            if (ajid == "" || ajid == "0") { ajid = jid; task = "-" }
            key = (task == "-") ? jid : ajid "_" task
            if (!(key in rec)) order[++n] = key
            rec[key] = jid " " ajid " " task " " st " " ec
        }
        END { for (i = 1; i <= n; i++) print order[i], rec[order[i]] }
    ' "$jobcomp"
}

# The record is written when the job leaves the queue; allow a short grace
# for every requested id to show up.
grace=$(( $(now) + 10 )); (( grace < deadline )) || grace=$deadline
while :; do
    outcomes="$(read_outcomes | sort -k3,3n -k4,4n)"
    missing=()
    for j in "${JOBS[@]}"; do
        awk -v j="$j" '$2 == j || $3 == j { found = 1 } END { exit !found }' <<< "$outcomes" \
            || missing+=("$j")
    done
    [[ ${#missing[@]} -eq 0 ]] && break
    (( $(now) < grace )) || break
    sleep "$POLL"
done

failed=()
total=0
while read -r key jid ajid task st ec; do
    [[ -n "$key" ]] || continue
    total=$(( total + 1 ))
    line="job=$ajid task=$task jobid=$jid state=$st exit=$ec"
    # Last squeue reason, for jobs/tasks that ended without running
    # (e.g. DependencyNeverSatisfied); a task never seen on its own falls
    # back to the reason of the array's pending group.
    if [[ -n "${reason[$key]+set}" ]]; then r="${reason[$key]}"; else r="${reason[$ajid]:-}"; fi
    [[ "$r" == None ]] && r=""
    if [[ "$st" != COMPLETED ]]; then
        [[ -n "$r" ]] && line+=" reason=$r"
        if [[ "$task" == - ]]; then failed+=("job $jid: $st (exit $ec${r:+, last reason $r})")
        else failed+=("job ${ajid} task $task (jobid $jid): $st (exit $ec${r:+, last reason $r})"); fi
    fi
    printf '%s\n' "$line"
done <<< "$outcomes"
for j in "${missing[@]}"; do
    printf 'job=%s task=- jobid=%s state=UNKNOWN exit=?\n' "$j" "$j"
    failed+=("job $j: no record in $jobcomp (unknown job id, or jobcomp file rotated?)")
done

if [[ ${#failed[@]} -eq 0 ]]; then
    printf 'wait-jobs: all %d job(s)/task(s) COMPLETED\n' "$total" >&2
    exit 0
fi
printf 'wait-jobs: %d of %d job(s)/task(s) did not complete:\n' "${#failed[@]}" "$(( total + ${#missing[@]} ))" >&2
printf '  %s\n' "${failed[@]}" >&2
exit 1
