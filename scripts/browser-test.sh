#!/usr/bin/env bash
# browser-test.sh: mc-merge's report.html in a real browser, headless Chromium (Debian's
# package, installed by scripts/setup.sh). Without an argument it runs a small job with the
# release binaries (a σ pair, a case whose name is HTML's and Markdown's trouble, and a case
# with pin joints, whose stages float) and merges it; with REPORT_DIR it checks that report.
#
# Checked, with the page opened from disk as it is:
# - every image loads (complete, with a width: a truncated or malformed SVG does not), every
#   image has alternative text, one image per SVG that mc-merge's manifest lists;
# - nothing is fetched (no resource entry: no file, no network) and there is no script;
# - one h1, and every table has a caption;
# - the answer's allowable σ is on the first screen: in a 1280 x 900 frame, not scrolled, the
#   list item that starts "Allowable σ" lies between 0 and 900 px down, is laid out (width
#   and height above 0), is not hidden (visibility, display, opacity) and holds a σ in mm;
# - screenshots of the first screen (1280 x 900 px, what a reader sees on opening the page)
#   and of the page further down (1280 x 2400 px) are not blank: the standard deviation of
#   their luminance is at least 20 (of 255) and at least 1 % of their pixels are ink
#   (luminance below 200); a blank page gives about 7 and 0.2 %;
# - the page prints (to PDF, with its print style sheet).
#
# How: `chromium --headless --dump-dom` on a small check page written here, which holds the
# report in an iframe and, once it has loaded, writes what it finds into its own DOM. That
# needs only the browser (no chromedriver process, port or WebDriver client), leaves the
# report unmodified, and the load event of the check page waits for the iframe and its
# images. Local files may read each other only in that run (--allow-file-access-from-files).
# The screenshot's pixels are decoded by the browser too, from a data: URI into a canvas, so
# no image library is needed. Every run has a fresh profile; the flags suit a root user on a
# machine without network (no sandbox, no GPU, no background or component updates).
#
# Usage: scripts/browser-test.sh [REPORT_DIR]
#        (needs chromium and python3; without REPORT_DIR, target/release/mc-shard and
#        mc-merge, or the binaries MC_SHARD and MC_MERGE name; CHROMIUM=/path/to/chromium to
#        use another build)
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CHROMIUM="${CHROMIUM:-chromium}"
MC_SHARD="${MC_SHARD:-$REPO/target/release/mc-shard}"
MC_MERGE="${MC_MERGE:-$REPO/target/release/mc-merge}"
WORK="$(mktemp -d /tmp/truss-mc-browser.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
fail() { echo "browser-test: $*" >&2; exit 1; }
command -v "$CHROMIUM" >/dev/null || fail "no $CHROMIUM: run scripts/setup.sh"

if (($#)); then
    REPORT="$(cd "$1" && pwd)"
else
    cat > "$WORK/job.json" <<'JOB'
{
  "model": {"prism": {"stages": 5}},
  "seed": 3,
  "cases": [
    {"name": "sigma-0.0033", "samples": 400,
     "length_errors": {"batten": {"normal": {"sigma": 0.0033}}, "longeron": {"normal": {"sigma": 0.0033}}}},
    {"name": "σ <0.0067> & \"q\" 'b' #1 %20 *x* [l](y)", "samples": 400,
     "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}}},
    {"name": "backlash-0.0067", "samples": 200, "model": {"prism": {"stages": 5, "backlash": true}},
     "backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}},
     "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}}}
  ]
}
JOB
    "$MC_SHARD" run --job "$WORK/job.json" --out "$WORK/run" --quiet > "$WORK/run.log" 2>&1 \
        || { cat "$WORK/run.log" >&2; fail "mc-shard run failed"; }
    "$MC_MERGE" "$WORK/run" --out "$WORK/report" --quiet
    REPORT="$WORK/report"
fi
[[ -s "$REPORT/report.html" ]] || fail "no report.html in $REPORT"
URL="$(python3 -c 'import pathlib, sys; print(pathlib.Path(sys.argv[1]).as_uri())' "$REPORT/report.html")"
svgs="$(grep -c '\.svg$' "$REPORT/.mc-merge.manifest" || true)"

# browser NAME ARGS...: one headless Chromium run with a fresh profile; its log in WORK.
browser() {
    local name="$1"
    shift
    timeout 180 "$CHROMIUM" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --user-data-dir="$(mktemp -d "$WORK/profile.XXXXXX")" "$@" 2> "$WORK/$name.log" \
        || { tail -20 "$WORK/$name.log" >&2; fail "chromium failed ($name)"; }
}

browser first --hide-scrollbars --window-size=1280,900 --screenshot="$WORK/first.png" "$URL"
[[ -s "$WORK/first.png" ]] || fail "no screenshot of the first screen"
browser screenshot --hide-scrollbars --window-size=1280,2400 --screenshot="$WORK/shot.png" "$URL"
[[ -s "$WORK/shot.png" ]] || fail "no screenshot"
browser print --no-pdf-header-footer --print-to-pdf="$WORK/report.pdf" "$URL"
[[ "$(head -c 5 "$WORK/report.pdf")" == "%PDF-" ]] || fail "the page did not print to PDF"
pages="$(grep -ac '/Type /Page\($\|[^s]\)' "$WORK/report.pdf" || true)"
((pages >= 1)) || fail "the PDF has no page"

{
    cat <<HTML
<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>check</title></head>
<body>
<pre id="images">not loaded</pre>
<pre id="pixels">not loaded</pre>
<pre id="first-pixels">not loaded</pre>
<iframe id="page" src="$URL" width="1280" height="900"></iframe>
<img id="shot" alt="screenshot" src="data:image/png;base64,
HTML
    base64 -w0 "$WORK/shot.png"
    cat <<'HTML'
">
<img id="first" alt="first screen" src="data:image/png;base64,
HTML
    base64 -w0 "$WORK/first.png"
    cat <<'HTML'
">
<script>
document.getElementById('page').addEventListener('load', function () {
  var out = document.getElementById('images');
  var d = this.contentDocument;
  if (!d) { out.textContent = 'IMAGES no access to the page'; return; }
  var imgs = Array.prototype.slice.call(d.images);
  var count = function (f) { return imgs.filter(f).length; };
  // The answer's allowable σ, where the page opens (1280 × 900, not scrolled): its bottom edge.
  var allowable = Array.prototype.slice.call(d.querySelectorAll('li')).filter(function (li) {
    return li.textContent.indexOf('Allowable σ') === 0;
  })[0];
  var box = allowable ? allowable.getBoundingClientRect() : null;
  var style = allowable ? d.defaultView.getComputedStyle(allowable) : null;
  var answerBottom = box ? Math.round(box.bottom) : 99999;
  var answerShown = box && box.top >= 0 && box.width > 0 && box.height > 0 &&
    style.visibility === 'visible' && style.display !== 'none' && parseFloat(style.opacity) > 0 &&
    /[0-9.]+e-?[0-9]+ mm/.test(allowable.textContent) ? 1 : 0;
  out.textContent = 'IMAGES images=' + imgs.length +
    ' loaded=' + count(function (i) { return i.complete && i.naturalWidth > 0; }) +
    ' noalt=' + count(function (i) { return !i.alt; }) +
    ' scripts=' + d.scripts.length +
    ' resources=' + d.defaultView.performance.getEntriesByType('resource').length +
    ' h1=' + d.querySelectorAll('h1').length +
    ' tables=' + d.querySelectorAll('table').length +
    ' captions=' + d.querySelectorAll('table > caption').length +
    ' answer_bottom=' + answerBottom + ' answer_shown=' + answerShown + ' end';
});
// The luminance statistics of a decoded screenshot, written into the <pre> of id `out`.
function pixels(id, out) {
  var img = document.getElementById(id);
  var c = document.createElement('canvas');
  c.width = img.naturalWidth;
  c.height = img.naturalHeight;
  var g = c.getContext('2d');
  g.drawImage(img, 0, 0);
  var p = g.getImageData(0, 0, c.width, c.height).data;
  var n = 0, sum = 0, sum2 = 0, ink = 0;
  for (var k = 0; k < p.length; k += 4) {
    var y = 0.2126 * p[k] + 0.7152 * p[k + 1] + 0.0722 * p[k + 2];
    n++; sum += y; sum2 += y * y; if (y < 200) ink++;
  }
  var mean = sum / Math.max(n, 1);
  document.getElementById(out).textContent = 'PIXELS width=' + c.width +
    ' height=' + c.height + ' sd=' + Math.sqrt(Math.max(0, sum2 / Math.max(n, 1) - mean * mean)).toFixed(1) +
    ' ink_permille=' + Math.round(1000 * ink / Math.max(n, 1)) + ' end';
}
window.addEventListener('load', function () {
  pixels('shot', 'pixels');
  pixels('first', 'first-pixels');
});
</script>
</body></html>
HTML
} > "$WORK/check.html"
browser check --allow-file-access-from-files --dump-dom "file://$WORK/check.html" > "$WORK/dom.html"

# The two result lines, as the check page's script wrote them into its <pre> elements.
images="$(sed -n 's|.*<pre id="images">\([^<]*\)</pre>.*|\1|p' "$WORK/dom.html")"
pixels="$(sed -n 's|.*<pre id="pixels">\([^<]*\)</pre>.*|\1|p' "$WORK/dom.html")"
first="$(sed -n 's|.*<pre id="first-pixels">\([^<]*\)</pre>.*|\1|p' "$WORK/dom.html")"
[[ "$images" == *" end" ]] || fail "the page did not load in the check page: ${images:-nothing}"
[[ "$pixels" == *" end" ]] || fail "the screenshot did not decode: ${pixels:-nothing}"
[[ "$first" == *" end" ]] || fail "the first screen's screenshot did not decode: ${first:-nothing}"
# value KEY LINE: the number after KEY= in LINE.
value() { sed -n "s/.* $1=\([0-9.]*\).*/\1/p" <<< "$2"; }
n="$(value images "$images")"
((n == svgs)) || fail "$n images in the page, $svgs SVG plots in the manifest ($images)"
(($(value loaded "$images") == n)) || fail "not every image loads ($images)"
(($(value noalt "$images") == 0)) || fail "an image without alternative text ($images)"
(($(value scripts "$images") == 0)) || fail "the page has a script ($images)"
(($(value resources "$images") == 0)) || fail "the page fetched something ($images)"
(($(value h1 "$images") == 1)) || fail "not one h1 ($images)"
tables="$(value tables "$images")"
((tables > 0 && $(value captions "$images") == tables)) || fail "a table without a caption ($images)"
answer_bottom="$(value answer_bottom "$images")"
((answer_bottom > 0 && answer_bottom <= 900)) \
    || fail "the allowable σ is not on the first screen at 1280 × 900 (its bottom at ${answer_bottom} px; $images)"
(($(value answer_shown "$images") == 1)) \
    || fail "the allowable σ is on the first screen but not shown: hidden, empty or without a σ in mm ($images)"
[[ "$pixels" == *"width=1280 height=2400"* ]] || fail "screenshot of the wrong size ($pixels)"
sd="$(value sd "$pixels")"
ink="$(value ink_permille "$pixels")"
((${sd%.*} >= 20 && ink >= 10)) || fail "the screenshot is blank ($pixels)"
[[ "$first" == *"width=1280 height=900"* ]] || fail "first-screen screenshot of the wrong size ($first)"
first_sd="$(value sd "$first")"
first_ink="$(value ink_permille "$first")"
((${first_sd%.*} >= 20 && first_ink >= 10)) || fail "the first screen is blank ($first)"
echo "browser-test: report.html in $("$CHROMIUM" --version 2>/dev/null | head -1): $n of $n images loaded, $tables tables, nothing fetched, no script; the allowable σ shown, ending $answer_bottom px down the first screen (900), whose screenshot has sd $first_sd, ink ${first_ink} ‰; the page's sd $sd, ink ${ink} ‰; printed $pages pages" >&2
