//! The per-sample solve: draw a sample's length errors and clearances, apply the case's
//! effects, solve, and measure the top surface (its tilt, decenter and despace). Everything that runs samples (the shard
//! runner, `reproduce`, the diagnosis) goes through [`SampleSolver`], so they see the same
//! numbers; the runner turns a [`SampleResult`] into its wire record.

use crate::job::Job;
use crate::sampler::{draw_sample_with_lots, stream_key};
use truss_core::measure::{Distortion, Placement};
use truss_core::solver::Perturbation;
use truss_core::solver::lanes::{Kernels, finish};
use truss_core::{SolveError, SolveOptions, Solver};

/// A converged sample's measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Converged {
    /// The top surface's tilt (θ_P \[rad\], tan θ_x, tan θ_y).
    pub distortion: Distortion,
    /// Where the top surface's centroid sits against the bottom's frame: decenter and
    /// despace \[mm\] (see [`truss_core::measure`]).
    pub placement: Placement,
    /// Final out-of-balance force, max over free DOFs \[N\].
    pub residual: f64,
    /// Number of the model's cables that ended slack.
    pub slack_cables: u32,
    /// Number of loose backlash joints, for a model with joints.
    pub loose_joints: Option<u32>,
    /// Whether some stage's tilt is held by pretension alone (see
    /// [`truss_core::limit`]), for a model whose bars do not frame the tilt.
    pub floating: Option<bool>,
    /// The holding force \[N\]: the smallest force on one top-surface node that moves θ_P
    /// by 1 % (see [`truss_core::SolveReport::holding_force`]); where `floating` is given.
    pub holding_force: Option<f64>,
    /// Where the limit's last attempt did not converge, the compression ratio of the
    /// one-sided members at the equilibrium that stands for it (see
    /// [`truss_core::SolveReport::limit_ratio`]).
    pub limit_ratio: Option<f64>,
}

/// How a sample ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Solved and measured.
    Converged(Converged),
    /// Not solved, or not measurable; the reason in words.
    Failed(String),
}

/// One sample's result.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleResult {
    /// Global sample index in the job.
    pub index: u64,
    /// Index of its case.
    pub case: usize,
    /// Index within the case.
    pub sample: u64,
    /// Newton iterations (linear solves) it took.
    pub iterations: u32,
    /// How it ended.
    pub outcome: Outcome,
}

/// Per-thread state: a solver per case (created on first use) and scratch.
pub struct SampleSolver<'j> {
    job: &'j Job,
    keys: Vec<[u8; 32]>,
    solvers: Vec<Option<Solver>>,
    /// The last sample's drawn length errors \[mm\].
    errors: Vec<f64>,
    /// The drawn length errors plus the case's thermal length changes \[mm\], where it has
    /// any (then what the solver is given).
    changed: Vec<f64>,
    /// Whether the last sample's case has thermal length changes (`changed` then holds
    /// its length errors).
    thermal: bool,
    clearances: Vec<f64>,
    lots: Vec<f64>,
    options: SolveOptions,
}

impl<'j> SampleSolver<'j> {
    /// A sample solver for `job`.
    pub fn new(job: &'j Job) -> Self {
        Self::with_options(job, SolveOptions::default())
    }

    /// A sample solver with given solver options (for example, recording iterations).
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
            changed: Vec::new(),
            thermal: false,
            clearances: Vec::new(),
            lots: Vec::new(),
            options,
        }
    }

    /// The job.
    pub fn job(&self) -> &'j Job {
        self.job
    }

    /// Solves global sample `index`. A solve that fails gives [`Outcome::Failed`] with its
    /// reason, never nothing.
    ///
    /// # Panics
    /// If `index` is beyond the job (a bug in the caller).
    pub fn solve(&mut self, index: u64) -> SampleResult {
        finish(self.solve_in(index, Kernels::OneSample))
    }

    /// [`SampleSolver::solve`], the solver's kernels run by `kernels`: at once, or in a
    /// lane of a batch of samples (see [`truss_core::solver::lanes`]); the same bits either
    /// way.
    ///
    /// # Panics
    /// If `index` is beyond the job (a bug in the caller).
    pub async fn solve_in(&mut self, index: u64, kernels: Kernels<'_>) -> SampleResult {
        let (c, k) = self.job.case_of(index).expect("index within the job");
        let case = &self.job.cases[c];
        draw_sample_with_lots(
            &self.keys[c],
            case,
            k,
            &mut self.errors,
            &mut self.clearances,
            &mut self.lots,
        );
        self.thermal = !case.applied.length_changes.is_empty();
        let length_errors = if !self.thermal {
            &self.errors
        } else {
            self.changed.clone_from(&self.errors);
            for (e, t) in self.changed.iter_mut().zip(&case.applied.length_changes) {
                *e += t;
            }
            &self.changed
        };
        let options = &self.options;
        let solver = self.solvers[c]
            .get_or_insert_with(|| Solver::with_structure(case.structure.clone(), options.clone()));
        let result = solver
            .solve_perturbed_in(
                Perturbation {
                    length_errors,
                    extra_loads: &case.applied.loads,
                    clearances: &self.clearances,
                },
                kernels,
            )
            .await;
        let has_joints = !case.model.joints().is_empty();
        let (iterations, outcome) = match result {
            Ok(report) => (
                report.iterations,
                match (
                    solver.distortion(),
                    truss_core::output::placement(&case.model, solver),
                ) {
                    (Some(d), Some(p)) if d.theta_p.is_finite() => Outcome::Converged(Converged {
                        distortion: d,
                        placement: p,
                        residual: report.residual,
                        slack_cables: report.slack_cables,
                        loose_joints: has_joints.then_some(report.loose_joints),
                        floating: (!case.structure.tilt_framed()).then_some(report.floating),
                        holding_force: report.holding_force,
                        limit_ratio: report.limit_ratio,
                    }),
                    (Some(_), _) => {
                        Outcome::Failed("the top surface's angles are not finite".into())
                    }
                    (None, _) => {
                        Outcome::Failed("the model names no top surface to measure".into())
                    }
                },
            ),
            Err(e) => (
                match &e {
                    SolveError::NotConverged { iterations, .. } => *iterations,
                    SolveError::Mechanism { iteration, .. }
                    | SolveError::NonFinite { iteration, .. } => *iteration,
                    SolveError::Input(_) => 0,
                },
                Outcome::Failed(if case.structure.near_the_limit() {
                    format!(
                        "{e} (the model's slack cables are solved at their limit, ratio 0, and \
                         a stage held by them alone may have no resolved position: an explicit \
                         compression_ratio such as 1e-4 regularises it; see the README, \
                         \"Slack cables\")"
                    )
                } else {
                    e.to_string()
                }),
            ),
        };
        SampleResult {
            index,
            case: c,
            sample: k,
            iterations,
            outcome,
        }
    }

    /// The length errors of the last sample \[mm\], model order: the drawn ones plus any
    /// thermal length change.
    pub fn last_errors(&self) -> &[f64] {
        if self.thermal {
            &self.changed
        } else {
            &self.errors
        }
    }

    /// The length errors the last sample drew \[mm\], model order, without its case's
    /// thermal length changes: what [`crate::sampler::draw_length_errors`] gives for the
    /// same sample (the measured members of `truss-diagnose` are compared with these).
    pub fn last_drawn_errors(&self) -> &[f64] {
        &self.errors
    }

    /// The shared parts of its lots the last sample drew \[mm\], numbered as
    /// [`crate::job::Case::member_lot`] numbers them (empty when its case has no lots);
    /// [`SampleSolver::last_errors`] includes them.
    pub fn last_lots(&self) -> &[f64] {
        &self.lots
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::draw_length_errors;
    use std::path::Path;

    /// A 5-stage prism job, with the case's `effects` JSON.
    fn job(effects: &str) -> Job {
        let text = format!(
            r#"{{"model": {{"prism": {{"stages": 5}}}}, "seed": 7,
                "cases": [{{"name": "c", "samples": 4, {effects}
                            "length_errors": {{"batten": {{"normal": {{"sigma": 0.0063}}}},
                                               "longeron": {{"normal": {{"sigma": 0.0063}}}}}}}}]}}"#
        );
        Job::from_json(&text, Path::new(".")).unwrap()
    }

    /// Without thermal changes the solver's length errors are the drawn ones; with them,
    /// the drawn ones stay what `draw_length_errors` gives, and the solver's are each
    /// drawn error plus its member's thermal change, as the solve used them (its θ_P is
    /// that of a solve given those errors).
    #[test]
    fn drawn_errors_are_kept_apart_from_thermal_changes() {
        let thermal = r#""effects": {"thermal_gradient": {"gradient": [0, 0, 0.002], "offset": 0.5, "alpha": 23e-6}},"#;
        for (effects, changed) in [("", false), (thermal, true)] {
            let job = job(effects);
            let case = &job.cases[0];
            assert_eq!(case.applied.length_changes.is_empty(), !changed);
            let key = crate::sampler::stream_key(job.seed, &case.name);
            let mut solver = SampleSolver::new(&job);
            let mut drawn = Vec::new();
            for k in 0..4 {
                let result = solver.solve(k);
                draw_length_errors(&key, case, k, &mut drawn);
                assert_eq!(solver.last_drawn_errors(), &drawn[..]);
                let want: Vec<f64> = if changed {
                    drawn
                        .iter()
                        .zip(&case.applied.length_changes)
                        .map(|(e, t)| e + t)
                        .collect()
                } else {
                    drawn.clone()
                };
                assert_eq!(solver.last_errors(), &want[..]);
                assert!(!changed || want != drawn);
                let mut alone = Solver::with_structure(case.structure.clone(), Default::default());
                alone
                    .solve_perturbed(Perturbation {
                        length_errors: &want,
                        extra_loads: &case.applied.loads,
                        clearances: &[],
                    })
                    .unwrap();
                let Outcome::Converged(c) = result.outcome else {
                    panic!("sample {k} failed")
                };
                assert_eq!(
                    c.distortion.theta_p.to_bits(),
                    alone.distortion().unwrap().theta_p.to_bits()
                );
            }
        }
    }
}
