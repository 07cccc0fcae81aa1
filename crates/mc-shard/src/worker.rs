//! Computing one sample's line: draw its length errors, solve, and format the record. The
//! runner and `reproduce` use the same code, so a reproduced line is the shard's line.

use crate::job::Job;
use crate::sampler::{draw_sample, stream_key};
use shard_record::{Sample, Status};
use truss_core::solver::Perturbation;
use truss_core::{SolveOptions, Solver};

/// Per-thread state: a solver per case (created on first use) and scratch.
pub struct Worker<'j> {
    job: &'j Job,
    keys: Vec<[u8; 32]>,
    solvers: Vec<Option<Solver>>,
    errors: Vec<f64>,
    clearances: Vec<f64>,
    options: SolveOptions,
}

impl<'j> Worker<'j> {
    /// A worker for `job`.
    pub fn new(job: &'j Job) -> Self {
        Self::with_options(job, SolveOptions::default())
    }

    /// A worker with given solver options (for example, recording iterations).
    pub fn with_options(job: &'j Job, options: SolveOptions) -> Self {
        Self {
            job,
            keys: job
                .cases
                .iter()
                .map(|c| stream_key(job.seed, &c.name))
                .collect(),
            solvers: job.cases.iter().map(|_| None).collect(),
            errors: Vec::new(),
            clearances: Vec::new(),
            options,
        }
    }

    /// The record of global sample `index`. A solve that fails gives a `failed` record with
    /// its reason, never a missing one.
    ///
    /// # Panics
    /// If `index` is beyond the job (a bug in the caller).
    pub fn sample(&mut self, index: u64) -> Sample {
        let (c, k) = self.job.case_of(index).expect("index within the job");
        let case = &self.job.cases[c];
        draw_sample(
            &self.keys[c],
            case,
            k,
            &mut self.errors,
            &mut self.clearances,
        );
        for (e, t) in self.errors.iter_mut().zip(&case.applied.length_changes) {
            *e += t;
        }
        let options = &self.options;
        let solver = self.solvers[c]
            .get_or_insert_with(|| Solver::with_structure(case.structure.clone(), options.clone()));
        let result = solver.solve_perturbed(Perturbation {
            length_errors: &self.errors,
            extra_loads: &case.applied.loads,
            clearances: &self.clearances,
        });
        let has_joints = !case.model.joints().is_empty();
        let base = Sample {
            index,
            case: case.name.clone(),
            sample: k,
            status: Status::Converged,
            iterations: 0,
            theta_p: None,
            tan_theta_x: None,
            tan_theta_y: None,
            residual: None,
            slack_cables: None,
            loose_joints: None,
            reason: None,
        };
        match result {
            Ok(report) => match solver.distortion() {
                Some(d) if d.theta_p.is_finite() => Sample {
                    iterations: report.iterations,
                    theta_p: Some(d.theta_p),
                    tan_theta_x: Some(d.tan_theta_x),
                    tan_theta_y: Some(d.tan_theta_y),
                    residual: Some(report.residual),
                    slack_cables: Some(report.slack_cables),
                    loose_joints: has_joints.then_some(report.loose_joints),
                    ..base
                },
                Some(_) => Sample {
                    status: Status::Failed,
                    iterations: report.iterations,
                    reason: Some("the top surface's angles are not finite".into()),
                    ..base
                },
                None => Sample {
                    status: Status::Failed,
                    iterations: report.iterations,
                    reason: Some("the model names no top surface to measure".into()),
                    ..base
                },
            },
            Err(e) => Sample {
                status: Status::Failed,
                iterations: match &e {
                    truss_core::SolveError::NotConverged { iterations, .. } => *iterations,
                    truss_core::SolveError::Mechanism { iteration, .. }
                    | truss_core::SolveError::NonFinite { iteration, .. } => *iteration,
                    truss_core::SolveError::Input(_) => 0,
                },
                reason: Some(e.to_string()),
                ..base
            },
        }
    }

    /// The length errors of the last sample \[mm\], model order: the drawn ones plus any
    /// thermal length change.
    pub fn last_errors(&self) -> &[f64] {
        &self.errors
    }

    /// The joint clearances the last sample drew \[mm\], model order (empty when its case
    /// draws none).
    pub fn last_clearances(&self) -> &[f64] {
        &self.clearances
    }

    /// The solver of case `c`, after it solved a sample of that case.
    pub fn solver(&self, c: usize) -> Option<&Solver> {
        self.solvers[c].as_ref()
    }
}
