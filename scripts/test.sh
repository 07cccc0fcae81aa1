#!/usr/bin/env bash
# test.sh: the project's test command (the README's, and what CI runs).
#
# Usage: scripts/test.sh           (scripts/test.sh --help prints this)
#
# Everything is compiled once, in the `ci` profile (Cargo.toml: optimised like release, with
# debug assertions and overflow checks on, so the tests catch what a debug build catches),
# into target/ci; every step below runs what that one build made.
# 1. Build: every test target of the workspace and the binaries.
# 2. cargo test --workspace --profile ci -- --include-ignored: unit, verification, property and
#    CLI tests of every crate and the cross-crate pipeline (tests/), and in the same run the
#    slow statistical checks that a plain `cargo test` ignores (the README's, step 5, apart).
# 3. The Python package: built into target/py-venv with `maturin develop --profile ci` (the
#    feature unifier crates/workspace-hack gives its dependencies the binaries' features, so
#    only PyO3 and the extension are compiled) and its pytest tests, which compare its
#    numbers with the binaries' bytes.
# 4. The end-to-end checks with real parts, on target/ci's binaries:
#    - scripts/slurm/e2e-test.sh: a real single-node Slurm cluster (started and stopped
#      here): an 8-task job array with a dependent merge, and a cancelled task resubmitted
#      (started beside step 2, since it mostly waits on the scheduler; its log is printed if
#      it fails);
#    - scripts/smoke-test.sh: the README's main command on a small job, and its SVG plots
#      rendered to PNG with rsvg-convert, and mc-merge's own PNGs checked;
#    - scripts/browser-test.sh: mc-merge's report.html opened in headless Chromium: every
#      image loads, nothing is fetched, the answer is on the first screen at 1280 x 900, a
#      screenshot is not blank, the page prints.
# 5. The README as pasted (tests/tests/it/readme.rs, readme_runs_as_pasted): every ```sh and
#    ```python block of README.md, in order, in a clean shell in a copy of the repository
#    (target/readme-test/clone), with the paper's job cut to 2,000 samples a case: its own
#    release build (`cargo build --release`, kept in the copy's target/ between runs), its
#    own virtual environment and `pip install .` (maturin and NumPy, and pandas for its
#    snippet, from PyPI), the Monte Carlo, the merge, the diagnosis, the tolerance study and
#    the browser check of the quick start's report.
# Installs first, when something is missing, by scripts/setup.sh (as root or with sudo):
# Debian's slurmctld, slurmd, slurm-client, munge, librsvg2-bin, fonts-dejavu-core and
# chromium through apt-get, and the Python virtual environment target/py-venv with maturin,
# pytest and numpy (and OpenTURNS where PyPI has a wheel) from PyPI; step 5 fetches maturin,
# NumPy and pandas from PyPI into the copy's own environment. Crates come from crates.io as
# cargo builds (Cargo.lock pins them).
# Takes about 45 minutes from a clean clone on 2 cores (43 min 51 s measured on a machine
# busy with other builds: step 1, 18 min; steps 2 and 3, 7 min, the Slurm check beside
# them; step 4, 15 s; step 5, 18 min, most of it the copy's release build), and about
# 13 minutes once built (measured part by part: step 1 finding nothing to build, 1 min;
# steps 2 and 3, 8½ min; step 4, 15 s; step 5, 3½ min, its copy rebuilding only what
# changed).
# `scripts/test.sh --help` prints this and runs nothing.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$REPO"
if [[ "${1:-}" == "-h" || "${1:-}" == "--help" ]]; then
    sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'
    exit 0
elif (($#)); then
    echo "test.sh: takes no arguments (got: $*); scripts/test.sh --help says what it does" >&2
    exit 2
fi
# Each phase says when it starts (seconds since this script began), so a slow CI run shows
# where its time went.
phase() { echo "test: $1 (at ${SECONDS} s)" >&2; }

command -v rsvg-convert >/dev/null && command -v slurmctld >/dev/null && command -v chromium >/dev/null && [ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] && [ -x target/py-venv/bin/maturin ] || scripts/setup.sh

phase "build: every test target and binary, in the ci profile"
cargo test --workspace --profile ci --no-run --quiet
cargo build --profile ci --quiet -p mc-shard -p mc-merge -p truss-cli -p truss-mc
BIN="$REPO/target/ci"
export TRUSS_MC_BIN_DIR="$BIN" MC_SHARD="$BIN/mc-shard" MC_MERGE="$BIN/mc-merge" TRUSS_MC="$BIN/truss-mc"

# The Slurm check mostly waits on the scheduler (a minute, little of it CPU): it runs beside
# the test suite, its output kept in a log that is printed if it fails, and waited for below.
SLURM_LOG="$REPO/target/ci/slurm-e2e.log"
phase "Slurm end to end: started in the background beside the tests (log: ${SLURM_LOG#"$REPO"/})"
scripts/slurm/e2e-test.sh > "$SLURM_LOG" 2>&1 &
slurm=$!
slurm_started=$SECONDS
# Whatever fails first, the cluster the check started is stopped by the check itself: wait for it.
trap 'wait "$slurm" 2>/dev/null || true' EXIT

phase "cargo test --workspace, default and slow tiers"
cargo test --workspace --profile ci --quiet -- --include-ignored --skip readme_runs_as_pasted

phase "Python package: maturin develop --profile ci, then pytest"
(
    # shellcheck disable=SC1091
    . target/py-venv/bin/activate
    maturin develop --profile ci --quiet
    python -m pytest python/tests -q
)

phase "Slurm end to end: waiting for it"
if wait "$slurm"; then
    echo "test: Slurm end to end passed ($((SECONDS - slurm_started)) s since it started)" >&2
else
    cat "$SLURM_LOG" >&2
    echo "test: Slurm end to end FAILED (its log above)" >&2
    exit 1
fi

phase "smoke test of the main command"
scripts/smoke-test.sh

phase "report.html in a browser"
scripts/browser-test.sh

phase "the README as pasted, in a copy of the repository (its own release build and Python package)"
cargo test --profile ci --quiet -p pipeline-tests --test it readme_runs_as_pasted -- --ignored

phase "all passed"
