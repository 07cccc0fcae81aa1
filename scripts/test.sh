#!/usr/bin/env bash
# test.sh: the project's test command (the README's, and what CI runs).
#
# Usage: scripts/test.sh           (scripts/test.sh --help prints this)
#
# Everything is compiled once, into target/ci: the release profile with debug assertions and
# overflow checks on (CARGO_PROFILE_RELEASE_DEBUG_ASSERTIONS, _OVERFLOW_CHECKS), so the tests
# catch what a debug build catches, and the workspace's own crates compiled through
# clippy-driver (RUSTC_WORKSPACE_WRAPPER, with clippy's -D warnings: the lints are checked by
# the same compilation, as `cargo clippy --all-targets -- -D warnings` checks them). Every
# step below runs what that one build made.
# 1. Build: every target of the workspace (tests, benchmarks and examples included, as
#    clippy's --all-targets) and the binaries, clippy's lints failing it on any warning; then
#    `cargo doc` with rustdoc's -D warnings (its dependencies checked once, its build scripts
#    and procedural macros those of this build).
# 2. The tests: unit, verification, property and CLI tests of every crate and the cross-crate
#    pipeline (tests/), and in the same run the slow statistical checks that a plain
#    `cargo test` ignores, by cargo-nextest (each test its own process, both cores busy, the
#    longest first: .config/nextest.toml), step 5 among them; where cargo-nextest is not
#    installed, `cargo test --workspace --release -- --include-ignored`, then step 5. No
#    crate has doc tests (tests/tests/it/doc_examples.rs keeps it so; each library sets
#    doctest = false).
# 3. The Python package: built into target/py-venv with `maturin develop --release` (the
#    feature unifier crates/workspace-hack gives its dependencies the binaries' features, so
#    only PyO3 and the extension are compiled) and its pytest tests, which compare its
#    numbers with the binaries' bytes.
# 4. The end-to-end checks with real parts, on target/ci's binaries:
#    - scripts/slurm/e2e-test.sh: a real single-node Slurm cluster (started and stopped
#      here): an 8-task job array with a dependent merge, and a cancelled task resubmitted
#      (started beside step 2, since it mostly waits on the scheduler; its log is printed
#      if it fails; beside the docs too it slowed them from 60 to 139 s);
#    - scripts/smoke-test.sh: the README's main command on a small job, and its SVG plots
#      rendered to PNG with rsvg-convert, and mc-merge's own PNGs checked;
#    - scripts/browser-test.sh: mc-merge's report.html opened in headless Chromium: every
#      image loads, nothing is fetched, the answer is on the first screen at 1280 x 900, a
#      screenshot is not blank, the page prints.
# 5. The README as pasted (tests/tests/it/readme.rs, readme_runs_as_pasted): every ```sh and
#    ```python block of README.md, in order, in a clean shell in a copy of the repository
#    (target/readme-test/clone), with the paper's job cut to 2,000 samples a case. The copy's
#    target/release starts as a copy of this build's (target/ci/release) and its shell gets
#    this build's settings, so the README's `cargo build --release` finds it built and its
#    `pip install .` compiles only PyO3 and the extension; then its own virtual environment
#    and `pip install .` (maturin and NumPy, and pandas for its snippet, from PyPI), the
#    Monte Carlo, the merge, the diagnosis, the tolerance study and the browser check of the
#    quick start's report.
# Installs first, when something is missing, by scripts/setup.sh (as root or with sudo):
# Debian's slurmctld, slurmd, slurm-client, munge, librsvg2-bin, fonts-dejavu-core and
# chromium through apt-get, and the Python virtual environment target/py-venv with maturin,
# pytest and numpy (and OpenTURNS where PyPI has a wheel) from PyPI; step 5 fetches maturin,
# NumPy and pandas from PyPI into the copy's own environment. Crates come from crates.io as
# cargo builds (Cargo.lock pins them).
# Takes about 14 minutes from a clean clone on 2 cores (831 s measured on a quiet machine: the
# build 396 s, the docs 60, the tests with the README as pasted 322 (the README 142 of it),
# Python 35, smoke and browser 12; the Slurm check beside them), and about 7 minutes once
# built (414 s measured, the tests 346 of it).
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

# The one build's settings, for every cargo below (and the README's copy, step 5).
export CARGO_TARGET_DIR="$REPO/target/ci"
export CARGO_PROFILE_RELEASE_DEBUG_ASSERTIONS=true CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS=true
# No line tables (the release profile's "line-tables-only"): a failing test still names its
# file and line (the panic's location), only a backtrace's frames lose theirs.
export CARGO_PROFILE_RELEASE_DEBUG=false
# PyO3's build script looks for Python on PATH unless told, and reruns when PATH changes; the
# README's clean shell has another PATH, so the interpreter is named here, for both.
PYO3_PYTHON="$(python3 -c 'import sys; print(sys.executable)')"
export PYO3_PYTHON
clippy_driver="$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver)" || {
    echo "test.sh: no clippy-driver: install clippy (rustup component add clippy)" >&2
    exit 1
}
export RUSTC_WORKSPACE_WRAPPER="$clippy_driver"
# cargo-clippy's way of passing `-- -D warnings` to clippy-driver.
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"

phase "build: every target and binary, clippy's lints with it (-D warnings)"
cargo test --workspace --all-targets --release --no-run --quiet
cargo build --release --quiet -p mc-shard -p mc-merge -p truss-cli -p truss-mc
BIN="$CARGO_TARGET_DIR/release"
export TRUSS_MC_BIN_DIR="$BIN" MC_SHARD="$BIN/mc-shard" MC_MERGE="$BIN/mc-merge" TRUSS_MC="$BIN/truss-mc"

phase "cargo doc (rustdoc -D warnings)"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release --quiet

# The Slurm check mostly waits on the scheduler (a minute, little of it CPU): it runs beside
# the test suite, its output kept in a log that is printed if it fails, and
# waited for below.
SLURM_LOG="$CARGO_TARGET_DIR/slurm-e2e.log"
phase "Slurm end to end: started in the background beside the tests (log: ${SLURM_LOG#"$REPO"/})"
scripts/slurm/e2e-test.sh > "$SLURM_LOG" 2>&1 &
slurm=$!
slurm_started=$SECONDS
# Whatever fails first, the cluster the check started is stopped by the check itself: wait for it.
trap 'wait "$slurm" 2>/dev/null || true' EXIT

if command -v cargo-nextest >/dev/null; then
    phase "tests, default and slow tiers, and the README as pasted (cargo nextest)"
    TRUSS_README_BUILD="$BIN" cargo nextest run --workspace --release --profile ci \
        --run-ignored all --no-fail-fast --hide-progress-bar
else
    phase "tests, default and slow tiers (cargo test: no cargo-nextest here)"
    cargo test --workspace --release --quiet -- --include-ignored --skip readme_runs_as_pasted
    readme=1
fi

phase "Python package: maturin develop --release, then pytest"
(
    # shellcheck disable=SC1091
    . target/py-venv/bin/activate
    maturin develop --release --quiet
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

if [[ -n "${readme:-}" ]]; then
    phase "the README as pasted, in a copy of the repository (its target/release a copy of this build's)"
    TRUSS_README_BUILD="$BIN" cargo test --release --quiet -p pipeline-tests --test it readme_runs_as_pasted -- --ignored
fi

phase "all passed"
