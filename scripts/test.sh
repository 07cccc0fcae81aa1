#!/usr/bin/env bash
# test.sh: the project's test command (the README's, and what CI runs).
#
# Usage: scripts/test.sh
#
# 1. cargo test --workspace (without mc-merge's png feature, checked in step 2): unit,
#    verification, property and CLI tests of every crate and the cross-crate pipeline
#    (tests/), then the slow statistical checks that the default run ignores
#    (cargo test --release -- --ignored).
# 2. The release binaries, then the Python package: built into target/py-venv with
#    `maturin develop --release` (in the workspace's target/release; the extension's
#    dependencies are built with other features than the binaries', so most of them are
#    compiled again) and its pytest tests, which compare its numbers with the release
#    binaries' bytes.
# 3. The end-to-end checks with real parts:
#    - scripts/slurm/e2e-test.sh: a real single-node Slurm cluster (started and stopped
#      here): an 8-task job array with a dependent merge, and a cancelled task resubmitted;
#    - scripts/smoke-test.sh: the README's main command on a small job, and its SVG plots
#      rendered to PNG with rsvg-convert, and mc-merge's own PNGs checked;
#    - scripts/browser-test.sh: mc-merge's report.html opened in headless Chromium: every
#      image loads, nothing is fetched, a screenshot is not blank, the page prints.
# Needs what scripts/setup.sh installs (it is run first when something is missing).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
# Each phase says when it starts (seconds since this script began), so a slow CI run shows
# where its time went.
phase() { echo "test: $1 (at ${SECONDS} s)" >&2; }

command -v rsvg-convert >/dev/null && command -v slurmctld >/dev/null && command -v chromium >/dev/null && [ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] && [ -x target/py-venv/bin/maturin ] || scripts/setup.sh

phase "cargo test --workspace (without the png feature)"
# Without mc-merge's default feature png: resvg's build is about 90 s of CPU in the debug
# profile, and the PNGs are checked on the release binaries by scripts/smoke-test.sh. (No
# other crate of the workspace has a default feature.)
cargo test --workspace --no-default-features --quiet

phase "the slow statistical checks (#[ignore]d in the default run), in release"
# Only the crates that have such tests: building every test target in release costs minutes.
for crate in $(grep -rl '#\[ignore' crates/*/src crates/*/tests | cut -d/ -f2 | sort -u); do
    cargo test --release --quiet -p "$crate" -- --ignored
done

phase "release binaries"
cargo build --release --quiet -p mc-shard -p mc-merge -p truss-cli -p truss-mc

phase "Python package: maturin develop --release, then pytest"
(
    # shellcheck disable=SC1091
    . target/py-venv/bin/activate
    maturin develop --release --quiet
    python -m pytest python/tests -q
)

phase "Slurm end to end"
scripts/slurm/e2e-test.sh

phase "smoke test of the main command"
scripts/smoke-test.sh

phase "report.html in a browser"
scripts/browser-test.sh

phase "all passed"
