#!/usr/bin/env bash
# Shared helpers for the scripts in scripts/slurm/ (sourced, not executed).
#
# Defines the layout of the local single-node Slurm cluster's state directory
# (one directory, default /tmp/truss-mc-slurm, overridable with SLURM_LOCAL_DIR),
# points SLURM_CONF at its slurm.conf when the caller did not set SLURM_CONF,
# and provides small pid-file helpers.
#
# Usage (from a script in the same directory):
#   source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

# The variables below are used by the scripts that source this file.
# shellcheck disable=SC2034

# Repository root: two levels above this file (scripts/slurm/_common.sh).
SLURM_SCRIPTS_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)"
REPO="$(cd "$SLURM_SCRIPTS_DIR/../.." && pwd -P)"

# State directory layout (everything the local cluster writes lives here).
SLURM_LOCAL_DIR="${SLURM_LOCAL_DIR:-/tmp/truss-mc-slurm}"
LOCAL_ETC="$SLURM_LOCAL_DIR/etc"           # slurm.conf (and cgroup.conf if needed)
LOCAL_RUN="$SLURM_LOCAL_DIR/run"           # slurmctld.pid, slurmd.pid
LOCAL_LOG="$SLURM_LOCAL_DIR/log"           # daemon logs, jobcomp.log
LOCAL_CTLD_STATE="$SLURM_LOCAL_DIR/state/ctld"   # StateSaveLocation
LOCAL_SLURMD_SPOOL="$SLURM_LOCAL_DIR/state/slurmd" # SlurmdSpoolDir
LOCAL_MUNGE="$SLURM_LOCAL_DIR/munge"       # munged key, socket, pid, seed, log (owned by munge)
LOCAL_CONF="$LOCAL_ETC/slurm.conf"
MUNGE_KEY="$LOCAL_MUNGE/munge.key"
MUNGE_SOCKET="$LOCAL_MUNGE/munge.socket"
MUNGE_PIDFILE="$LOCAL_MUNGE/munged.pid"
MUNGE_LOG="$LOCAL_MUNGE/munged.log"
MUNGE_SEED="$LOCAL_MUNGE/munged.seed"
SLURMCTLD_PIDFILE="$LOCAL_RUN/slurmctld.pid"
SLURMD_PIDFILE="$LOCAL_RUN/slurmd.pid"
SLURMCTLD_LOG="$LOCAL_LOG/slurmctld.log"
SLURMD_LOG="$LOCAL_LOG/slurmd.log"
JOBCOMP_LOG="$LOCAL_LOG/jobcomp.log"

# Client commands (sbatch, squeue, sinfo, scontrol) find the local cluster
# through SLURM_CONF. An explicitly set SLURM_CONF always wins, so the same
# scripts can target a real cluster.
if [[ -z "${SLURM_CONF:-}" && -f "$LOCAL_CONF" ]]; then
    export SLURM_CONF="$LOCAL_CONF"
fi

log() { printf '[%s] %s\n' "${0##*/}" "$*" >&2; }
die() { printf '%s: error: %s\n' "${0##*/}" "$1" >&2; exit "${2:-2}"; }

now() { date +%s; }

# pid_from_file FILE: print the pid stored in FILE (empty if none/garbage).
pid_from_file() {
    local f="$1" pid=""
    if [[ -r "$f" ]]; then read -r pid < "$f" || true; fi
    if [[ "$pid" =~ ^[0-9]+$ ]]; then printf '%s\n' "$pid"; fi
}

# pid_is NAME PID: true if PID is alive and its executable name is NAME
# (guards against a stale pid file whose pid was reused by another process).
pid_is() {
    local name="$1" pid="$2" comm=""
    [[ -n "$pid" && -r "/proc/$pid/comm" ]] || return 1
    read -r comm < "/proc/$pid/comm" 2>/dev/null || return 1
    [[ "$comm" == "$name" ]]
}

# daemon_pid NAME PIDFILE: print the pid of the running daemon, or nothing.
daemon_pid() {
    local pid
    pid="$(pid_from_file "$2")"
    if pid_is "$1" "$pid"; then printf '%s\n' "$pid"; fi
}
