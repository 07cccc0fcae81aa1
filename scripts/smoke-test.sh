#!/usr/bin/env bash
# smoke-test.sh: the README's main command (truss-mc run-all) on a small job, checked end
# to end: shards written, merged, report.json, report.md and report.html present (the page
# in a browser: scripts/browser-test.sh), every SVG plot renders to a PNG
# (rsvg-convert parses and rasterises it; a malformed SVG fails), and mc-merge wrote its own
# PNG beside each SVG, at twice its size. This is where CI checks those PNGs: its default
# tests run without the png feature (see scripts/test.sh).
#
# Usage: scripts/smoke-test.sh     (needs target/release/truss-mc and rsvg-convert)
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
TRUSS_MC="${TRUSS_MC:-$REPO/target/release/truss-mc}"
WORK="$(mktemp -d /tmp/truss-mc-smoke.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT

cat > "$WORK/job.json" <<'JOB'
{
  "model": {"prism": {"stages": 5}},
  "seed": 1,
  "cases": [
    {"name": "sigma-0.0033", "samples": 2000, "length_errors": {"batten": {"normal": {"sigma": 0.0033}}, "longeron": {"normal": {"sigma": 0.0033}}}},
    {"name": "sigma-0.0067", "samples": 2000, "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}}}
  ]
}
JOB
"$TRUSS_MC" run-all --job "$WORK/job.json" --out "$WORK/run" --shards 4 --quiet > "$WORK/out.txt"
grep -q "run-all: 4000 samples in 4 shards" "$WORK/out.txt" || { cat "$WORK/out.txt"; exit 1; }
for report in report.json report.md report.html; do
    [[ -s "$WORK/run/report/$report" ]] || { echo "smoke: no $report" >&2; exit 1; }
done
n=0
mkdir "$WORK/check"
for svg in "$WORK"/run/report/*.svg; do
    name="$(basename "${svg%.svg}")"
    rsvg-convert -o "$WORK/check/$name.png" "$svg"
    [[ -s "$WORK/check/$name.png" ]] || { echo "smoke: $svg did not render" >&2; exit 1; }
    # mc-merge's own PNG (resvg) beside it.
    png="${svg%.svg}.png"
    [[ "$(head -c 4 "$png" | tail -c 3)" == PNG ]] || { echo "smoke: no PNG for $svg" >&2; exit 1; }
    # At twice the SVG's size: the PNG's width and height (IHDR, bytes 16-23, big-endian)
    # against the SVG's.
    read -r pw ph < <(od -An -j16 -N8 -tu1 "$png" | awk '{print $1*16777216+$2*65536+$3*256+$4, $5*16777216+$6*65536+$7*256+$8}')
    read -r sw sh < <(head -c 200 "$svg" | sed -n 's/^<svg width="\([0-9]*\)" height="\([0-9]*\)".*/\1 \2/p')
    [[ "$pw $ph" == "$((2 * sw)) $((2 * sh))" ]] || { echo "smoke: $png is ${pw}x$ph, the SVG ${sw}x$sh" >&2; exit 1; }
    n=$((n + 1))
done
# 2 cases x 5 plots + the σ sweep.
((n >= 11)) || { echo "smoke: expected at least 11 plots, found $n" >&2; exit 1; }
echo "smoke: run-all, merge and $n plots rendered (SVG by rsvg-convert, PNG by mc-merge)" >&2
