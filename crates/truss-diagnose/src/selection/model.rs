//! What the steps of the selection share: the data, the settings and the simulation size
//! (`Context`); a model compared with the measurements ([`ComparedModel`], stage 1 of a
//! step); the model's effects at their values; and the candidates still to try (`Pool`).

use crate::candidates::candidate::Candidate;
use crate::comparison::baseline::{Baseline, CaseEdit};
use crate::comparison::measured::Measured;
use crate::comparison::simulate::{Noise, Simulation, simulate};
use crate::comparison::statistics::{Comparison, compare};
use crate::errors::DiagnoseError;
use crate::likelihood::conditional::GaugeNoise;
use crate::likelihood::score::{Evaluator, FittedParameter, Memo};
use crate::settings::{Progress, Settings};
use std::cell::{Cell, RefCell};
use std::time::Instant;

/// What every step shares: the data, the settings, the simulation size and the noise.
pub(crate) struct Context<'a> {
    pub baseline: &'a Baseline,
    pub measured: &'a Measured,
    pub settings: &'a Settings,
    pub samples: usize,
    pub noise: Noise,
    pub top: [[usize; 3]; 3],
    pub progress: &'a Progress,
    /// Simulations run so far.
    pub simulations: Cell<usize>,
    /// ℓ's terms of the cases simulated so far.
    pub memo: Memo,
    /// The simulated gauge noise of the member measurements, of `samples` samples.
    pub gauge: GaugeNoise,
    /// Each stage's wall time and simulations, in order.
    pub stages: RefCell<Vec<StageTime>>,
}

/// The wall time and the simulations of one stage of the diagnosis (`timing.stages` of
/// `diagnosis.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct StageTime {
    /// The stage: `step 2: fit the candidates`, `final fit`, ….
    pub stage: String,
    /// Wall time \[s\].
    pub seconds: f64,
    /// Simulations of N samples run in it (cases met again are not simulated again).
    pub simulations: usize,
}

impl Context<'_> {
    /// An evaluator of ℓ for candidates applied to `start`.
    pub(crate) fn evaluator(&self, start: &CaseEdit) -> Evaluator<'_> {
        Evaluator {
            baseline: self.baseline,
            start: start.clone(),
            measured: self.measured,
            samples: self.samples,
            sigma_m: self.settings.measurement_sigma,
            condition: self.settings.condition_on_members,
            threads: self.settings.thread_count(),
            simulations: Cell::new(0),
            memo: Some(&self.memo),
            gauge: &self.gauge,
        }
    }

    /// Adds an evaluator's simulations to the count.
    pub(crate) fn count(&self, ev: &Evaluator) {
        self.simulations
            .set(self.simulations.get() + ev.simulations.get());
    }

    /// Runs `work` as the stage `stage`, recording its wall time and the simulations it
    /// ran (those counted into the context, and those of `ev` if given, which is counted
    /// into the context later).
    pub(crate) fn timed<T>(
        &self,
        stage: impl Into<String>,
        ev: Option<&Evaluator>,
        work: impl FnOnce() -> T,
    ) -> T {
        let count = || self.simulations.get() + ev.map_or(0, |e| e.simulations.get());
        let (clock, before) = (Instant::now(), count());
        let out = work();
        self.stages.borrow_mut().push(StageTime {
            stage: stage.into(),
            seconds: clock.elapsed().as_secs_f64(),
            simulations: count() - before,
        });
        out
    }

    /// c = 1 + n/N, the simulation's own noise in the tests.
    pub(crate) fn inflation(&self) -> f64 {
        1.0 + self.measured.n() as f64 / self.samples as f64
    }
}

/// A model compared with the measurements: stage 1 of a step.
pub struct ComparedModel {
    /// Its case.
    pub edit: CaseEdit,
    /// Its simulation, with the instrument's noise.
    pub simulation: Simulation,
    /// Every statistic against the measurements.
    pub comparison: Comparison,
    /// ℓ of the measurements under it.
    pub log_likelihood: f64,
}

/// Simulates, compares and scores a model.
pub(crate) fn compare_model(ctx: &Context, edit: CaseEdit) -> Result<ComparedModel, DiagnoseError> {
    let ev = ctx.evaluator(&edit);
    let job = ev.job(&edit)?;
    let simulation = simulate(
        &job,
        &ctx.measured.coords,
        ctx.samples,
        Some((ctx.noise, ctx.top)),
        ctx.settings.thread_count(),
    )?;
    ctx.simulations.set(ctx.simulations.get() + 1);
    let terms = ev.score(&job, &simulation)?;
    ctx.memo.put(&job.id, &terms);
    let log_likelihood: f64 = terms.iter().sum();
    let comparison = compare(
        ctx.measured,
        &simulation,
        ctx.top,
        ctx.settings.measurement_sigma,
        ctx.settings.thread_count(),
    );
    Ok(ComparedModel {
        edit,
        simulation,
        comparison,
        log_likelihood,
    })
}

/// An effect of the model re-fitted jointly with the others.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RefitEffect {
    /// The candidate's name.
    pub name: String,
    /// Its parameters with the joint fit's 95 % Wald intervals.
    pub parameters: Vec<FittedParameter>,
}

/// An effect in a model, at its values.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ModelEffect {
    /// The candidate's name.
    pub name: String,
    /// (parameter, unit, value).
    pub parameters: Vec<(String, &'static str, f64)>,
}

/// An effect added in an earlier step and its current values.
pub(crate) struct Added {
    pub candidate: Box<dyn Candidate>,
    pub values: Vec<f64>,
    /// The step that added it.
    pub step: usize,
    /// Its rivals for a swap ([`crate::selection::update`]): the other candidates that
    /// were significant at that step and explained at least half as much (ΔBIC), with
    /// their fitted values then.
    pub rivals: Vec<(String, Vec<f64>)>,
}

/// The candidates of a selection: those still to try, and the effects of the model.
pub(crate) struct Pool {
    /// Candidates not yet in the model (nor removed from it).
    pub remaining: Vec<Box<dyn Candidate>>,
    /// The model's effects, in the order they entered it.
    pub added: Vec<Added>,
}
