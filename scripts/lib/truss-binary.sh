# truss-binary.sh: the start the diagnosis scripts share; sourced, not run
# (`source "$(dirname "${BASH_SOURCE[0]}")/lib/truss-binary.sh" "$@"`).
# Sets REPO (the repository root) and WORK (the script's first argument, or a new mktemp
# directory; created), changes into REPO, and sets T to the `truss` binary to run: $TRUSS
# when given, else the release build, built now; and SAMPLES_OPTION, the array of
# `truss diagnose` arguments that $SAMPLES asks for (`--samples $SAMPLES`, or none when
# SAMPLES is unset or empty). Exits 4 if REPO cannot be entered, 1 if the build fails.
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
WORK="${1:-$(mktemp -d)}"
mkdir -p "$WORK"
cd "$REPO" || exit 4
if [[ -n "${TRUSS:-}" ]]; then
  T="$TRUSS"
else
  cargo build --release -p truss-cli --quiet || exit 1
  T="${CARGO_TARGET_DIR:-$REPO/target}/release/truss"
fi
SAMPLES_OPTION=()
if [[ -n "${SAMPLES:-}" ]]; then
  SAMPLES_OPTION=(--samples "$SAMPLES")
fi
