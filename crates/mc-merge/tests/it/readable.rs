//! The readable reports (crate doc of `mc_merge::readable`): `report.md` and `report.html`
//! are written by every merge with a report directory, hold every section and every case
//! with numbers equal to `report.json`'s, link or embed exactly the plots written, escape
//! case names, print no NaN, do not depend on the split, and follow the report directory's
//! rules (manifest, no link followed). The page in a real browser is checked by
//! scripts/browser-test.sh.

use crate::common::{SynthCase, SynthJob};
use mc_merge::readable::{HTML_FILE, MARKDOWN_FILE};
use std::collections::BTreeSet;
use std::path::Path;

/// A case name that is Markdown, HTML and a file name's trouble at once.
const HOSTILE: &str = "<script>alert(\"x\")</script> | *a* [b](c) & 'q' $x$ `t`";

/// A σ-series (one case with the hostile name, floating stages and loose joints) and a
/// stages series whose second case has failed samples.
fn job() -> SynthJob {
    let mut hostile = SynthCase::rayleigh(HOSTILE, 300, 4e-5, &[("sigma", 0.008), ("stages", 5.0)]);
    hostile.floating_every = Some(3);
    hostile.loose = true;
    let mut failing = SynthCase::rayleigh(
        "stages-10",
        300,
        2.5e-5,
        &[("sigma", 0.002), ("stages", 10.0)],
    );
    failing.fail_every = Some(50);
    SynthJob::new(
        7,
        vec![
            SynthCase::rayleigh(
                "sigma-0.002",
                300,
                1e-5,
                &[("sigma", 0.002), ("stages", 5.0)],
            ),
            SynthCase::rayleigh(
                "sigma-0.004",
                300,
                2e-5,
                &[("sigma", 0.004), ("stages", 5.0)],
            ),
            hostile,
            failing,
        ],
    )
}

fn options(shards: &Path, out: &Path, plots: bool) -> mc_merge::Options {
    mc_merge::Options {
        paths: vec![shards.to_path_buf()],
        out: Some(out.to_path_buf()),
        plots,
        progress: false,
        settings: mc_merge::Settings {
            replicates: 100,
            gof_replicates: 19,
            allow_failed: true,
            ..Default::default()
        },
    }
}

/// Merges `job` split in `k` into a new report directory; returns it and the report.
fn merged(job: &SynthJob, k: u64, plots: bool) -> (tempfile::TempDir, serde_json::Value) {
    let shards = tempfile::tempdir().unwrap();
    job.write_split(shards.path(), k);
    let out = tempfile::tempdir().unwrap();
    mc_merge::run(&options(shards.path(), out.path(), plots), &mut Vec::new()).unwrap();
    let report =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();
    (out, report)
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap()
}

/// The files of `dir` ending in `.ext`.
fn files_with(dir: &Path, ext: &str) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(&format!(".{ext}")))
        .collect()
}

/// Words a number that is not one would print as.
fn assert_no_nan(text: &str, what: &str) {
    for word in text.split(|c: char| !c.is_ascii_alphanumeric()) {
        assert!(
            !["NaN", "nan", "inf", "Inf", "infinity", "Infinity"].contains(&word),
            "{what}: {word}"
        );
    }
}

/// Each case's θ_P95 as the reports write it (rad, four significant digits).
fn p95s(report: &serde_json::Value) -> Vec<String> {
    report["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| format!("{:.3e}", p95(c)))
        .collect()
}

/// A case's θ_P95 in `report.json` (rad).
pub(crate) fn p95(case: &serde_json::Value) -> f64 {
    case["percentiles"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["percentile"] == 95.0)
        .unwrap()["value"]
        .as_f64()
        .unwrap()
}

/// The destinations of the Markdown's links and images.
fn md_links(md: &str) -> Vec<String> {
    md.match_indices("](")
        .filter(|(at, _)| !md[..*at].ends_with('\\'))
        .map(|(at, _)| {
            let rest = &md[at + 2..];
            rest[..rest.find(')').unwrap()].to_string()
        })
        .collect()
}

/// One merge with plots (drawing them, PNGs included, is most of the time), both files
/// checked.
#[test]
fn the_reports_hold_every_case_and_plot_escaped() {
    let (out, report) = merged(&job(), 2, true);
    check_markdown(out.path(), &report);
    check_page(out.path(), &report);
}

fn check_markdown(out: &Path, report: &serde_json::Value) {
    let md = read(out, MARKDOWN_FILE);
    for heading in [
        "# Distortion angle θ_P: Monte Carlo report\n",
        "\n## The run\n",
        "\n## Summary at the 95th percentile\n",
        "\n## Percentiles of θ_P\n",
        "\n## The Rayleigh law\n",
        "\n## Floating stages and loose joints\n",
        "\n## Caveats\n",
        "\n## Sweeps over σ and the allowable σ\n",
        "\n## Sweeps over the number of stages\n",
        "\n## Plots of each case\n",
        "\n## Definitions\n",
    ] {
        assert!(md.contains(heading), "{heading:?} missing");
    }
    assert!(md.contains(report["job_id"].as_str().unwrap()));
    assert!(
        md.contains("Shards written by: mc-shard 0.1.0 (shard format 1)."),
        "{md}"
    );
    assert!(
        md.contains("Failed samples: 6, excluded from every figure"),
        "{md}"
    );
    // Every case, each percentile in the full table, with report.json's numbers.
    let escaped = mc_merge::readable::markdown::escape(HOSTILE);
    let names = ["sigma-0.002", "sigma-0.004", &escaped, "stages-10"];
    for name in names {
        let rows = md
            .lines()
            .filter(|l| l.starts_with(&format!("| {name} | ")))
            .count();
        // Summary (1), percentiles (4), Rayleigh (1); the σ-series and floating tables.
        assert!(rows >= 6, "{name}: {rows} rows");
    }
    for p in p95s(report) {
        assert!(md.contains(&p), "{p}");
    }
    // The target as it was set (9.69e-5 rad), the same words wherever it is named.
    assert!(
        md.contains("Allowable σ for θ_P95 ≤ 9.69e-5 rad (19.99″)"),
        "{md}"
    );
    assert!(md.contains("Target: θ_P95 ≤ 9.69e-5 rad (19.99″)."), "{md}");
    assert!(md.contains("floating stages in 100 of 300 samples"), "{md}");
    // The hostile name never opens markup: no raw tag, link or code span of it.
    assert!(!md.contains("<script>") && !md.contains("[b](c)"));
    assert!(md.contains("\\<script\\>") && md.contains("[b\\](c)"));
    // Every link is an anchor or a file written beside it, and every plot is linked.
    let links = md_links(&md);
    for l in &links {
        if let Some(anchor) = l.strip_prefix('#') {
            assert!(!anchor.is_empty());
        } else {
            assert!(out.join(l).is_file(), "{l}: no such file");
        }
    }
    let linked: BTreeSet<&str> = links.iter().map(String::as_str).collect();
    let svgs = files_with(out, "svg");
    assert_eq!(
        svgs.len(),
        4 * mc_merge::plot::CASE_PLOTS.len() + 2,
        "{svgs:?}"
    );
    for f in svgs.iter().chain(&files_with(out, "png")) {
        assert!(linked.contains(f.as_str()), "{f} not linked");
    }
    assert_no_nan(&md, MARKDOWN_FILE);
}

/// The text of every `<tag …>` element's start tag in the page.
fn elements<'a>(html: &'a str, tag: &str) -> Vec<&'a str> {
    html.match_indices(&format!("<{tag}"))
        .map(|(at, _)| &html[at..at + html[at..].find('>').unwrap()])
        .filter(|e| e[tag.len() + 1..].starts_with([' ', '>']) || e.len() == tag.len() + 1)
        .collect()
}

/// The value of `name="…"` (or `name='…'`) in an element's text.
fn attribute<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    for quote in ['"', '\''] {
        if let Some(at) = element.find(&format!(" {name}={quote}")) {
            let rest = &element[at + name.len() + 3..];
            return Some(&rest[..rest.find(quote).unwrap()]);
        }
    }
    None
}

/// Percent-decodes a `data:` URI's body.
fn decode(body: &str) -> Vec<u8> {
    let b = body.as_bytes();
    let mut out = vec![];
    let mut k = 0;
    while k < b.len() {
        if b[k] == b'%' {
            out.push(u8::from_str_radix(&body[k + 1..k + 3], 16).unwrap());
            k += 3;
        } else {
            out.push(b[k]);
            k += 1;
        }
    }
    out
}

fn check_page(out: &Path, report: &serde_json::Value) {
    let html = read(out, HTML_FILE);
    assert!(html.starts_with("<!DOCTYPE html>\n<html lang=\"en\">\n"));
    assert!(html.contains("<meta charset=\"utf-8\">"));
    assert!(html.contains("default-src 'none'; img-src data:; style-src 'unsafe-inline'"));
    assert!(html.contains("<title>Distortion angle θ_P: Monte Carlo report</title>"));
    // No script, nothing fetched: every image inline, every link inside the page.
    assert!(!html.to_lowercase().contains("<script"), "a script element");
    assert!(elements(&html, "link").is_empty());
    let ids: BTreeSet<&str> = html
        .match_indices(" id=\"")
        .map(|(at, _)| {
            let rest = &html[at + 5..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect();
    for a in elements(&html, "a") {
        let href = attribute(a, "href").unwrap();
        let id = href
            .strip_prefix('#')
            .unwrap_or_else(|| panic!("{href}: not in the page"));
        assert!(ids.contains(id), "{href}: no such heading");
    }
    // One image per SVG written, each its file's bytes, with words for who cannot see it.
    let imgs = elements(&html, "img");
    let svgs = files_with(out, "svg");
    assert_eq!(imgs.len(), svgs.len());
    let mut embedded = BTreeSet::new();
    for img in &imgs {
        let alt = attribute(img, "alt").unwrap();
        assert!(alt.len() > 40, "{alt}");
        assert!(attribute(img, "width").is_some() && attribute(img, "height").is_some());
        let body = attribute(img, "src")
            .unwrap()
            .strip_prefix("data:image/svg+xml,")
            .unwrap();
        embedded.insert(decode(body));
    }
    let on_disk: BTreeSet<Vec<u8>> = svgs
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    assert_eq!(embedded, on_disk);
    // Headings in order: one h1, no h3 before an h2.
    assert_eq!(elements(&html, "h1").len(), 1);
    assert!(html.find("<h2").unwrap() < html.find("<h3").unwrap());
    // Every table has a caption, column headers and row headers.
    for table in html.split("<table>").skip(1) {
        let table = &table[..table.find("</table>").unwrap()];
        assert!(table.starts_with("\n<caption>"), "{table}");
        assert!(table.contains("<th scope=\"col\">"));
        let body = &table[table.find("<tbody>").unwrap()..];
        for row in body.split("<tr>").skip(1) {
            assert!(row.starts_with("<th scope=\"row\">"), "{row}");
        }
    }
    // The hostile name, escaped wherever it appears.
    assert!(html.contains(
        "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; | *a* [b](c) &amp; &#39;q&#39; $x$ `t`"
    ));
    for p in p95s(report) {
        assert!(html.contains(&p), "{p}");
    }
    assert!(html.contains("θ<sub>P95</sub>"));
    assert_no_nan(&html.replace(|c: char| !c.is_ascii(), " "), HTML_FILE);
}

/// Like report.json, the readable reports do not depend on how the job was split (the plots
/// they embed are the files, checked above).
#[test]
fn the_readable_reports_do_not_depend_on_the_split() {
    let job = job();
    let (one, _) = merged(&job, 1, false);
    let (three, _) = merged(&job, 3, false);
    for name in [MARKDOWN_FILE, HTML_FILE] {
        assert!(read(one.path(), name) == read(three.path(), name), "{name}");
    }
}

/// Without plots the reports are still written and say so; the manifest lists them, so a
/// rerun replaces them and removes only what mc-merge wrote.
#[test]
fn without_plots_the_reports_are_written_and_listed() {
    let job = job();
    let (out, _) = merged(&job, 1, false);
    let md = read(out.path(), MARKDOWN_FILE);
    assert!(md.contains("No plots were written with this report"));
    assert!(!md.contains(".svg"));
    assert!(elements(&read(out.path(), HTML_FILE), "img").is_empty());
    let manifest = read(out.path(), ".mc-merge.manifest");
    for name in [MARKDOWN_FILE, HTML_FILE] {
        let listed = |l: &str| l.starts_with("file ") && l.ends_with(&format!(" {name}"));
        assert!(manifest.lines().any(listed), "{manifest}");
    }
}
