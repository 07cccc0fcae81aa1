//! The report directory (crate doc of `mc_merge::report_dir`): `report.json` is replaced
//! atomically, a directory of another job is refused with exit 5 and left untouched, our own
//! earlier plots are removed when the same job's report is written again, other files stay
//! (also files named like plots in a directory without a report),
//! and plot names stay unique after sanitising the case names. (More in `shared_dir`.)

use crate::common::{SynthCase, SynthJob};
use std::path::Path;
use std::process::{Command, Output};

/// A job of one 200-sample Rayleigh case per name (also the authorship tests').
pub(crate) fn job(seed: u64, names: &[&str]) -> SynthJob {
    SynthJob::new(
        seed,
        names
            .iter()
            .map(|n| SynthCase::rayleigh(n, 200, 3e-5, &[("stages", 5.0)]))
            .collect(),
    )
}

/// mc-merge of `shards` into `out` with few replicates, and `extra` (also the authorship
/// tests').
pub(crate) fn merge(shards: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mc-merge"))
        .arg(shards)
        .args(["--replicates", "50", "--gof-replicates", "19", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// The merge succeeded (exit 0); else its stderr.
fn assert_merged(o: &Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The directory's files but the hidden ones (mc-merge's manifest and the directory's lock
/// file: crate doc of `mc_merge::report_dir`).
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| !n.starts_with('.'))
        .collect();
    v.sort();
    v
}

#[test]
fn same_job_reuses_the_directory_and_clears_its_own_plots() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(1, &["a"]).write_split(shards.path(), 1);
    std::fs::write(out.path().join("notes.txt"), "mine").unwrap();
    let o = merge(shards.path(), out.path(), &[]);
    assert_merged(&o);
    assert!(listing(out.path()).contains(&"theta_p-a.svg".to_string()));
    // Again without plots: the earlier plots do not stay beside the new report.
    let o = merge(shards.path(), out.path(), &["--no-plots"]);
    assert_merged(&o);
    assert_eq!(
        listing(out.path()),
        ["notes.txt", "report.html", "report.json", "report.md"]
    );
}

/// Files named like our plots in a directory without a report are not ours: a diagnosis's
/// `theta_p-ecdf-before.svg` stays when a merge writes its first report there.
#[test]
fn plot_like_files_without_a_report_are_left_alone() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(4, &["a"]).write_split(shards.path(), 1);
    for name in ["theta_p-ecdf-before.svg", "qq-mine.png"] {
        std::fs::write(out.path().join(name), "not mc-merge's").unwrap();
    }
    let o = merge(shards.path(), out.path(), &[]);
    assert_merged(&o);
    let files = listing(out.path());
    for name in ["theta_p-ecdf-before.svg", "qq-mine.png", "theta_p-a.svg"] {
        assert!(
            files.contains(&name.to_string()),
            "{name} missing: {files:?}"
        );
    }
}

#[test]
fn another_jobs_directory_is_refused_and_left_untouched() {
    let (first, second) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let out = tempfile::tempdir().unwrap();
    job(1, &["a"]).write_split(first.path(), 1);
    let other = job(2, &["a"]);
    other.write_split(second.path(), 1);
    assert_eq!(merge(first.path(), out.path(), &[]).status.code(), Some(0));
    let before = listing(out.path());
    let report = std::fs::read(out.path().join("report.json")).unwrap();
    let o = merge(second.path(), out.path(), &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("report.json"), "{stderr}");
    assert!(stderr.contains(&other.job_id), "{stderr}");
    assert!(stderr.contains("another --out directory"), "{stderr}");
    assert_eq!(listing(out.path()), before);
    assert_eq!(
        std::fs::read(out.path().join("report.json")).unwrap(),
        report
    );
    // A report.json that mc-merge did not write is not ours to replace either.
    let foreign = tempfile::tempdir().unwrap();
    std::fs::write(foreign.path().join("report.json"), "{\"results\": []}").unwrap();
    let o = merge(second.path(), foreign.path(), &[]);
    assert_eq!(
        o.status.code(),
        Some(5),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(listing(foreign.path()), ["report.json"]);
}

#[test]
fn plot_names_stay_unique_after_sanitising() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(3, &["σ", "δ", "a/b", "a_b"]).write_split(shards.path(), 1);
    let o = merge(shards.path(), out.path(), &[]);
    assert_merged(&o);
    let histograms: Vec<String> = listing(out.path())
        .into_iter()
        .filter(|f| f.starts_with("theta_p-") && f.ends_with(".svg"))
        .collect();
    assert_eq!(
        histograms,
        [
            "theta_p-_~1.svg",
            "theta_p-_~2.svg",
            "theta_p-a_b.svg",
            "theta_p-a_b~3.svg"
        ]
    );
    // Each file shows its own case.
    for (file, case) in [("theta_p-_~1.svg", "σ"), ("theta_p-a_b~3.svg", "a/b")] {
        let svg = std::fs::read_to_string(out.path().join(file)).unwrap();
        assert!(
            svg.contains(&format!("{case} — distortion angle")),
            "{file}"
        );
    }
    // No temporary file is left behind.
    let all: Vec<String> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert!(!all.iter().any(|f| f.contains(".tmp-")), "{all:?}");
}
