//! Computing one sample's line: the job crate's per-sample solve, formatted as its wire
//! record. The runner and `reproduce` use the same code, so a reproduced line is the
//! shard's line.

use shard_record::{Sample, Status};
use truss_core::{SolveOptions, Solver};
use truss_job::Job;
use truss_job::solve::{Outcome, SampleResult, SampleSolver};

/// Per-thread state of the runner: the job's [`SampleSolver`].
pub struct Worker<'j> {
    inner: SampleSolver<'j>,
}

impl<'j> Worker<'j> {
    /// A worker for `job`.
    pub fn new(job: &'j Job) -> Self {
        Self::with_options(job, SolveOptions::default())
    }

    /// A worker with given solver options (for example, recording iterations).
    pub fn with_options(job: &'j Job, options: SolveOptions) -> Self {
        Self {
            inner: SampleSolver::with_options(job, options),
        }
    }

    /// The record of global sample `index`: converged, or failed with its reason, never
    /// missing.
    ///
    /// # Panics
    /// If `index` is beyond the job (a bug in the caller).
    pub fn sample(&mut self, index: u64) -> Sample {
        let result = self.inner.solve(index);
        record(self.inner.job(), &result)
    }

    /// The length errors of the last sample \[mm\], model order.
    pub fn last_errors(&self) -> &[f64] {
        self.inner.last_errors()
    }

    /// The joint clearances the last sample drew \[mm\], model order.
    pub fn last_clearances(&self) -> &[f64] {
        self.inner.last_clearances()
    }

    /// The solver of case `c`, after it solved a sample of that case.
    pub fn solver(&self, c: usize) -> Option<&Solver> {
        self.inner.solver(c)
    }
}

/// The wire record of a sample's result.
pub fn record(job: &Job, r: &SampleResult) -> Sample {
    let base = Sample {
        index: r.index,
        case: job.cases[r.case].name.clone(),
        sample: r.sample,
        status: Status::Converged,
        iterations: r.iterations,
        theta_p: None,
        tan_theta_x: None,
        tan_theta_y: None,
        decenter_x: None,
        decenter_y: None,
        decenter: None,
        despace: None,
        residual: None,
        slack_cables: None,
        loose_joints: None,
        floating: None,
        holding_force: None,
        limit_ratio: None,
        reason: None,
    };
    match &r.outcome {
        Outcome::Converged(c) => Sample {
            theta_p: Some(c.distortion.theta_p),
            tan_theta_x: Some(c.distortion.tan_theta_x),
            tan_theta_y: Some(c.distortion.tan_theta_y),
            decenter_x: Some(c.placement.decenter_x),
            decenter_y: Some(c.placement.decenter_y),
            decenter: Some(c.placement.decenter),
            despace: Some(c.placement.despace),
            residual: Some(c.residual),
            slack_cables: Some(c.slack_cables),
            loose_joints: c.loose_joints,
            floating: c.floating,
            holding_force: c.holding_force,
            limit_ratio: c.limit_ratio,
            ..base
        },
        Outcome::Failed(reason) => Sample {
            status: Status::Failed,
            reason: Some(reason.clone()),
            ..base
        },
    }
}
