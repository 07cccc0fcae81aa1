//! Runs the samples of a one-case job in-process, over scoped threads, through
//! `truss_job::solve::SampleSolver` (the same per-sample solve as the shard runner).
//!
//! Samples are split into contiguous blocks, one per thread; every sample's result depends
//! only on (job, seed, case, index) and the blocks are joined in index order, so the result
//! does not depend on the thread count. A failed sample is never dropped: the run fails with
//! the count and the first reason.

use crate::errors::ToleranceError;
use truss_job::Job;
use truss_job::solve::{Outcome, SampleSolver};

/// The samples of a run, in index order.
#[derive(Debug, Clone, Default)]
pub struct Run {
    /// Members whose length errors are kept (model indices), the columns of `errors`.
    pub columns: Vec<usize>,
    /// Row-major `samples × columns.len()` length errors \[mm\] (empty unless asked for).
    pub errors: Vec<f64>,
    /// Per sample (tan θ_x, tan θ_y) \[-\].
    pub tilt: Vec<[f64; 2]>,
    /// Per sample θ_P \[rad\].
    pub theta_p: Vec<f64>,
}

impl Run {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.theta_p.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.theta_p.is_empty()
    }

    /// The length errors of sample `k` \[mm\], one per column.
    pub fn errors_of(&self, k: usize) -> &[f64] {
        let m = self.columns.len();
        &self.errors[k * m..(k + 1) * m]
    }
}

/// Worker threads to use: the machine's parallelism.
pub fn threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Solves every sample of the single case of `job` over `threads` threads. `columns`: the
/// members whose drawn length errors are kept (for the regression; empty for none).
/// `stage` names the run in errors.
pub fn run_case(
    job: &Job,
    columns: &[usize],
    threads: usize,
    stage: &'static str,
) -> Result<Run, ToleranceError> {
    assert_eq!(job.cases.len(), 1, "a one-case job");
    let samples = job.cases[0].samples as usize;
    let threads = threads.clamp(1, samples.max(1));
    let chunk = samples.div_ceil(threads).max(1);
    type Block = (Run, Vec<(u64, String)>);
    let blocks: Vec<Block> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..samples)
            .step_by(chunk)
            .map(|from| {
                let to = (from + chunk).min(samples);
                scope.spawn(move || {
                    let mut solver = SampleSolver::new(job);
                    let mut run = Run {
                        columns: columns.to_vec(),
                        ..Run::default()
                    };
                    let mut failed = Vec::new();
                    for k in from..to {
                        let result = solver.solve(k as u64);
                        match result.outcome {
                            Outcome::Converged(c) => {
                                let d = c.distortion;
                                run.tilt.push([d.tan_theta_x, d.tan_theta_y]);
                                run.theta_p.push(d.theta_p);
                                let e = solver.last_errors();
                                run.errors.extend(columns.iter().map(|&i| e[i]));
                            }
                            Outcome::Failed(reason) => failed.push((k as u64, reason)),
                        }
                    }
                    (run, failed)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a sample thread panicked"))
            .collect()
    });
    let mut run = Run {
        columns: columns.to_vec(),
        ..Run::default()
    };
    let mut failed: Vec<(u64, String)> = Vec::new();
    for (block, f) in blocks {
        run.errors.extend(block.errors);
        run.tilt.extend(block.tilt);
        run.theta_p.extend(block.theta_p);
        failed.extend(f);
    }
    if let Some((first, reason)) = failed.first() {
        return Err(ToleranceError::FailedSamples {
            stage,
            failed: failed.len(),
            samples,
            first: *first,
            reason: reason.clone(),
        });
    }
    Ok(run)
}
