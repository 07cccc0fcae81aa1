//! The plots (crate doc of `mc_merge::plot`): every plot is written as SVG and PNG, the SVG
//! renders with an independent renderer (librsvg's `rsvg-convert`, as scripts/smoke-test.sh
//! does), the PNG is a PNG at twice the SVG's size, and the text follows the plots' rules
//! (real subscripts, no "1400.0" tick labels, angles in µrad and arcsec, no rad e-notation).
//! A θ_P tail beyond the histogram's axis is counted in its legend.

use crate::common::{SynthCase, SynthJob};
use mc_merge::plot::{CASE_PLOTS, JOB_PLOTS};
use shard_record::ShardRange;
use std::path::Path;
use std::process::Command;

/// The `width` and `height` attributes of an SVG's root element.
fn svg_size(svg: &str) -> (u32, u32) {
    let attr = |name: &str| -> u32 {
        let at = svg.find(&format!("{name}=\"")).expect(name) + name.len() + 2;
        svg[at..at + svg[at..].find('"').unwrap()].parse().unwrap()
    };
    (attr("width"), attr("height"))
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(png: &[u8]) -> (u32, u32) {
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(&png[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes(b.try_into().unwrap());
    (be(&png[16..20]), be(&png[20..24]))
}

/// Checks every plot of a report directory whose cases have the plot stems `stems`.
pub fn check_every_plot(dir: &Path, stems: &[&str], sigma: bool, stages: bool) {
    let mut names: Vec<String> = stems
        .iter()
        .flat_map(|s| CASE_PLOTS.map(|p| format!("{p}-{s}")))
        .collect();
    for (name, wanted) in JOB_PLOTS.iter().zip([sigma, stages]) {
        if wanted {
            names.push(name.to_string());
        } else {
            assert!(!dir.join(format!("{name}.svg")).exists(), "{name}");
        }
    }
    let rendered = tempfile::tempdir().unwrap();
    for name in &names {
        let path = dir.join(format!("{name}.svg"));
        let svg = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}.svg: {e}"));
        assert!(
            svg.starts_with("<svg") && svg.ends_with("</svg>\n"),
            "{name}"
        );
        // Text: subscripts are tspans, no marker or underscore left; ticks without ".0";
        // angles in µrad (and arcsec), never in rad.
        assert!(
            !svg.contains(['\u{E000}', '\u{E001}']),
            "{name}: subscript marker left"
        );
        assert!(
            !svg.contains("θ_") && !svg.contains("σ_"),
            "{name}: literal underscore"
        );
        assert!(svg.contains("<tspan dy="), "{name}: no subscript");
        assert!(!svg.contains(".0</text>"), "{name}: a label ends in .0");
        assert!(!svg.contains(" rad"), "{name}: an angle in rad");
        // An independent renderer reads it.
        let check = rendered.path().join(format!("{name}.png"));
        let status = Command::new("rsvg-convert")
            .arg("-o")
            .arg(&check)
            .arg(&path)
            .status()
            .expect("rsvg-convert (librsvg2-bin; scripts/setup.sh installs it)");
        assert!(status.success(), "{name}.svg does not render");
        assert!(std::fs::metadata(&check).unwrap().len() > 1000, "{name}");
        // Our PNG (feature png): twice the SVG's size.
        let png = dir.join(format!("{name}.png"));
        if cfg!(feature = "png") {
            let (w, h) = svg_size(&svg);
            let ours = std::fs::read(&png).expect("PNG beside the SVG");
            assert_eq!(png_size(&ours), (2 * w, 2 * h), "{name}.png");
        } else {
            assert!(!png.exists(), "{name}.png without the png feature");
        }
    }
}

/// One case of 6000 Rayleigh samples of which every 2000th (3 samples) is five times larger:
/// the histogram's axis stays at the bulk and its legend counts the 3 beyond it.
#[test]
fn histogram_counts_the_tail_beyond_its_axis() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let job = SynthJob::new(
        11,
        vec![SynthCase::rayleigh(
            "tail",
            6000,
            4e-5,
            &[("sigma", 0.0063)],
        )],
    );
    let range = ShardRange {
        start: 0,
        end: 6000,
    };
    let bytes = job.shard_bytes_with(range, |s| {
        if s.index % 2000 == 1999 {
            s.theta_p = s.theta_p.map(|t| 5.0 * t + 2e-4);
        }
    });
    SynthJob::write_bytes(shards.path(), &range.file_name(), &bytes);
    merge_into(shards.path(), out.path());
    let svg = std::fs::read_to_string(out.path().join("theta_p-tail.svg")).unwrap();
    assert!(
        svg.contains("3 of 6000 samples (0.05 %) lie beyond "),
        "no tail note in the legend"
    );
    check_every_plot(out.path(), &["tail"], false, false);
}

/// Without a tail the axis reaches the largest sample and nothing is said.
#[test]
fn histogram_axis_holds_every_sample_when_the_tail_is_short() {
    let mut v: Vec<f64> = (1..=1000).map(f64::from).collect();
    let (hi, beyond) = mc_merge::plot::axis_end(&v, 10.0);
    assert_eq!(beyond, 0);
    assert!(hi >= 1000.0, "{hi}");
    v.push(5000.0);
    let (hi, beyond) = mc_merge::plot::axis_end(&v, 10.0);
    assert_eq!(beyond, 1);
    assert!(hi < 5000.0 && hi > 999.0, "{hi}");
}

/// Runs `mc-merge` on `shards` into `out` with few replicates, quietly; panics unless it
/// exits 0 with nothing on stdout.
fn merge_into(shards: &Path, out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_mc-merge"))
        .arg(shards)
        .args(["-q", "--replicates", "50", "--gof-replicates", "19", "-o"])
        .arg(out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.stdout.is_empty(), "--quiet printed {:?}", o.stdout);
}

/// The decenter and despace plot of a case whose samples record them (synthetic: decenter
/// Rayleigh(1000 σ_t mm) = Rayleigh(40 µm), despace N(0, (28 µm)²)) under a budget: written
/// as SVG and PNG, rendering, its legend giving the report's fitted Rayleigh scale in µm and
/// the budget's limits, listed in report.md, report.html and the directory's manifest. A
/// case whose samples do not record them (as shards of numerics version 7 or earlier) gets
/// no such plot, and its other plots are written as before.
#[test]
fn decenter_and_despace_are_plotted_with_their_laws_and_the_budget() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let mut job = SynthJob::new(
        5,
        vec![
            SynthCase::rayleigh("placed", 3000, 4e-5, &[("sigma", 0.0063)]),
            SynthCase::rayleigh("old", 500, 4e-5, &[("sigma", 0.0033)]),
        ],
    );
    job.budget = Some(shard_record::Budget {
        percentile: 95.0,
        theta_p: None,
        decenter: Some(0.1),
        despace: Some(0.06),
    });
    let range = ShardRange {
        start: 0,
        end: 3500,
    };
    let bytes = job.shard_bytes_with(range, |s| {
        if s.case == "old" {
            (s.decenter_x, s.decenter_y, s.decenter, s.despace) = (None, None, None, None);
        }
    });
    SynthJob::write_bytes(shards.path(), &range.file_name(), &bytes);
    merge_into(shards.path(), out.path());
    check_every_plot(out.path(), &["placed"], true, false);

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("report.json")).unwrap())
            .unwrap();
    let sigma_um = report["cases"][0]["decenter"]["law"]["sigma"]["value"]
        .as_f64()
        .unwrap()
        * 1e3;
    assert!((sigma_um / 40.0 - 1.0).abs() < 0.05, "σ̂_d = {sigma_um} µm");
    let svg = std::fs::read_to_string(out.path().join("placement-placed.svg")).unwrap();
    let shown = truss_plot::style::number(truss_plot::style::round_sig(sigma_um, 4));
    assert!(
        svg.contains("left: Rayleigh fit, σ̂") && svg.contains(&format!("= {shown} µm")),
        "no Rayleigh fit of σ̂ = {shown} µm in the legend"
    );
    assert!(svg.contains("right: normal fit, mean "), "no normal fit");
    assert!(
        svg.contains("budget: decenter = 100 µm, |despace| = 60 µm"),
        "no budget limits in the legend"
    );
    // The histograms: Rice's 2·3000^(1/3) = 29 bars in each panel (the bars' fill, BAR),
    // and the legend's swatch.
    let bars = svg.matches(r##"fill="#96AFD7""##).count();
    assert_eq!(bars, 2 * 29 + 1, "bars drawn");

    // The case without decenter and despace: no plot, the others written.
    assert!(!out.path().join("placement-old.svg").exists());
    assert!(!out.path().join("placement-old.png").exists());
    assert!(out.path().join("theta_p-old.svg").exists());

    // Listed with the other plots.
    let md = std::fs::read_to_string(out.path().join("report.md")).unwrap();
    let html = std::fs::read_to_string(out.path().join("report.html")).unwrap();
    assert!(md.contains("placement-placed.svg"), "not in report.md");
    assert!(html.contains("placement-placed.svg"), "not in report.html");
    assert!(!md.contains("placement-old.svg") && !html.contains("placement-old"));
    let manifest = std::fs::read_to_string(out.path().join(".mc-merge.manifest")).unwrap();
    for ext in if cfg!(feature = "png") {
        &["svg", "png"][..]
    } else {
        &["svg"][..]
    } {
        assert!(
            manifest.contains(&format!("placement-placed.{ext}")),
            "placement-placed.{ext} not in the manifest"
        );
    }
}
