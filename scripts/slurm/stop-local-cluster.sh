#!/usr/bin/env bash
# stop-local-cluster.sh: stop the local single-node Slurm cluster started by
# start-local-cluster.sh (slurmd, slurmctld, then munged).
#
# Usage: scripts/slurm/stop-local-cluster.sh [--purge] [--keep-jobs]
#
#   --purge      also delete the state directory ($SLURM_LOCAL_DIR, default
#                /tmp/truss-mc-slurm): config, logs, job state, munge key.
#                The next start is then a clean one and job ids restart at 1.
#   --keep-jobs  do not cancel queued/running jobs first. By default they are
#                cancelled (and waited for) so that no job process outlives
#                the daemons; mc-shard is crash-safe, so the cancelled shards
#                can be resubmitted with `submit.sh ... --only-missing`.
#
# Daemons are found only through their pid files in $SLURM_LOCAL_DIR (a pid
# is used only if that process still has the expected name); each gets
# SIGTERM, up to SLURM_STOP_TIMEOUT seconds (default 30) to exit, then SIGKILL.
# Safe to run when nothing runs, and to run twice.
#
# Exit status: 0 stopped (or nothing was running); 1 a daemon would not die;
# 2 usage error.
set -euo pipefail

# shellcheck source-path=SCRIPTDIR source=_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

PURGE=0 KEEP_JOBS=0
while [[ $# -gt 0 ]]; do
    case "$1" in
        --purge) PURGE=1; shift ;;
        --keep-jobs) KEEP_JOBS=1; shift ;;
        -h|--help) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
        *) die "unknown argument: $1 (usage: stop-local-cluster.sh [--purge] [--keep-jobs])" ;;
    esac
done
STOP_TIMEOUT="${SLURM_STOP_TIMEOUT:-30}"
[[ "$STOP_TIMEOUT" =~ ^[1-9][0-9]*$ ]] || die "SLURM_STOP_TIMEOUT must be a positive integer, got '$STOP_TIMEOUT'"

if [[ ! -d "$SLURM_LOCAL_DIR" ]]; then
    log "no state directory $SLURM_LOCAL_DIR: nothing to stop"
    exit 0
fi
[[ $EUID -eq 0 ]] || die "must run as root"

exec 9> "$SLURM_LOCAL_DIR/.lock"
flock -w 120 9 || die "could not take the lock $SLURM_LOCAL_DIR/.lock" 1

# ------------------------------------------------------- cancel jobs
if [[ $KEEP_JOBS -eq 0 && -n "$(daemon_pid slurmctld "$SLURMCTLD_PIDFILE")" && -f "$LOCAL_CONF" ]]; then
    export SLURM_CONF="$LOCAL_CONF"
    jobs="$(timeout 10 squeue -h -o '%A' 2>/dev/null | sort -un | paste -sd, - || true)"
    if [[ -n "$jobs" ]]; then
        log "cancelling jobs $jobs"
        IFS=, read -r -a ids <<< "$jobs"
        timeout 10 scancel "${ids[@]}" 2>/dev/null || true
        deadline=$(( $(now) + STOP_TIMEOUT ))
        while [[ -n "$(timeout 10 squeue -h -o '%A' 2>/dev/null || true)" ]] && (( $(now) < deadline )); do
            sleep 0.25
        done
    fi
fi

# ------------------------------------------------------- stop daemons
failed=0
stopped=0
stop_daemon() {  # stop_daemon NAME PIDFILE
    local name="$1" pidfile="$2" pid deadline
    pid="$(daemon_pid "$name" "$pidfile")"
    if [[ -z "$pid" ]]; then
        rm -f "$pidfile"
        return 0
    fi
    log "stopping $name (pid $pid)"
    stopped=$(( stopped + 1 ))
    kill -TERM "$pid" 2>/dev/null || true
    deadline=$(( $(now) + STOP_TIMEOUT ))
    while pid_is "$name" "$pid" && (( $(now) < deadline )); do sleep 0.1; done
    if pid_is "$name" "$pid"; then
        log "$name (pid $pid) still running after ${STOP_TIMEOUT} s; sending SIGKILL"
        kill -KILL "$pid" 2>/dev/null || true
        deadline=$(( $(now) + 5 ))
        while pid_is "$name" "$pid" && (( $(now) < deadline )); do sleep 0.1; done
    fi
    if pid_is "$name" "$pid"; then
        printf '%s: error: %s (pid %s) would not exit\n' "${0##*/}" "$name" "$pid" >&2
        failed=1
    else
        rm -f "$pidfile"
    fi
}
stop_daemon slurmd "$SLURMD_PIDFILE"
stop_daemon slurmctld "$SLURMCTLD_PIDFILE"
stop_daemon munged "$MUNGE_PIDFILE"
[[ $failed -eq 0 ]] || exit 1

# ------------------------------------------------------------- purge
if [[ $PURGE -eq 1 ]]; then
    # Only delete a directory that looks like ours.
    if [[ "$SLURM_LOCAL_DIR" == / || ! -e "$SLURM_LOCAL_DIR/.lock" ]]; then
        die "$SLURM_LOCAL_DIR does not look like a local-cluster state directory; not deleting it" 1
    fi
    log "deleting $SLURM_LOCAL_DIR"
    rm -rf -- "$SLURM_LOCAL_DIR"
fi
if [[ $stopped -eq 0 ]]; then log "nothing was running"; else log "stopped"; fi
