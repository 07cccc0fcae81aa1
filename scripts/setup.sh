#!/usr/bin/env bash
# setup.sh: installs what truss-mc's tests and scripts need on a fresh Debian machine.
#
# Usage: scripts/setup.sh        (as root, or with sudo available)
#
# - Debian packages: munge, slurmctld, slurmd, slurm-client (the real single-node Slurm
#   cluster of the end-to-end test, see scripts/slurm/README.md) and librsvg2-bin
#   (rsvg-convert, which the tests use to render the SVG plots to PNG), fonts-dejavu-core
#   (the font mc-merge's own PNG rendering and rsvg-convert draw text with), and chromium
#   (the headless browser that opens mc-merge's report.html in scripts/browser-test.sh).
# - A Python virtual environment for the Python package's tests, target/py-venv (under the
#   git-ignored target/), with the pinned tools of python/requirements-test.txt (maturin,
#   pytest, numpy) from PyPI; then, if PyPI has a wheel for this Python, OpenTURNS
#   (python/requirements-optional.txt), without which the example's test is skipped.
#   Debian's python3-venv is installed if python3 cannot make a virtual environment.
# - Nothing else: the Rust toolchain comes with the machine; crates come from crates.io
#   when cargo builds (Cargo.lock pins them).
# Idempotent: packages already installed are not fetched again.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(munge slurmctld slurmd slurm-client librsvg2-bin fonts-dejavu-core chromium)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    SUDO=""
    [[ $(id -u) -eq 0 ]] || SUDO="sudo"
    echo "setup: installing ${missing[*]}" >&2
    $SUDO apt-get update -q
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
else
    echo "setup: Debian packages present" >&2
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust (rustup) first" >&2; exit 1; }

VENV="$REPO/target/py-venv"
if [[ ! -x "$VENV/bin/python" ]]; then
    if ! python3 -m venv "$VENV" 2>/dev/null; then
        echo "setup: installing python3-venv" >&2
        rm -rf "$VENV"
        SUDO=""
        [[ $(id -u) -eq 0 ]] || SUDO="sudo"
        $SUDO apt-get update -q
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends python3-venv
        python3 -m venv "$VENV"
    fi
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$REPO/python/requirements-test.txt"
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: \
    -r "$REPO/python/requirements-optional.txt" \
    || echo "setup: OpenTURNS has no wheel for this Python; the example's test will be skipped" >&2
echo "setup: Python environment in $VENV" >&2
echo "setup: done" >&2
