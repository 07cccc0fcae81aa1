#!/usr/bin/env bash
# work.sh: one cron round of a truss-mc worker pool on a shared directory.
#
# Usage: scripts/cron/work.sh JOB.json DIR K [mc-shard work options...]
#
# Runs `mc-shard work --job JOB --out DIR --shards K --quiet` (claims the next
# unclaimed shard, runs it, repeats; a dead worker's stale claim is taken over;
# a damaged shard is quarantined and the others run), appending its JSON action
# lines to DIR/work.log with a UTC timestamp per round. When no shard is left
# (`mc-shard status --missing` prints an empty line) and DIR/report/report.json
# does not exist yet, exactly one round (an flock on DIR/merge.lock, so two
# machines' rounds never both do it) audits 32 seeded random lines (`mc-shard
# audit`, a mismatch: exit 6, DIR/audit.json) and merges into DIR/report.
#
# A crontab line (every 10 minutes on each workstation sharing DIR):
#   */10 * * * * /path/to/truss-mc/scripts/cron/work.sh /path/to/job.json /shared/runs/p31 64
#
# Environment: MC_SHARD, MC_MERGE (default <repo>/target/release/{mc-shard,mc-merge}).
#
# Exit status: 5 when DIR/work.log, DIR/merge.lock or DIR/report is a symbolic
# link (nothing is written through it); mc-shard's (0 done or nothing to do; 2
# usage, e.g. another --shards count than the directory's pool; 5 a shard
# quarantined, the others ran; 130/143 interrupted), then the audit's or the
# merge's.
set -uo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd -P)"
MC_SHARD="${MC_SHARD:-$REPO/target/release/mc-shard}"
MC_MERGE="${MC_MERGE:-$REPO/target/release/mc-merge}"

if [[ $# -lt 3 ]]; then
    echo "usage: $0 JOB.json DIR K [mc-shard work options...]" >&2
    exit 2
fi
JOB="$1" DIR="$2" K="$3"
shift 3
mkdir -p "$DIR" || exit 4
LOG="$DIR/work.log"
# Nothing is written through a link planted in the shared directory (the shell's > and >>
# follow links): the round's log, its lock file and the report directory; exit 5, a file
# in the way.
for f in "$LOG" "$DIR/merge.lock" "$DIR/report"; do
    if [[ -L "$f" ]]; then
        echo "$0: $f: is a symbolic link; nothing is written through a link (remove it)" >&2
        exit 5
    fi
done

echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ) $(hostname) pid $$: mc-shard work --shards $K" >> "$LOG"
"$MC_SHARD" work --job "$JOB" --out "$DIR" --shards "$K" --quiet "$@" >> "$LOG" 2>&1
rc=$?
if [[ $rc -ne 0 ]]; then
    echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ) mc-shard work exited $rc" >> "$LOG"
    exit "$rc"
fi

missing="$("$MC_SHARD" status --job "$JOB" --out "$DIR" --shards "$K" --missing)" || exit $?
if [[ -n "$missing" || -e "$DIR/report/report.json" ]]; then
    exit 0
fi
# Every shard is complete: audit and merge, once.
exec 9>> "$DIR/merge.lock"
flock -n 9 || exit 0
[[ -e "$DIR/report/report.json" ]] && exit 0
{
    echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ) all $K shards complete: audit and merge"
    "$MC_SHARD" audit --job "$JOB" "$DIR" --samples 32 \
        && "$MC_MERGE" "$DIR" --out "$DIR/report"
} >> "$LOG" 2>&1
rc=$?
echo "# $(date -u +%Y-%m-%dT%H:%M:%SZ) audit and merge exited $rc" >> "$LOG"
exit "$rc"
