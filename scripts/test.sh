#!/usr/bin/env bash
# test.sh: the project's test command (the README's, and what CI runs).
#
# Usage: scripts/test.sh
#
# 1. cargo test --workspace: unit, verification, property and CLI tests of every crate and
#    the cross-crate pipeline (tests/), then the slow statistical checks that the default run
#    ignores (cargo test --release -- --ignored).
# 2. The release binaries, then the end-to-end checks with real parts:
#    - scripts/slurm/e2e-test.sh: a real single-node Slurm cluster (started and stopped
#      here): an 8-task job array with a dependent merge, and a cancelled task resubmitted;
#    - scripts/smoke-test.sh: the README's main command on a small job, and its SVG plots
#      rendered to PNG with rsvg-convert.
# Needs what scripts/setup.sh installs (it is run first when something is missing).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"

command -v rsvg-convert >/dev/null && command -v slurmctld >/dev/null && [ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || scripts/setup.sh

echo "test: cargo test --workspace" >&2
cargo test --workspace --quiet

echo "test: the cross-check against faer (a large build the default tests do without)" >&2
cargo test --release --quiet -p truss-core --features cross-checks --lib -- block::tests::agrees_with_faer_dense

echo "test: the slow statistical checks (#[ignore]d in the default run), in release" >&2
# Only the crates that have such tests: building every test target in release costs minutes.
for crate in $(grep -rl '#\[ignore' crates/*/src crates/*/tests | cut -d/ -f2 | sort -u); do
    cargo test --release --quiet -p "$crate" -- --ignored
done

echo "test: release binaries" >&2
cargo build --release --quiet -p mc-shard -p mc-merge -p truss-cli -p truss-mc

echo "test: Slurm end to end" >&2
scripts/slurm/e2e-test.sh

echo "test: smoke test of the main command" >&2
scripts/smoke-test.sh

echo "test: all passed" >&2
