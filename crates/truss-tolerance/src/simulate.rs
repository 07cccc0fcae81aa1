//! Runs the samples of a one-case job in-process on the job crate's sample engine
//! (`truss_job::engine`: the same per-sample solve as the shard runner, results in index
//! order), so the result does not depend on the thread count. A failed sample is never
//! dropped: the run fails with the count and the first reason.

use crate::errors::ToleranceError;
use truss_job::Engine;
use truss_job::Job;
use truss_job::solve::Outcome;

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
    /// Per sample decenter \[mm\] (see `truss_core::measure`).
    pub decenter: Vec<f64>,
    /// Per sample despace, signed \[mm\].
    pub despace: Vec<f64>,
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

/// Solves every sample of the single case of `job` over `threads` threads (the job crate's
/// sample engine). `columns`: the members whose drawn length errors are kept (for the
/// regression; empty for none). `stage` names the run in errors.
pub fn run_case(
    job: &Job,
    columns: &[usize],
    threads: usize,
    stage: &'static str,
) -> Result<Run, ToleranceError> {
    assert_eq!(job.cases.len(), 1, "a one-case job");
    let samples = job.cases[0].samples;
    let solved = Engine::new(job, threads).map(0..samples, |solver, result| match result.outcome {
        Outcome::Converged(c) => {
            let e = solver.last_errors();
            Ok((
                c.distortion,
                c.placement,
                columns.iter().map(|&i| e[i]).collect::<Vec<_>>(),
            ))
        }
        Outcome::Failed(reason) => Err((result.index, reason)),
    });
    let mut run = Run {
        columns: columns.to_vec(),
        ..Run::default()
    };
    let mut failed: Vec<(u64, String)> = Vec::new();
    for sample in solved {
        match sample {
            Ok((d, p, errors)) => {
                run.tilt.push([d.tan_theta_x, d.tan_theta_y]);
                run.theta_p.push(d.theta_p);
                run.decenter.push(p.decenter);
                run.despace.push(p.despace);
                run.errors.extend(errors);
            }
            Err(f) => failed.push(f),
        }
    }
    if let Some((first, reason)) = failed.first() {
        return Err(ToleranceError::FailedSamples {
            stage,
            failed: failed.len(),
            samples: samples as usize,
            first: *first,
            reason: reason.clone(),
        });
    }
    Ok(run)
}
