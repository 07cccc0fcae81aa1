#!/usr/bin/env bash
# e2e-test.sh: end-to-end test of the Slurm path on a real (local, single-node) Slurm cluster.
#
# Usage: scripts/slurm/e2e-test.sh            (run by scripts/test.sh)
#
# 1. Starts the local cluster (start-local-cluster.sh installs Slurm and munge if missing).
# 2. Runs a job of 24,000 samples (the paper's 5-stage truss) in one process and merges it.
# 3. Submits the same job as an 8-task array plus a dependent merge (submit.sh), waits on a
#    wall-clock deadline (wait-jobs.sh), and checks the merged report.json is byte-identical
#    to the single-process one.
# 4. Submits it again to a fresh directory, cancels one array task while it is writing its
#    shard, checks that the task is reported CANCELLED, the merge cancelled and the shard
#    missing, resubmits the missing shards (submit.sh --only-missing), and checks the
#    completed report is again byte-identical.
# 5. Stops the cluster (also on failure).
#
# Needs target/release/mc-shard and mc-merge (scripts/test.sh builds them), or MC_SHARD and
# MC_MERGE. Exit 0 when every check passes.
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export MC_SHARD="${MC_SHARD:-$REPO/target/release/mc-shard}"
export MC_MERGE="${MC_MERGE:-$REPO/target/release/mc-merge}"
SLURM="$REPO/scripts/slurm"
for b in "$MC_SHARD" "$MC_MERGE"; do
    [[ -x "$b" ]] || { echo "e2e: $b not built (cargo build --release -p mc-shard -p mc-merge)" >&2; exit 2; }
done

WORK="$(mktemp -d /tmp/truss-mc-slurm-e2e.XXXXXX)"
cleanup() {
    "$SLURM/stop-local-cluster.sh" --purge >/dev/null 2>&1 || true
}
trap cleanup EXIT
fail() { echo "e2e: FAIL: $*" >&2; exit 1; }
step() { echo "e2e: $*" >&2; }

cat > "$WORK/job.json" <<'EOF'
{
  "model": {"prism": {"stages": 30}},
  "seed": 4242,
  "cases": [
    {"name": "sigma-0.0063", "samples": 120000,
     "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}
  ]
}
EOF

step "starting the local Slurm cluster"
t0=$SECONDS
eval "$("$SLURM/start-local-cluster.sh")"   # exports SLURM_CONF for scancel below
step "cluster up in $((SECONDS - t0)) s"

step "single-process reference"
"$MC_SHARD" run --job "$WORK/job.json" --out "$WORK/single" --quiet >/dev/null
"$MC_MERGE" "$WORK/single" --out "$WORK/single/report" --no-plots >/dev/null
[[ -s "$WORK/single/report/report.json" ]] || fail "no reference report"

step "an 8-task array and a dependent merge"
t0=$SECONDS
eval "$("$SLURM/submit.sh" "$WORK/job.json" --shards 8 --out "$WORK/array")"
# shellcheck disable=SC2154 # set by the eval above
"$SLURM/wait-jobs.sh" "$jobs" --timeout 600 > "$WORK/array.states" || fail "array run: $(cat "$WORK/array.states")"
step "array and merge completed in $((SECONDS - t0)) s"
cmp "$WORK/single/report/report.json" "$WORK/array/report/report.json" \
    || fail "the merged report differs from the single-process one"
step "merged report is byte-identical to the single-process report"

step "cancelling one array task mid-shard, then resubmitting what is missing"
eval "$("$SLURM/submit.sh" "$WORK/job.json" --shards 8 --out "$WORK/killed")"
victim=5
# Shards of 15,000 samples of the 30-stage truss (about 150 µs each: two seconds of one
# core): the cancel lands mid-shard. Shards of 30,000 samples of the 5-stage truss (0.2 s
# on two threads) sometimes finished between their first lines and the scancel on a loaded
# machine, leaving nothing missing.
shard_file="$WORK/killed/$(printf 'shard-%010d-%010d.jsonl' 75000 90000)"
deadline=$((SECONDS + 300))
until [[ -f "$shard_file" ]] && (( $(wc -l < "$shard_file") > 1 )); do
    (( SECONDS < deadline )) || fail "task $victim never started writing"
    sleep 0.01
done
# shellcheck disable=SC2154 # set by the eval above
scancel "${array_job}_${victim}"
set +e
"$SLURM/wait-jobs.sh" "$jobs" --timeout 600 > "$WORK/killed.states"
status=$?
set -e
[[ $status -eq 1 ]] || fail "wait-jobs should report a failure (exit $status): $(cat "$WORK/killed.states")"
grep -q "task=$victim .*state=CANCELLED" "$WORK/killed.states" || fail "task $victim not CANCELLED: $(cat "$WORK/killed.states")"
grep -q "jobid=$merge_job .*state=CANCELLED" "$WORK/killed.states" || fail "the merge was not cancelled: $(cat "$WORK/killed.states")"
missing="$("$MC_SHARD" status --job "$WORK/job.json" --out "$WORK/killed" --shards 8 --missing)"
[[ ",$missing," == *",$victim,"* ]] || fail "shard $victim should be missing, status says '$missing'"
step "task $victim cancelled with $(($(wc -l < "$shard_file") - 1)) lines written; missing: $missing"
eval "$("$SLURM/submit.sh" "$WORK/job.json" --shards 8 --out "$WORK/killed" --only-missing)"
# shellcheck disable=SC2154 # set by the eval above
[[ "$array_indices" == "$missing" ]] || fail "resubmitted '$array_indices', missing was '$missing'"
"$SLURM/wait-jobs.sh" "$jobs" --timeout 600 > "$WORK/resubmit.states" || fail "resubmission: $(cat "$WORK/resubmit.states")"
cmp "$WORK/single/report/report.json" "$WORK/killed/report/report.json" \
    || fail "the report after resubmission differs from the single-process one"
cmp <(cat "$WORK"/single/shard-*.jsonl | grep '"record":"sample"') \
    <(cat "$WORK"/killed/shard-*.jsonl | grep '"record":"sample"') \
    || fail "the sample lines after resubmission differ"
step "resubmission completed the job; report and sample lines byte-identical"
rm -rf "$WORK"
echo "e2e: all Slurm checks passed"
