//! Writes valid synthetic shard files of a job (Rayleigh-distributed θ_P, correct digests) for
//! benchmarks and demonstrations:
//!
//! ```text
//! cargo run --release -p mc-merge --example synth-shards -- OUT_DIR --samples 50000 --shards 8 --cases 1
//! ```
//!
//! With `--cases K > 1` the job is a σ-sweep (σ = 0.0033·k mm, σ_t proportional to σ as in the
//! paper: σ_t = 3.96e-5 at σ = 6.30e-3 mm), with `--stages` a stages sweep is added, and with
//! `--backlash` a second σ-series with backlash = 1 and loose joints recorded.

#[path = "../tests/it/common/mod.rs"]
mod common;

use clap::Parser;
use common::{SynthCase, SynthJob};

/// Writes synthetic shards.
#[derive(Debug, Parser)]
struct Args {
    /// Output directory (created).
    out: std::path::PathBuf,
    /// Samples per case.
    #[arg(long, default_value_t = 50_000)]
    samples: u64,
    /// Shards to split the job into.
    #[arg(long, default_value_t = 4)]
    shards: u64,
    /// Cases of the σ-sweep.
    #[arg(long, default_value_t = 1)]
    cases: u64,
    /// The σ of the sweep's cases in mm, comma separated (instead of 0.0033·k for k = 1..=cases),
    /// e.g. the paper's 0.0033,0.0067,0.017,0.033,0.067,0.0063.
    #[arg(long, value_delimiter = ',')]
    sigmas: Vec<f64>,
    /// Add a 1..=8 stages sweep at σ = 0.067 mm.
    #[arg(long)]
    stages: bool,
    /// Add a σ-series with backlash = 1.
    #[arg(long)]
    backlash: bool,
    /// Seed of the angles.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

fn main() {
    let a = Args::parse();
    let per_mm = 3.96e-5 / 6.30e-3;
    let mut cases = vec![];
    let sigmas: Vec<f64> = if a.sigmas.is_empty() {
        (1..=a.cases).map(|k| 0.0033 * k as f64).collect()
    } else {
        a.sigmas.clone()
    };
    for &sigma in &sigmas {
        cases.push(SynthCase::rayleigh(
            &format!("sigma-{sigma:.4}"),
            a.samples,
            per_mm * sigma,
            &[("sigma", sigma), ("stages", 5.0), ("backlash", 0.0)],
        ));
    }
    if a.backlash {
        for k in 1..=a.cases.max(2) {
            let sigma = 0.0033 * k as f64;
            let mut c = SynthCase::rayleigh(
                &format!("backlash-sigma-{sigma:.4}"),
                a.samples,
                0.85 * per_mm * sigma + 4e-6,
                &[("sigma", sigma), ("stages", 5.0), ("backlash", 1.0)],
            );
            c.loose = true;
            cases.push(c);
        }
    }
    if a.stages {
        for st in 1..=8u32 {
            let bump = 1.0 + 0.25 * (-(f64::from(st) - 4.0).powi(2) / 4.0).exp();
            cases.push(SynthCase::rayleigh(
                &format!("stages-{st}"),
                a.samples,
                per_mm * 0.067 * bump / (1.0 + 0.02 * f64::from(st)),
                &[
                    ("sigma", 0.067),
                    ("stages", f64::from(st)),
                    ("backlash", 0.0),
                ],
            ));
        }
    }
    let job = SynthJob::new(a.seed, cases);
    std::fs::create_dir_all(&a.out).expect("create the output directory");
    let files = job.write_split(&a.out, a.shards);
    eprintln!(
        "wrote {} shards, {} samples, job {} into {}",
        files.len(),
        job.samples(),
        job.job_id,
        a.out.display()
    );
}
