//! The `truss` binary's tests, in one binary: its commands ([`cli`]) and its refusals of
//! hostile or meaningless input ([`limits`]).

mod cli;
mod files;
#[path = "../../../run-dir/tests/support/hostile.rs"]
mod hostile;
mod limits;

use std::process::Command;

/// Runs `truss` with `args`.
pub fn truss(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_truss"))
        .args(args)
        .output()
        .unwrap()
}

/// The JSON `truss` printed.
pub fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout)))
}

/// A job of one case (`c`, 1000 samples, batten and longeron σ 0.01 mm) of the 1-stage
/// prism, written into `dir`: enough for `truss tolerance` to start.
pub fn one_stage_job(dir: &std::path::Path) -> std::path::PathBuf {
    let job = dir.join("job.json");
    std::fs::write(
        &job,
        r#"{"model": {"prism": {"stages": 1}}, "seed": 1, "cases": [{"name": "c", "samples": 1000,
  "length_errors": {"batten": {"normal": {"sigma": 0.01}}, "longeron": {"normal": {"sigma": 0.01}}}}]}"#,
    )
    .unwrap();
    job
}

/// `truss tolerance` on case `c` of `job` ([`one_stage_job`]) for a 20″ target, small
/// (1000 samples for the sensitivity and for the verification), no plots, into `out`, with
/// `extra` arguments.
pub fn small_tolerance(
    job: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "tolerance",
        "--job",
        job.to_str().unwrap(),
        "--case",
        "c",
        "--target-arcsec",
        "20",
        "--samples",
        "1000",
        "--sensitivity-samples",
        "1000",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    truss(&args)
}
