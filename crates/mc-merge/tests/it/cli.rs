//! The `mc-merge` binary end to end: verification failures and their exit codes and messages,
//! tolerated inputs (byte-identical duplicates, agreeing overlaps, `--allow-partial`,
//! `--allow-failed`), degenerate cases, and the invariants of the report (split, file order,
//! threads; no NaN).
//!
//! Source of the contract: the crate doc of `mc-merge` (exit codes, verification rules) and the
//! crate doc of `shard-record` (file format). Shards are synthetic (see `common`), written with
//! `shard_record`'s own types so that they verify by construction unless a test breaks them.

use crate::common::{SynthCase, SynthJob};
use serde_json::Value;
use shard_record::ShardRange;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_mc-merge");

/// A small job: a σ-series of two cases and a stages case, 600 samples each.
fn job() -> SynthJob {
    SynthJob::new(
        7,
        vec![
            SynthCase::rayleigh("s1", 600, 2e-5, &[("sigma", 0.0033), ("stages", 5.0)]),
            SynthCase::rayleigh("s2", 600, 4e-5, &[("sigma", 0.0066), ("stages", 5.0)]),
            SynthCase::rayleigh("s3", 600, 3e-5, &[("sigma", 0.0066), ("stages", 2.0)]),
        ],
    )
}

struct Out {
    code: i32,
    stdout: String,
    stderr: String,
}

fn mc_merge(args: &[&str], paths: &[PathBuf]) -> Out {
    let mut cmd = Command::new(BIN);
    cmd.args(paths)
        .args(["--replicates", "200", "--gof-replicates", "99"]);
    cmd.args(args);
    let o = cmd.output().expect("run mc-merge");
    Out {
        code: o.status.code().expect("exit code"),
        stdout: String::from_utf8_lossy(&o.stdout).into(),
        stderr: String::from_utf8_lossy(&o.stderr).into(),
    }
}

fn report(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("report.json")).expect("report.json")
}

/// Every number is finite (serde_json cannot even parse NaN), and every null has a reason
/// beside it or in an enclosing object.
fn check_nulls_have_reasons(v: &Value, path: &str, reason_in_scope: bool) {
    match v {
        Value::Object(m) => {
            let here = reason_in_scope || m.get("reason").is_some_and(|r| r.is_string());
            for (k, x) in m {
                if x.is_null() {
                    assert!(here, "null without a reason at {path}.{k}");
                }
                check_nulls_have_reasons(x, &format!("{path}.{k}"), here);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                check_nulls_have_reasons(x, &format!("{path}[{i}]"), reason_in_scope);
            }
        }
        Value::Number(n) => assert!(n.as_f64().is_some_and(f64::is_finite), "{path}"),
        _ => {}
    }
}

#[test]
fn complete_job_reports_and_plots() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job().write_split(shards.path(), 3);
    let o = mc_merge(
        &["--out", out.path().to_str().unwrap()],
        &[shards.path().to_path_buf()],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stdout.contains("1800 of 1800 samples (complete)"),
        "{}",
        o.stdout
    );
    assert!(o.stdout.contains("Rayleigh law"), "{}", o.stdout);
    assert!(o.stdout.contains("allowable σ"), "{}", o.stdout);
    let text = report(out.path());
    let v: Value = serde_json::from_str(&text).unwrap();
    check_nulls_have_reasons(&v, "", false);
    assert_eq!(v["format"], "truss-mc-merge-report");
    assert_eq!(v["coverage"]["complete"], true);
    assert_eq!(v["cases"].as_array().unwrap().len(), 3);
    assert_eq!(v["sweep"]["sigma_series"].as_array().unwrap().len(), 1);
    assert_eq!(v["sweep"]["stages_series"].as_array().unwrap().len(), 1);
    assert!(
        v["definitions"]["percentile"]
            .as_str()
            .unwrap()
            .contains("Hyndman")
    );
    crate::plots::check_every_plot(out.path(), &["s1", "s2", "s3"], true, true);
    check_answer_last(&o.stdout, &v, out.path());
}

/// The report does not depend on how the job was split, on the order of the files, on the
/// thread count, nor on duplicate copies or agreeing overlaps.
#[test]
fn report_is_byte_identical_for_any_split_order_and_threads() {
    let j = job();
    let run = |paths: &[PathBuf], extra: &[&str]| {
        let out = tempfile::tempdir().unwrap();
        let mut args = vec!["--no-plots", "--out", out.path().to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = mc_merge(&args, paths);
        assert_eq!(o.code, 0, "{}", o.stderr);
        report(out.path())
    };
    let one = tempfile::tempdir().unwrap();
    let seven = tempfile::tempdir().unwrap();
    let mixed = tempfile::tempdir().unwrap();
    let single = j.write_split(one.path(), 1);
    let mut split = j.write_split(seven.path(), 7);
    let reference = run(&single, &[]);
    assert_eq!(run(&split, &[]), reference, "7 shards");
    split.reverse();
    split.swap(1, 4);
    assert_eq!(run(&split, &[]), reference, "shuffled order");
    assert_eq!(run(&split, &["--threads", "1"]), reference, "1 thread");
    assert_eq!(run(&split, &["--threads", "3"]), reference, "3 threads");
    // Overlapping ranges of different splits, plus a byte-identical copy of one file.
    let mut overlap = j.write_split(mixed.path(), 2);
    let other = mixed.path().join("other");
    std::fs::create_dir(&other).unwrap();
    overlap.extend(j.write_split(&other, 5));
    let copy = mixed.path().join("copy.jsonl");
    std::fs::copy(&overlap[0], &copy).unwrap();
    overlap.push(copy);
    assert_eq!(run(&overlap, &[]), reference, "overlaps and duplicates");
}

#[test]
fn missing_range_is_refused_naming_ranges_and_cases() {
    let dir = tempfile::tempdir().unwrap();
    let files = job().write_split(dir.path(), 6);
    std::fs::remove_file(&files[2]).unwrap(); // 600..900: case s2
    let o = mc_merge(&[], &[dir.path().to_path_buf()]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(o.stderr.contains("600..900 (case \"s2\""), "{}", o.stderr);
    assert!(o.stderr.contains("1500 of 1800"), "{}", o.stderr);
}

#[test]
fn allow_partial_marks_every_figure_with_coverage() {
    let dir = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let files = job().write_split(dir.path(), 4); // 0..450 | 450..900 | 900..1350 | 1350..1800
    std::fs::remove_file(&files[1]).unwrap();
    let o = mc_merge(
        &[
            "--allow-partial",
            "--no-plots",
            "--out",
            out.path().to_str().unwrap(),
        ],
        &[dir.path().to_path_buf()],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stdout.contains("PARTIAL"), "{}", o.stdout);
    let v: Value = serde_json::from_str(&report(out.path())).unwrap();
    check_nulls_have_reasons(&v, "", false);
    assert_eq!(v["coverage"]["complete"], false);
    assert_eq!(v["coverage"]["present"], 1350);
    assert_eq!(v["coverage"]["expected"], 1800);
    let s1 = &v["cases"][0];
    assert_eq!(s1["present"], 450);
    let partial = |x: &Value| {
        x["caveats"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c.as_str().unwrap().contains("450 of 600"))
    };
    assert!(partial(s1));
    assert!(s1["percentiles"].as_array().unwrap().iter().all(partial));
    assert!(partial(&s1["rayleigh"]) && partial(&s1["gof"]));
    // The complete case s3 carries no caveat.
    assert!(v["cases"][2]["caveats"].as_array().unwrap().is_empty());
    let series = &v["sweep"]["sigma_series"][0];
    assert!(!series["caveats"].as_array().unwrap().is_empty());
}

#[test]
fn disagreeing_overlap_names_both_files_and_first_index() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let a = SynthJob::write_bytes(
        dir.path(),
        "a.jsonl",
        &j.shard_bytes(ShardRange::new(0, 1000)),
    );
    // A valid shard of 500..1800 whose samples 700 and 750 differ from a's.
    let bytes = j.shard_bytes_with(ShardRange::new(500, 1800), |s| {
        if s.index == 700 || s.index == 750 {
            s.theta_p = Some(s.theta_p.unwrap() * 1.5);
        }
    });
    let b = SynthJob::write_bytes(dir.path(), "b.jsonl", &bytes);
    for order in [vec![a.clone(), b.clone()], vec![b.clone(), a.clone()]] {
        let o = mc_merge(&[], &order);
        assert_eq!(o.code, 6, "{}", o.stderr);
        assert!(o.stderr.contains("sample 700"), "{}", o.stderr);
        assert!(
            o.stderr.contains("a.jsonl") && o.stderr.contains("b.jsonl"),
            "{}",
            o.stderr
        );
    }
}

#[test]
fn same_range_with_different_bytes_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let range = ShardRange::new(0, 1800);
    let a = SynthJob::write_bytes(dir.path(), "a.jsonl", &j.shard_bytes(range));
    // Same samples, written with a different iteration count: not byte-identical.
    let b = SynthJob::write_bytes(
        dir.path(),
        "b.jsonl",
        &j.shard_bytes_with(range, |s| {
            if s.index == 5 {
                s.iterations += 1;
            }
        }),
    );
    let o = mc_merge(&[], &[a, b]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(
        o.stderr.contains("a.jsonl") && o.stderr.contains("b.jsonl"),
        "{}",
        o.stderr
    );
}

#[test]
fn torn_line_is_refused_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let bytes = j.shard_bytes(ShardRange::new(0, 1800));
    // Keep the header and 10 sample lines, then half of the 11th: line 12 is torn.
    let lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
    let mut torn = lines[..11].concat();
    torn.extend_from_slice(&lines[11][..20]);
    let p = SynthJob::write_bytes(dir.path(), "torn.jsonl", &torn);
    let o = mc_merge(&[], &[p]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(
        o.stderr.contains("torn.jsonl:12: torn line"),
        "{}",
        o.stderr
    );
}

#[test]
fn incomplete_and_corrupt_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let bytes = String::from_utf8(j.shard_bytes(ShardRange::new(0, 1800))).unwrap();
    let lines: Vec<&str> = bytes.split_inclusive('\n').collect();
    let inc = SynthJob::write_bytes(dir.path(), "inc.jsonl", lines[..50].concat().as_bytes());
    let o = mc_merge(&[], &[inc]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(o.stderr.contains("inc.jsonl: incomplete"), "{}", o.stderr);

    let mut bad = lines.clone();
    bad[30] = "{\"record\":\"sample\",\"index\":29,\n";
    let p = SynthJob::write_bytes(dir.path(), "bad.jsonl", bad.concat().as_bytes());
    let o = mc_merge(&[], &[p]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(o.stderr.contains("bad.jsonl:31:"), "{}", o.stderr);
}

#[test]
fn digest_mismatch_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let bytes = String::from_utf8(j.shard_bytes(ShardRange::new(0, 1800))).unwrap();
    // Change one number of sample 3 (line 5) without updating the closing digest.
    let mut lines: Vec<String> = bytes.split_inclusive('\n').map(String::from).collect();
    lines[4] = lines[4].replacen("\"iterations\":", "\"iterations\":1", 1);
    let p = SynthJob::write_bytes(dir.path(), "d.jsonl", lines.concat().as_bytes());
    let o = mc_merge(&[], &[p]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(
        o.stderr.contains("d.jsonl:1802:") && o.stderr.contains("sha256"),
        "{}",
        o.stderr
    );
}

#[test]
fn other_job_id_is_refused_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let j = job();
    let mut other = job();
    other.job_id = "ab".repeat(32);
    let a = SynthJob::write_bytes(
        dir.path(),
        "a.jsonl",
        &j.shard_bytes(ShardRange::new(0, 900)),
    );
    let b = SynthJob::write_bytes(
        dir.path(),
        "b.jsonl",
        &other.shard_bytes(ShardRange::new(900, 1800)),
    );
    let o = mc_merge(&[], &[a, b]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(o.stderr.contains("b.jsonl:1: job id abab"), "{}", o.stderr);
    assert!(o.stderr.contains("a.jsonl"), "{}", o.stderr);
}

#[test]
fn failed_samples_are_refused_by_default_and_counted_when_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let mut j = job();
    j.cases[1].fail_every = Some(100); // samples 99, 199, … of s2: global 699, 799, …
    j.write_split(dir.path(), 3);
    let o = mc_merge(&[], &[dir.path().to_path_buf()]);
    assert_eq!(o.code, 7, "{}", o.stderr);
    assert!(o.stderr.contains("6 failed samples"), "{}", o.stderr);
    assert!(
        o.stderr.contains("case \"s2\": 6 failed, indices 699, 799"),
        "{}",
        o.stderr
    );
    assert!(o.stderr.contains("Newton did not converge"), "{}", o.stderr);

    let o = mc_merge(
        &[
            "--allow-failed",
            "--no-plots",
            "--out",
            out.path().to_str().unwrap(),
        ],
        &[dir.path().to_path_buf()],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Value = serde_json::from_str(&report(out.path())).unwrap();
    let s2 = &v["cases"][1];
    assert_eq!(s2["failed"]["count"], 6);
    assert_eq!(s2["n"], 594);
    assert_eq!(s2["failed"]["ranges"][0], serde_json::json!([699, 700]));
    assert_eq!(s2["failed"]["reasons"].as_array().unwrap().len(), 5);
    let says = |x: &Value| {
        x["caveats"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c.as_str().unwrap().contains("6 failed samples excluded"))
    };
    assert!(says(s2) && says(&s2["percentiles"][2]) && says(&s2["gof"]));
    assert!(!says(&v["cases"][0]));
    assert_eq!(v["failed"]["total"], 6);
}

/// 0 or 1 sample in a case, or all-equal values: a message or an explicit null with a reason,
/// never a panic or a NaN.
#[test]
fn degenerate_cases_give_nulls_with_reasons() {
    let dir = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let j = SynthJob::new(
        3,
        vec![
            SynthCase::rayleigh("single", 1, 1e-5, &[("sigma", 0.01)]),
            SynthCase::rayleigh("zero", 3, 1e-5, &[]),
            SynthCase::rayleigh("empty", 0, 1e-5, &[]),
            SynthCase::rayleigh("pair", 2, 1e-5, &[("sigma", 0.02)]),
        ],
    );
    let range = ShardRange::new(0, j.samples());
    // The "zero" case has every angle exactly zero (a perfect truss).
    let bytes = j.shard_bytes_with(range, |s| {
        if s.case == "zero" {
            s.theta_p = Some(0.0);
            s.tan_theta_x = Some(0.0);
            s.tan_theta_y = Some(0.0);
        }
    });
    let p = SynthJob::write_bytes(dir.path(), "d.jsonl", &bytes);
    let o = mc_merge(&["--out", out.path().to_str().unwrap()], &[p]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Value = serde_json::from_str(&report(out.path())).unwrap();
    check_nulls_have_reasons(&v, "", false);
    let single = &v["cases"][0];
    assert!(
        single["percentiles"][0]["bca"]["reason"]
            .as_str()
            .unwrap()
            .contains("n = 1")
    );
    assert!(single["gof"]["reason"].is_string());
    let zero = &v["cases"][1];
    assert!(zero["gof"]["reason"].as_str().unwrap().contains("zero"));
    let empty = &v["cases"][2];
    assert_eq!(empty["n"], 0);
    assert!(empty["percentiles"][0]["value"].is_null());
}

#[test]
fn usage_and_io_errors_have_their_codes() {
    let o = mc_merge(&["--percentiles", "0,95"], &[PathBuf::from(".")]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    let o = mc_merge(&["--no-such-flag"], &[PathBuf::from(".")]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    let o = mc_merge(&[], &[PathBuf::from("/nonexistent/shards")]);
    assert_eq!(o.code, 4, "{}", o.stderr);
    let empty = tempfile::tempdir().unwrap();
    let o = mc_merge(&[], &[empty.path().to_path_buf()]);
    assert_eq!(o.code, 6, "{}", o.stderr);
    assert!(o.stderr.contains("no shard files"), "{}", o.stderr);
}

#[test]
fn help_documents_exit_codes() {
    let o = Command::new(BIN).arg("--help").output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    for code in [
        "0  ",
        "2  usage",
        "4  I/O",
        "5  a file in the way",
        "6  verification",
        "7  failed samples",
    ] {
        assert!(text.contains(code), "{code}: {text}");
    }
}

#[test]
fn quiet_short_flags_and_absurd_numbers() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job().write_split(shards.path(), 1);
    let o = mc_merge(
        &["-q", "--no-plots", "-o", out.path().to_str().unwrap()],
        &[shards.path().to_path_buf()],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert_eq!((o.stdout.as_str(), o.stderr.as_str()), ("", ""));
    assert!(out.path().join("report.json").exists());
    // 4e9 replicates aborted with an allocation failure; now a usage error naming the flag
    // and its cap, before any shard is read.
    let o = Command::new(BIN)
        .args(["/nonexistent", "--replicates", "4000000000"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--replicates 4000000000") && stderr.contains("100000"),
        "{stderr}"
    );
}

#[test]
fn completions_and_man_page() {
    for shell in ["bash", "zsh", "fish"] {
        let o = Command::new(BIN)
            .args(["completions", shell])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{shell}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.contains("mc-merge") && text.contains("replicates"),
            "{shell}"
        );
    }
    let o = Command::new(BIN).arg("man").output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    let roff = String::from_utf8_lossy(&o.stdout);
    assert!(
        roff.starts_with(".ie") || roff.contains(".TH mc-merge"),
        "{roff}"
    );
    assert!(roff.contains("\\-\\-replicates"), "{roff}");
    // A helper command takes no merge flags.
    let o = Command::new(BIN)
        .args(["man", "--out", "x"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // The help text has no markdown escapes and no internal names.
    let o = Command::new(BIN).arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(!help.contains("\\["), "{help}");
    assert!(
        help.contains("-o, --out") && help.contains("-q, --quiet"),
        "{help}"
    );
}

/// `job` written in `shards` shards and merged into their directory's `report/` (exit 0):
/// the directory (kept while it lives), the report directory, the run and `report.json`.
fn merged(job: &SynthJob, shards: u64) -> (tempfile::TempDir, PathBuf, Out, Value) {
    let dir = tempfile::tempdir().unwrap();
    job.write_split(dir.path(), shards);
    let out = dir.path().join("report");
    let run = mc_merge(
        &["--out", out.to_str().unwrap()],
        &[dir.path().to_path_buf()],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let v: Value = serde_json::from_str(&report(&out)).unwrap();
    (dir, out, run, v)
}

/// The holding forces of a case, against the same figures computed here from the samples:
/// the 5th, 50th and 95th percentiles (definition 1: the `⌈p·n⌉`-th smallest), the samples
/// held by less than 1 µN among all and among those above θ_P95, and a caveat naming the
/// latter; a case that records none reports none and no caveat.
#[test]
fn holding_forces_are_summarised_and_a_loosely_held_tail_is_named() {
    let mut loose = SynthCase::rayleigh("loose", 400, 2e-5, &[("sigma", 0.0067)]);
    loose.floating_every = Some(4);
    let framed = SynthCase::rayleigh("framed", 400, 2e-5, &[("sigma", 0.05)]);
    let job = SynthJob::new(11, vec![loose, framed]);
    let (_dir, out, _, v) = merged(&job, 3);
    let h = &v["cases"][0]["holding_force"];
    let samples: Vec<_> = (0..400).map(|i| job.sample(i)).collect();
    let mut forces: Vec<f64> = samples.iter().map(|s| s.holding_force.unwrap()).collect();
    forces.sort_by(f64::total_cmp);
    let nth = |p: f64| forces[(p * 400.0_f64).ceil() as usize - 1];
    assert_eq!(h["recorded"], 400);
    for (i, p) in [0.05, 0.5, 0.95].iter().enumerate() {
        assert_eq!(
            h["percentiles"][i]["value"].as_f64().unwrap(),
            nth(*p),
            "{p}"
        );
    }
    let mut thetas: Vec<f64> = samples.iter().map(|s| s.theta_p.unwrap()).collect();
    thetas.sort_by(f64::total_cmp);
    let p95 = thetas[(0.95 * 400.0_f64).ceil() as usize - 1];
    let tail: Vec<_> = samples
        .iter()
        .filter(|s| s.theta_p.unwrap() > p95)
        .collect();
    let tail_loose = tail
        .iter()
        .filter(|s| s.holding_force.unwrap() < 1e-6)
        .count();
    assert_eq!(h["loose"], 100);
    assert_eq!(h["loose_fraction"]["value"], 0.25);
    assert_eq!(h["tail_recorded"], tail.len());
    assert_eq!(h["tail_loose"], tail_loose);
    assert!(
        tail_loose > 0,
        "the synthetic tail holds a loosely held sample"
    );
    let caveats = v["cases"][0]["caveats"].as_array().unwrap();
    let named = format!("{tail_loose} of the {} samples above", tail.len());
    assert!(
        caveats
            .iter()
            .any(|c| c.as_str().unwrap().starts_with(&named)),
        "{caveats:?}"
    );
    let framed = &v["cases"][1];
    assert_eq!(framed["holding_force"]["recorded"], 0);
    assert!(framed["holding_force"]["percentiles"][1]["value"].is_null());
    assert!(
        !framed["caveats"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c.as_str().unwrap().contains("held by less than 1 µN"))
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Holding forces [N]"), "{md}");
}

/// Samples whose line records a `limit_ratio` (the solve at the limit did not converge and
/// a stage of the continuation stands for it) are counted in a caveat naming the largest
/// ratio; a case without them has no such caveat.
#[test]
fn samples_whose_limit_stands_at_a_stage_are_named_in_a_caveat() {
    let mut staged = SynthCase::rayleigh("staged", 400, 2e-5, &[("sigma", 0.0063)]);
    staged.floating_every = Some(2);
    staged.limit_stage_every = Some(25);
    let plain = SynthCase::rayleigh("plain", 400, 2e-5, &[("sigma", 0.0067)]);
    let job = SynthJob::new(11, vec![staged, plain]);
    let (_dir, _, run, v) = merged(&job, 2);
    let caveats = |i: usize| -> Vec<String> {
        v["cases"][i]["caveats"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap().to_string())
            .collect()
    };
    // Samples 0, 25, ..., 375: 16, with ratios 1e-12 × (1 + k % 7); the largest 7e-12.
    let staged = caveats(0);
    let named = staged
        .iter()
        .find(|c| c.starts_with("in 16 of 400 converged samples the solve at the limit"))
        .unwrap_or_else(|| panic!("{staged:?}"));
    assert!(named.contains("at most 7.0e-12"), "{named}");
    assert!(
        !caveats(1)
            .iter()
            .any(|c| c.contains("the solve at the limit")),
        "{:?}",
        caveats(1)
    );
    assert!(
        run.stdout.contains("staged: CAVEAT in 16 of 400"),
        "{}",
        run.stdout
    );
}

/// The fraction of samples with a floating stage, per case, with its Clopper–Pearson
/// interval; where it exceeds the 5 % tail that θ_P95 reads, a caveat says that the upper
/// percentiles rest on what the model leaves out and names the lever. Cases whose lines do
/// not record `floating` (models framed by bars) report none recorded and no caveat.
#[test]
fn floating_stages_are_counted_and_a_heavy_tail_is_named() {
    let mut heavy = SynthCase::rayleigh("heavy", 400, 2e-5, &[("sigma", 0.0067)]);
    heavy.floating_every = Some(10);
    let mut light = SynthCase::rayleigh("light", 400, 2e-5, &[("sigma", 0.033)]);
    light.floating_every = Some(50);
    let framed = SynthCase::rayleigh("framed", 400, 2e-5, &[("sigma", 0.05)]);
    let job = SynthJob::new(9, vec![heavy, light, framed]);
    let (_dir, _, run, v) = merged(&job, 2);
    let case = |i: usize| &v["cases"][i];
    assert_eq!(case(0)["floating"]["recorded"], 400);
    assert_eq!(case(0)["floating"]["floating"], 40);
    assert_eq!(case(0)["floating"]["fraction"]["value"], 0.1);
    let lower = case(0)["floating"]["fraction"]["lower"].as_f64().unwrap();
    assert!(lower > 0.07 && lower < 0.1, "{lower}");
    let caveat = |i: usize| {
        case(i)["caveats"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c.as_str().unwrap().starts_with("floating stages in"))
    };
    assert!(caveat(0));
    assert!(
        run.stdout
            .contains("heavy: floating stages in 40 of 400 samples"),
        "{}",
        run.stdout
    );
    assert!(
        run.stdout
            .contains("more diagonal pretension or smaller clearances"),
        "{}",
        run.stdout
    );
    assert_eq!(case(1)["floating"]["floating"], 8);
    assert!(!caveat(1));
    assert_eq!(case(2)["floating"]["recorded"], 0);
    assert!(case(2)["floating"]["fraction"]["value"].is_null());
    assert!(!caveat(2));
}

/// The merge's last lines are the answer, then the report's path: the files in one line,
/// every case placed against the target by its θ_P95 in report.json, the allowable σ with
/// its interval and conservative end as report.json has them, the Rayleigh rejections
/// counted against what chance gives, and `report.html` last.
fn check_answer_last(stdout: &str, v: &Value, dir: &Path) {
    let lines: Vec<&str> = stdout.lines().collect();
    let html = dir.join("report.html");
    assert_eq!(
        lines.last().copied(),
        Some(format!("report: {}", html.display()).as_str())
    );
    assert_eq!(
        stdout.matches("wrote ").count(),
        1,
        "the files are summarised in one line: {stdout}"
    );
    let start = lines
        .iter()
        .position(|l| l.starts_with("answer: θ_P95 against the target "))
        .unwrap_or_else(|| panic!("no answer: {stdout}"));
    let answer = lines[start..].join("\n");
    let target = v["settings"]["target_angle"].as_f64().unwrap();
    for case in v["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let p95 = crate::readable::p95(case);
        let side = if p95 > target {
            "  above the target: "
        } else {
            "  at or below it: "
        };
        let line = lines[start..].iter().find(|l| l.starts_with(side)).unwrap();
        assert!(
            line.contains(&format!("{name} (")),
            "{name} not in {line:?}"
        );
    }
    let a = &v["sweep"]["sigma_series"][0]["allowable_sigma"]["through_origin"];
    let lower = a["lower"].as_f64().unwrap();
    assert!(
        answer.contains(&format!(
            "{:.3e} [{lower:.3e}, ",
            a["value"].as_f64().unwrap()
        )) && answer.contains(&format!("conservative σ ≤ {lower:.3e} mm")),
        "{answer}\n{a}"
    );
    // The σ-sweep marks the target on both axes: the target written where its line meets
    // the θ axis (besides the legend's entry) and in arcsec on the arcsec axis, the
    // allowable σ written where it meets the σ axis (the legend's entry starts "allowable").
    let sweep = std::fs::read_to_string(dir.join("sigma-sweep.svg")).unwrap();
    let texts: Vec<&str> = sweep.lines().collect();
    assert!(
        texts.iter().filter(|l| l.starts_with("target ")).count() >= 2,
        "no target at the θ axis"
    );
    let arcsec = format!(
        "{:.2}″",
        v["settings"]["target_angle"].as_f64().unwrap() * truss_units::ARCSEC_PER_RAD
    );
    assert!(
        texts.iter().any(|l| *l == arcsec),
        "no target {arcsec} at the arcsec axis"
    );
    assert!(
        texts
            .iter()
            .any(|l| l.starts_with("σ = ") && l.ends_with(" mm")),
        "no allowable σ at the σ axis"
    );
    // The readable report opens with the same answer, before the run's details.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let first = md.split("\n## ").nth(1).unwrap_or_default();
    assert!(
        first.starts_with("The answer\n")
            && first.contains(&format!(
                "the conservative choice is **σ ≤ {lower:.3e} mm**"
            )),
        "{first}"
    );
    let rejected = v["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["gof"]["verdict"] == "rejected")
        .count();
    assert!(
        answer.contains(&format!(
            "Rayleigh law rejected in {rejected} of 3 cases at α = 0.05"
        )),
        "{answer}"
    );
    check_answer_section(v, &answer);
}

/// report.json's `answer` holds what the cases and the sweep say: each case's θ_P95 and its
/// side of the target, the allowable σ, and each verdict's p-value (the smaller of KS's and
/// AD's) with Holm's adjustment, recomputed here from the sorted p-values; the console
/// names the cases Holm still rejects (or the smallest adjusted p).
fn check_answer_section(v: &Value, console: &str) {
    let a = &v["answer"];
    let target = v["settings"]["target_angle"].as_f64().unwrap();
    assert_eq!(a["target_angle"].as_f64(), Some(target));
    let cases = v["cases"].as_array().unwrap();
    for (case, placed) in cases.iter().zip(a["cases"].as_array().unwrap()) {
        assert_eq!(placed["case"], case["name"]);
        let p95 = crate::readable::p95(case);
        assert_eq!(placed["value"]["value"].as_f64(), Some(p95));
        let side = if p95 > target { "above" } else { "within" };
        assert_eq!(placed["against"], side, "{placed}");
    }
    assert_eq!(
        a["allowable_sigma"][0]["sigma"],
        v["sweep"]["sigma_series"][0]["allowable_sigma"]["through_origin"]
    );
    let p: Vec<f64> = cases
        .iter()
        .map(|c| {
            let ks = c["gof"]["ks"]["p_value"].as_f64().unwrap();
            let ad = c["gof"]["ad"]["p_value"].as_f64().unwrap();
            ks.min(ad)
        })
        .collect();
    let m = p.len();
    let mut sorted = p.clone();
    sorted.sort_by(f64::total_cmp);
    let verdicts = a["rayleigh"]["cases"].as_array().unwrap();
    assert_eq!(verdicts.len(), m);
    let mut holm_rejected = vec![];
    for (k, (verdict, &pk)) in verdicts.iter().zip(&p).enumerate() {
        assert_eq!(verdict["p_value"].as_f64(), Some(pk));
        let rank = sorted.iter().position(|&x| x == pk).unwrap();
        let adjusted = (0..=rank)
            .map(|j| ((m - j) as f64 * sorted[j]).min(1.0))
            .fold(0.0, f64::max);
        let got = verdict["holm_p_value"].as_f64().unwrap();
        assert!((got - adjusted).abs() < 1e-12, "{got} vs {adjusted}");
        if adjusted < 0.05 {
            holm_rejected.push(cases[k]["name"].clone());
        }
        assert_eq!(
            verdict["relative_difference"],
            cases[k]["gof"]["effect"]["relative_difference"]
        );
    }
    assert_eq!(
        a["rayleigh"]["holm_rejected"],
        Value::from(holm_rejected.clone())
    );
    assert!(
        console.contains(&format!("after Holm's adjustment across the {m} cases: "))
            && (holm_rejected.is_empty()
                == console.contains("none rejected (smallest adjusted p = ")),
        "{console}"
    );
}
