#!/usr/bin/env bash
# start-local-cluster.sh: bring up a single-node Slurm cluster on this machine
# (Debian bookworm, root, no systemd) for running truss-mc job arrays locally.
#
# Usage: scripts/slurm/start-local-cluster.sh
#
# What it does (each step is skipped when already done, so running it twice
# is safe; when the cluster is already up and healthy it changes nothing):
#   1. installs munge, slurmctld, slurmd, slurm-client from Debian if missing;
#   2. creates a private munge key and starts munged as the munge user, with
#      its key, socket, pid file, seed and log in $SLURM_LOCAL_DIR/munge;
#   3. writes $SLURM_LOCAL_DIR/etc/slurm.conf for one node named $(hostname -s)
#      on 127.0.0.1 with the CPUs `slurmd -C` reports;
#   4. starts slurmctld and slurmd (daemonised, pid files in
#      $SLURM_LOCAL_DIR/run, logs in $SLURM_LOCAL_DIR/log);
#   5. waits until `sinfo` shows the node idle (or mixed/allocated when jobs
#      kept across a restart run), or fails after the deadline and prints
#      where the logs are.
# On stdout it prints one line, `export SLURM_CONF=<path>`, for interactive
# use of sinfo/squeue/sbatch (submit.sh and wait-jobs.sh find it themselves).
#
# Environment:
#   SLURM_LOCAL_DIR        state directory (default /tmp/truss-mc-slurm)
#   SLURM_START_TIMEOUT    seconds to wait for the daemons and the idle node,
#                          counted after the install step (default 60)
#   SLURM_INSTALL_TIMEOUT  seconds allowed for apt-get (default 600)
#   SLURMCTLD_PORT, SLURMD_PORT  TCP ports on 127.0.0.1 (default 6817, 6818)
#
# Exit status: 0 cluster up (node idle, or busy when it already was up),
# 1 failed to come up, 2 usage/environment error.
set -euo pipefail

# shellcheck source-path=SCRIPTDIR source=_common.sh
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

START_TIMEOUT="${SLURM_START_TIMEOUT:-60}"
INSTALL_TIMEOUT="${SLURM_INSTALL_TIMEOUT:-600}"
SLURMCTLD_PORT="${SLURMCTLD_PORT:-6817}"
SLURMD_PORT="${SLURMD_PORT:-6818}"

if [[ $# -gt 0 ]]; then
    case "$1" in
        -h|--help) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
        *) die "unexpected argument: $1 (this script takes none; see --help)" ;;
    esac
fi
[[ "$START_TIMEOUT" =~ ^[1-9][0-9]*$ ]] || die "SLURM_START_TIMEOUT must be a positive integer, got '$START_TIMEOUT'"
[[ "$INSTALL_TIMEOUT" =~ ^[1-9][0-9]*$ ]] || die "SLURM_INSTALL_TIMEOUT must be a positive integer, got '$INSTALL_TIMEOUT'"
[[ $EUID -eq 0 ]] || die "must run as root (installs packages, runs munged as the munge user)"

T_START=$(now)
NODE="$(hostname -s)"
[[ -n "$NODE" ]] || die "hostname -s printed nothing"

mkdir -p "$LOCAL_ETC" "$LOCAL_RUN" "$LOCAL_LOG" "$LOCAL_CTLD_STATE" "$LOCAL_SLURMD_SPOOL"
chmod 0755 "$SLURM_LOCAL_DIR"

# One start/stop at a time.
exec 9> "$SLURM_LOCAL_DIR/.lock"
flock -w 120 9 || die "could not take the lock $SLURM_LOCAL_DIR/.lock" 1

print_logs_and_fail() {
    local msg="$1" f
    printf '%s: error: %s\n' "${0##*/}" "$msg" >&2
    printf 'Logs are in %s:\n' "$SLURM_LOCAL_DIR" >&2
    for f in "$SLURMCTLD_LOG" "$SLURMD_LOG" "$MUNGE_LOG" \
             "$LOCAL_LOG/slurmctld.stdout" "$LOCAL_LOG/slurmd.stdout" \
             "$LOCAL_LOG/munged.stdout" "$LOCAL_LOG/apt.log"; do
        [[ -s "$f" ]] || continue
        printf '  %s (last lines):\n' "$f" >&2
        tail -n 15 "$f" | sed 's/^/    /' >&2
    done
    exit 1
}

# ---------------------------------------------------------------- 1. install
install_packages() {
    local p missing=()
    for p in munge slurmctld slurmd slurm-client; do
        dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -qx 'install ok installed' \
            || missing+=("$p")
    done
    [[ ${#missing[@]} -eq 0 ]] && return 0
    log "installing Debian packages (missing: ${missing[*]}); apt output in $LOCAL_LOG/apt.log"
    local t0; t0=$(now)
    export DEBIAN_FRONTEND=noninteractive
    {
        timeout "$INSTALL_TIMEOUT" apt-get -o DPkg::Lock::Timeout=120 update &&
        timeout "$INSTALL_TIMEOUT" apt-get -o DPkg::Lock::Timeout=120 install -y \
            --no-install-recommends munge slurmctld slurmd slurm-client
    } > "$LOCAL_LOG/apt.log" 2>&1 || print_logs_and_fail "apt-get failed"
    log "installed in $(( $(now) - t0 )) s"
}
install_packages
for cmd in munged munge unmunge slurmctld slurmd sinfo scontrol; do
    command -v "$cmd" > /dev/null || die "$cmd not found after installing the packages" 1
done

# ----------------------------------------------------------- 2. slurm.conf
# Hardware as slurmd sees it (slurmd checks its registration against these);
# fall back to nproc. RealMemory is set a little below what slurmd reports
# so that a small fluctuation never drains the node for "Low RealMemory".
hw="$(slurmd -C 2>/dev/null | head -n 1 || true)"
hw_field() { sed -n "s/.*[[:space:]]$1=\([0-9]*\).*/\1/p" <<< "$hw"; }
CPUS="$(hw_field CPUs)"; SOCKETS="$(hw_field SocketsPerBoard)"
CORES="$(hw_field CoresPerSocket)"; THREADS="$(hw_field ThreadsPerCore)"
MEM="$(hw_field RealMemory)"
if [[ -z "$CPUS" || -z "$SOCKETS" || -z "$CORES" || -z "$THREADS" ]]; then
    CPUS="$(nproc)"; SOCKETS=1; CORES="$CPUS"; THREADS=1
fi
[[ -n "$MEM" && "$MEM" -gt 100 ]] && MEM=$(( MEM * 95 / 100 )) || MEM=1

new_conf="$(cat <<EOF
# Generated by scripts/slurm/start-local-cluster.sh; rewritten on start.
# Single-node local cluster for truss-mc; see scripts/slurm/README.md.
ClusterName=truss-mc-local
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$SLURMCTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MUNGE_SOCKET,cred_expire=30
StateSaveLocation=$LOCAL_CTLD_STATE
SlurmdSpoolDir=$LOCAL_SLURMD_SPOOL
SlurmctldPidFile=$SLURMCTLD_PIDFILE
SlurmdPidFile=$SLURMD_PIDFILE
SlurmctldLogFile=$SLURMCTLD_LOG
SlurmdLogFile=$SLURMD_LOG
SlurmctldDebug=info
SlurmdDebug=info
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$JOBCOMP_LOG
SchedulerParameters=batch_sched_delay=0,sched_interval=5
DependencyParameters=kill_invalid_depend
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
SwitchType=switch/none
MaxArraySize=10001
MaxJobCount=50000
NodeName=$NODE NodeAddr=127.0.0.1 NodeHostname=$NODE CPUs=$CPUS SocketsPerBoard=$SOCKETS CoresPerSocket=$CORES ThreadsPerCore=$THREADS RealMemory=$MEM State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
)"

# ------------------------------------------------ already up and healthy?
node_state() {
    # Lower-case long state of our node, e.g. idle, mixed, allocated,
    # idle* (not responding), drained, down*. Empty if slurmctld is unreachable.
    timeout 10 sinfo -h -N -n "$NODE" -o '%T' 2>/dev/null | head -n 1 || true
}
healthy_state() { [[ "$1" =~ ^(idle|mixed|allocated|completing)$ ]]; }

MUNGED_PID="$(daemon_pid munged "$MUNGE_PIDFILE")"
CTLD_PID="$(daemon_pid slurmctld "$SLURMCTLD_PIDFILE")"
SLURMD_PID="$(daemon_pid slurmd "$SLURMD_PIDFILE")"
if [[ -n "$MUNGED_PID" && -n "$CTLD_PID" && -n "$SLURMD_PID" && -f "$LOCAL_CONF" ]] \
    && [[ "$(cat "$LOCAL_CONF")" == "$new_conf" ]]; then
    export SLURM_CONF="$LOCAL_CONF"
    state="$(node_state)"
    if healthy_state "$state"; then
        log "cluster already up (munged $MUNGED_PID, slurmctld $CTLD_PID, slurmd $SLURMD_PID, node $NODE $state); nothing to do"
        printf 'export SLURM_CONF=%s\n' "$LOCAL_CONF"
        exit 0
    fi
    log "daemons run but node $NODE is '${state:-unreachable}'; repairing"
fi

# ------------------------------------------------------------- 3. munged
wait_until() {  # wait_until DEADLINE CMD...: poll CMD every 0.2 s until it succeeds
    local deadline="$1"; shift
    until "$@"; do
        (( $(now) < deadline )) || return 1
        sleep 0.2
    done
}
munge_works() { munge -n -S "$MUNGE_SOCKET" 2>/dev/null | unmunge -S "$MUNGE_SOCKET" > /dev/null 2>&1; }

install -d -o munge -g munge -m 0755 "$LOCAL_MUNGE"
if [[ ! -s "$MUNGE_KEY" ]]; then
    log "creating munge key $MUNGE_KEY"
    if command -v mungekey > /dev/null; then
        mungekey --create --keyfile="$MUNGE_KEY" --force
    else
        dd if=/dev/urandom of="$MUNGE_KEY" bs=1024 count=1 status=none
    fi
fi
chown munge:munge "$MUNGE_KEY"
chmod 0600 "$MUNGE_KEY"

if [[ -z "$MUNGED_PID" ]]; then
    log "starting munged (socket $MUNGE_SOCKET)"
    rm -f "$MUNGE_PIDFILE"
    runuser -u munge -- munged --force \
        --key-file="$MUNGE_KEY" --socket="$MUNGE_SOCKET" --pid-file="$MUNGE_PIDFILE" \
        --log-file="$MUNGE_LOG" --seed-file="$MUNGE_SEED" \
        < /dev/null >> "$LOCAL_LOG/munged.stdout" 2>&1 9>&- \
        || print_logs_and_fail "munged failed to start"
fi
wait_until $(( $(now) + 15 )) munge_works || print_logs_and_fail "munged does not answer on $MUNGE_SOCKET"
MUNGED_PID="$(daemon_pid munged "$MUNGE_PIDFILE")"
[[ -n "$MUNGED_PID" ]] || print_logs_and_fail "munged answers but its pid file $MUNGE_PIDFILE is missing"

CTLD_PID="$(daemon_pid slurmctld "$SLURMCTLD_PIDFILE")"
SLURMD_PID="$(daemon_pid slurmd "$SLURMD_PIDFILE")"

stop_pid() {  # stop_pid NAME PID: SIGTERM, wait up to 20 s, then SIGKILL
    local name="$1" pid="$2" deadline
    [[ -n "$pid" ]] || return 0
    log "stopping $name (pid $pid)"
    kill -TERM "$pid" 2>/dev/null || true
    deadline=$(( $(now) + 20 ))
    while pid_is "$name" "$pid" && (( $(now) < deadline )); do sleep 0.2; done
    if pid_is "$name" "$pid"; then kill -KILL "$pid" 2>/dev/null || true; sleep 0.5; fi
}

if [[ ! -f "$LOCAL_CONF" ]] || [[ "$(cat "$LOCAL_CONF")" != "$new_conf" ]]; then
    if [[ -n "$CTLD_PID" || -n "$SLURMD_PID" ]]; then
        log "slurm.conf changed; restarting the Slurm daemons"
        stop_pid slurmd "$SLURMD_PID"; SLURMD_PID=""
        stop_pid slurmctld "$CTLD_PID"; CTLD_PID=""
    fi
    printf '%s\n' "$new_conf" > "$LOCAL_CONF.tmp"
    mv -f "$LOCAL_CONF.tmp" "$LOCAL_CONF"
    log "wrote $LOCAL_CONF (node $NODE: CPUs=$CPUS, RealMemory=$MEM MB)"
fi
export SLURM_CONF="$LOCAL_CONF"

# ---------------------------------------------------------- 4. daemons
# running_with_conf NAME: a process NAME started with our slurm.conf exists.
# (Used to notice at once a daemon that forked and then died, e.g. because
# its port is taken, instead of waiting for the deadline.)
running_with_conf() {
    local p comm args
    for p in /proc/[0-9]*; do
        read -r comm < "$p/comm" 2>/dev/null || continue
        [[ "$comm" == "$1" ]] || continue
        args="$(tr '\0' ' ' < "$p/cmdline" 2>/dev/null)" || continue
        [[ "$args" == *" -f $LOCAL_CONF "* ]] && return 0
    done
    return 1
}
# wait_daemon NAME READY_CMD...: wait until READY_CMD succeeds; fail at once
# if NAME has exited, or at the deadline.
wait_daemon() {
    local name="$1"; shift
    until "$@"; do
        running_with_conf "$name" || { sleep 0.3; "$@" && return 0
            print_logs_and_fail "$name exited during start-up"; }
        (( $(now) < deadline )) || print_logs_and_fail "$name not ready within ${START_TIMEOUT} s"
        sleep 0.2
    done
}
deadline=$(( $(now) + START_TIMEOUT ))

if [[ -z "$CTLD_PID" ]]; then
    # A StateSaveLocation without job_state means slurmctld starts from a
    # clean state and hands out job ids from 1 again. Old job ids must then
    # not be mistaken for new ones: move the old jobcomp file aside (wait-jobs
    # reads outcomes from it; it takes the last record of a job id anyway).
    # slurmd's spool from the old incarnation is emptied too when slurmd is
    # not running (Slurm 22.05 reissues credentials for reused job ids, so
    # this is only hygiene).
    if [[ ! -e "$LOCAL_CTLD_STATE/job_state" ]]; then
        if [[ -s "$JOBCOMP_LOG" ]]; then
            old="$JOBCOMP_LOG.$(date +%Y%m%dT%H%M%S)"
            log "clean slurmctld state: job ids restart at 1; moving old $JOBCOMP_LOG to $old"
            mv -f "$JOBCOMP_LOG" "$old"
        fi
        [[ -n "$SLURMD_PID" ]] || find "$LOCAL_SLURMD_SPOOL" -mindepth 1 -delete
    fi
    log "starting slurmctld"
    rm -f "$SLURMCTLD_PIDFILE"
    setsid slurmctld -f "$LOCAL_CONF" < /dev/null >> "$LOCAL_LOG/slurmctld.stdout" 2>&1 9>&- \
        || print_logs_and_fail "slurmctld failed to start"
fi
ctld_up() { timeout 10 scontrol ping 2>/dev/null | grep -q 'is UP'; }
wait_daemon slurmctld ctld_up

if [[ -z "$SLURMD_PID" ]]; then
    log "starting slurmd"
    rm -f "$SLURMD_PIDFILE"
    setsid slurmd -f "$LOCAL_CONF" -N "$NODE" < /dev/null >> "$LOCAL_LOG/slurmd.stdout" 2>&1 9>&- \
        || print_logs_and_fail "slurmd failed to start"
fi
slurmd_up() { [[ -n "$(daemon_pid slurmd "$SLURMD_PIDFILE")" ]]; }
wait_daemon slurmd slurmd_up

# ---------------------------------------------------- 5. wait for idle node
resumed=0
while :; do
    state="$(node_state)"
    # idle, or already running jobs kept across a restart (stop --keep-jobs,
    # or a restart because slurm.conf changed)
    healthy_state "$state" && break
    [[ -n "$(daemon_pid slurmctld "$SLURMCTLD_PIDFILE")" ]] || print_logs_and_fail "slurmctld died"
    slurmd_up || print_logs_and_fail "slurmd died"
    # A node left drained by an earlier run (a responding node, so no '*')
    # is put back into service once; a down node returns by itself once
    # slurmd registers (ReturnToService=2).
    if [[ $resumed -eq 0 && "$state" == *drain* && "$state" != *'*' ]]; then
        log "node $NODE is '$state'; resuming it"
        scontrol update NodeName="$NODE" State=RESUME 2>/dev/null || true
        resumed=1
    fi
    if (( $(now) >= deadline )); then
        print_logs_and_fail "node $NODE not idle after ${START_TIMEOUT} s (state: '${state:-slurmctld unreachable}')"
    fi
    sleep 0.25
done

log "cluster up in $(( $(now) - T_START )) s: node $NODE $state, CPUs=$CPUS; state in $SLURM_LOCAL_DIR"
printf 'export SLURM_CONF=%s\n' "$LOCAL_CONF"
