#!/usr/bin/env bash
# setup.sh: installs what truss-mc's tests and scripts need on a fresh Debian machine.
#
# Usage: scripts/setup.sh        (as root, or with sudo available)
#
# - Debian packages: munge, slurmctld, slurmd, slurm-client (the real single-node Slurm
#   cluster of the end-to-end test, see scripts/slurm/README.md) and librsvg2-bin
#   (rsvg-convert, which the tests use to render the SVG plots to PNG), and fonts-dejavu-core
#   (the font mc-merge's own PNG rendering and rsvg-convert draw text with).
# - Nothing else: the Rust toolchain comes with the machine; crates come from crates.io
#   when cargo builds (Cargo.lock pins them).
# Idempotent: packages already installed are not fetched again.
set -euo pipefail

packages=(munge slurmctld slurmd slurm-client librsvg2-bin fonts-dejavu-core)
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
echo "setup: done" >&2
