//! One step of the forward selection, as one pass through its stages:
//!
//! 1. **compare** (`compare_model`): the current model (the baseline with the effects added
//!    so far) is simulated with N samples and the instrument's noise, compared with the
//!    measurements statistic by statistic ([`crate::compare`]), and its ℓ computed: the
//!    null of this step's tests.
//! 2. **fit each candidate** (`fit_each`): every remaining candidate applied to the
//!    current model's typed case ([`CaseEdit`]), its ℓ maximised and tested against the
//!    current model ([`crate::score`]).
//! 3. **decide** (`decide_and_profile`): the verdict of [`decide`]; the candidate it names
//!    and those indistinguishable from it get profile-likelihood intervals, and should a
//!    profile find a higher maximum the verdict is decided again on the new fits.
//! 4. **update**: the named candidate is added at its fitted values, and the new model is
//!    compared (stage 1 of the next step, whose "before" it is).

use crate::baseline::{Baseline, CaseEdit};
use crate::candidates::Candidate;
use crate::compare::{Comparison, compare};
use crate::derivatives::Terms;
use crate::diagnose::{Decision, Progress, Settings, Verdict, decide, vuong};
use crate::errors::DiagnoseError;
use crate::measured::Measured;
use crate::score::{CandidateScore, Evaluator, Fitted, Test, fit_candidate, profile_candidate};
use crate::simulate::{Noise, Simulation, simulate};
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
}

impl Context<'_> {
    fn evaluator(&self, start: &CaseEdit) -> Evaluator<'_> {
        Evaluator {
            baseline: self.baseline,
            start: start.clone(),
            measured: self.measured,
            samples: self.samples,
            sigma_m: self.settings.measurement_sigma,
            condition: self.settings.condition_on_members,
            simulations: Cell::new(0),
        }
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

/// Stage 1: simulates, compares and scores a model.
pub(crate) fn compare_model(ctx: &Context, edit: CaseEdit) -> Result<ComparedModel, DiagnoseError> {
    let ev = ctx.evaluator(&edit);
    let job = ev.job(&edit)?;
    let simulation = simulate(
        &job,
        &ctx.measured.coords,
        ctx.samples,
        Some((ctx.noise, ctx.top)),
    )?;
    ctx.simulations.set(ctx.simulations.get() + 1);
    let log_likelihood: f64 = ev.score(&job, &simulation)?.iter().sum();
    let comparison = compare(
        ctx.measured,
        &simulation,
        ctx.top,
        ctx.settings.measurement_sigma,
    );
    Ok(ComparedModel {
        edit,
        simulation,
        comparison,
        log_likelihood,
    })
}

/// One step's outcome.
#[derive(Debug, Clone)]
pub struct Step {
    /// 1, 2, …
    pub number: usize,
    /// The step's verdict on what the current model still lacks.
    pub verdict: Verdict,
    /// Why.
    pub reason: String,
    /// The named candidate's index in `candidates`.
    pub named: Option<usize>,
    /// Whether the named effect is kept (the false discovery rate over the steps; see
    /// [`crate::diagnose`]). A named effect that is not kept ends the selection.
    pub kept: bool,
    /// Names of the candidates indistinguishable from the named one.
    pub indistinguishable: Vec<String>,
    /// Every remaining candidate's score against the current model.
    pub candidates: Vec<CandidateScore>,
    /// ℓ of the current model (the null of the step's tests).
    pub log_likelihood_before: f64,
    /// The named candidate's p-value adjusted over the step's K candidates, min(1, K·p).
    pub adjusted_p: Option<f64>,
    /// The current model's comparison.
    pub before: Comparison,
    /// The comparison with the named effect added.
    pub after: Option<Comparison>,
    /// The effects added in earlier steps, re-fitted with this step's effect added (the
    /// others held at their values), in the order they were added.
    pub refitted: Vec<CandidateScore>,
    /// The model's effects after this step, with their values: each (name, parameter
    /// names and units, values).
    pub effects: Vec<ModelEffect>,
    /// Wall time of the step \[s\].
    pub seconds: f64,
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
}

/// Stage 4, update: the named effect added to the model, and every effect added before
/// re-fitted in turn with the others (the new one included) held, since effects interact (a
/// scatter fitted before a mean shift was found has absorbed part of it). Returns the new
/// model's case, the re-fits, and its effects at their values.
fn update(
    ctx: &Context,
    added: &[Added],
    (new, new_values): (&dyn Candidate, &[f64]),
) -> Result<(CaseEdit, Vec<CandidateScore>, Vec<ModelEffect>), DiagnoseError> {
    let mut values: Vec<Vec<f64>> = added.iter().map(|a| a.values.clone()).collect();
    let model_with = |values: &[Vec<f64>], skip: Option<usize>| {
        let mut edit = ctx.baseline.derived_case();
        for (k, a) in added.iter().enumerate() {
            if Some(k) != skip {
                a.candidate.apply(&values[k], &mut edit)?;
            }
        }
        new.apply(new_values, &mut edit)?;
        Ok::<CaseEdit, DiagnoseError>(edit)
    };
    let n = ctx.measured.n();
    let mut refits = Vec::new();
    for (j, a) in added.iter().enumerate() {
        let c = a.candidate.as_ref();
        ctx.progress
            .note(&format!("re-fitting {} with the others held…", c.name()));
        let ev = ctx.evaluator(&model_with(&values, Some(j))?);
        let nulls: Vec<f64> = c.parameters().iter().map(|p| p.null).collect();
        let l0: f64 = ev.terms_at(c, &nulls)?.iter().sum();
        let test = Test {
            l0,
            n,
            inflation: 1.0 + n as f64 / ctx.samples as f64,
            level: ctx.settings.candidate_level(),
        };
        let f = fit_candidate(&ev, c, &test);
        ctx.simulations
            .set(ctx.simulations.get() + ev.simulations.get());
        if f.score.error.is_none() {
            values[j] = f.score.parameters.iter().map(|p| p.value).collect();
        }
        ctx.progress.note(&format!(
            "  {}: {}",
            c.name(),
            f.score
                .parameters
                .iter()
                .map(|p| format!("{} {:.4e}", p.name, p.value))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        refits.push(f.score);
    }
    let effect = |c: &dyn Candidate, v: &[f64]| ModelEffect {
        name: c.name().into(),
        parameters: c
            .parameters()
            .iter()
            .zip(v)
            .map(|(p, &x)| (p.name.clone(), p.unit, x))
            .collect(),
    };
    let mut effects: Vec<ModelEffect> = added
        .iter()
        .zip(&values)
        .map(|(a, v)| effect(a.candidate.as_ref(), v))
        .collect();
    effects.push(effect(new, new_values));
    Ok((model_with(&values, None)?, refits, effects))
}

impl Step {
    /// The named effect's name.
    pub fn named_effect(&self) -> Option<&str> {
        self.named.map(|i| self.candidates[i].name.as_str())
    }

    /// The named effect's score.
    pub fn named_score(&self) -> Option<&CandidateScore> {
        self.named.map(|i| &self.candidates[i])
    }
}

/// Runs one step against `current` with the remaining `candidates`; returns the step and,
/// when an effect is named, the model with it added (compared: the next step's stage 1).
pub(crate) fn run_step(
    ctx: &Context,
    number: usize,
    current: &ComparedModel,
    candidates: &[Box<dyn Candidate>],
    added: &[Added],
) -> Result<(Step, Option<ComparedModel>), DiagnoseError> {
    let clock = Instant::now();
    let n = ctx.measured.n();
    let ev = ctx.evaluator(&current.edit);
    let test = Test {
        l0: current.log_likelihood,
        n,
        inflation: 1.0 + n as f64 / ctx.samples as f64,
        level: ctx.settings.candidate_level() / candidates.len().max(1) as f64,
    };
    ctx.progress.note(&format!(
        "step {number}: ℓ₀ = {:.1}; {} of {} statistics disagree; energy distance {:.3} (p = {:.3}); {} candidates",
        current.log_likelihood,
        current.comparison.statistics.iter().filter(|s| s.disagrees).count(),
        current.comparison.statistics.len(),
        current.comparison.energy,
        current.comparison.energy_p,
        candidates.len()
    ));
    let mut fitted = fit_each(ctx, &ev, candidates, &test);
    let (decision, scores) = decide_and_profile(
        ctx,
        &ev,
        candidates,
        &mut fitted,
        &test,
        &current.comparison,
    );
    ctx.simulations
        .set(ctx.simulations.get() + ev.simulations.get());
    let Decision {
        verdict,
        reason,
        named,
        indistinguishable,
    } = decision;
    ctx.progress
        .note(&format!("step {number}: {}: {reason}", verdict.words()));
    let mut refitted = Vec::new();
    let mut effects = Vec::new();
    let next = match named {
        Some(i) => {
            let values: Vec<f64> = scores[i].parameters.iter().map(|p| p.value).collect();
            let (edit, refits, now) = update(ctx, added, (candidates[i].as_ref(), &values))?;
            refitted = refits;
            effects = now;
            let model = compare_model(ctx, edit)?;
            ctx.progress.note(&format!(
                "step {number}: with {}: energy distance {:.3} (p = {:.3}), was {:.3}",
                scores[i].name,
                model.comparison.energy,
                model.comparison.energy_p,
                current.comparison.energy
            ));
            Some(model)
        }
        None => None,
    };
    // An added effect must improve the fit where the likelihood does not look: the
    // discrepancy (energy distance of the displacement vectors) must shrink.
    let improves = next
        .as_ref()
        .is_none_or(|m| m.comparison.energy < current.comparison.energy);
    let (verdict, reason) = if improves {
        (verdict, reason)
    } else {
        (
            Verdict::CannotTell,
            format!(
                "{reason}; but it does not improve the fit: the discrepancy grows from {:.4} to {:.4} with it, so it is not added (the likelihood's preference rests on what the model's Gaussian approximation cannot represent)",
                current.comparison.energy,
                next.as_ref().map_or(f64::NAN, |m| m.comparison.energy)
            ),
        )
    };
    let step = Step {
        number,
        verdict,
        reason,
        named,
        kept: named.is_some() && improves,
        indistinguishable: indistinguishable
            .iter()
            .map(|&j| scores[j].name.clone())
            .collect(),
        adjusted_p: named.map(|i| (scores[i].p_value * candidates.len() as f64).min(1.0)),
        log_likelihood_before: current.log_likelihood,
        before: current.comparison.clone(),
        after: next.as_ref().map(|m| m.comparison.clone()),
        candidates: scores,
        refitted,
        effects,
        seconds: clock.elapsed().as_secs_f64(),
    };
    Ok((step, next.filter(|_| improves)))
}

/// Stage 2: every candidate fitted and tested against the current model.
fn fit_each(
    ctx: &Context,
    ev: &Evaluator,
    candidates: &[Box<dyn Candidate>],
    test: &Test,
) -> Vec<Fitted> {
    candidates
        .iter()
        .map(|c| {
            ctx.progress.note(&format!(
                "fitting {} ({} parameters)…",
                c.name(),
                c.parameters().len()
            ));
            let f = fit_candidate(ev, c.as_ref(), test);
            let s = &f.score;
            ctx.progress.note(&format!(
                "  {}: ΔBIC {:.1}, Λ {:.1}, p {}, {} evaluations in {:.1} s",
                s.name,
                s.delta_bic,
                s.lr_statistic,
                crate::report::p_text(s.p_value),
                s.evaluations,
                s.seconds
            ));
            f
        })
        .collect()
}

/// Stage 3: the verdict, and profiles of the candidates it rests on (decided again when a
/// profile moves a fit); returns the decision and the final scores, Vuong's z against the
/// named one filled in.
fn decide_and_profile(
    ctx: &Context,
    ev: &Evaluator,
    candidates: &[Box<dyn Candidate>],
    fitted: &mut [Fitted],
    test: &Test,
    before: &Comparison,
) -> (Decision, Vec<CandidateScore>) {
    let note = |m: &str| ctx.progress.note(m);
    let cache: TermsCache = RefCell::new(vec![None; candidates.len()]);
    let n = ctx.measured.n();
    let decision = loop {
        let scores: Vec<&CandidateScore> = fitted.iter().map(|f| &f.score).collect();
        let closeness = |i: usize, j: usize| {
            closeness_of(ev, candidates, fitted, &cache, test.inflation, (i, j))
                .unwrap_or(f64::INFINITY)
        };
        let d = decide(&scores, before, n, test.level, &closeness);
        let wanted: Vec<usize> = d
            .named
            .into_iter()
            .chain(d.indistinguishable.iter().copied())
            .filter(|&i| !fitted[i].profiled)
            .collect();
        if wanted.is_empty() {
            break d;
        }
        for i in wanted {
            note(&format!(
                "profile-likelihood intervals of {}…",
                candidates[i].name()
            ));
            profile_candidate(ev, candidates[i].as_ref(), &mut fitted[i], test, &note);
            let s = &fitted[i].score;
            note(&format!(
                "  {}: {} profile evaluations, {:.1} s for the fit and profiles; {}",
                s.name,
                s.profile_evaluations,
                s.seconds,
                s.parameters
                    .iter()
                    .map(|p| format!(
                        "{} {:.4e} [{}, {}]",
                        p.name,
                        p.value,
                        p.interval.lower.map_or("?".into(), |v| format!("{v:.4e}")),
                        p.interval.upper.map_or("?".into(), |v| format!("{v:.4e}"))
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    };
    let mut scores: Vec<CandidateScore> = fitted.iter().map(|f| f.score.clone()).collect();
    if let Some(i) = decision.named {
        for (j, s) in scores.iter_mut().enumerate() {
            if j != i && s.significant && s.error.is_none() {
                s.vuong_z = closeness_of(ev, candidates, fitted, &cache, test.inflation, (i, j));
            }
        }
    }
    (decision, scores)
}

/// Vuong's z of fitted candidate i against j ([`vuong`]), `inflation` = c = 1 + n/N;
/// `None` if a simulation failed.
fn closeness_of(
    ev: &Evaluator,
    candidates: &[Box<dyn Candidate>],
    fitted: &[Fitted],
    cache: &TermsCache,
    inflation: f64,
    (i, j): (usize, usize),
) -> Option<f64> {
    let a = fitted_terms(ev, candidates[i].as_ref(), &fitted[i], cache, i)?;
    let b = fitted_terms(ev, candidates[j].as_ref(), &fitted[j], cache, j)?;
    Some(vuong(&a, &b, &ev.measured.clusters(), inflation))
}

/// Each candidate's fitted parameter values and ℓ's per-unit terms there.
type TermsCache = RefCell<Vec<Option<(Vec<f64>, Terms)>>>;

/// ℓ's per-unit terms at a candidate's fit, computed once per fitted point (one simulation).
fn fitted_terms(
    ev: &Evaluator,
    c: &dyn Candidate,
    fitted: &Fitted,
    cache: &TermsCache,
    i: usize,
) -> Option<Terms> {
    let values: Vec<f64> = fitted.score.parameters.iter().map(|p| p.value).collect();
    if let Some((at, terms)) = &cache.borrow()[i]
        && at == &values
    {
        return Some(terms.clone());
    }
    let terms = ev.terms_at(c, &values).ok()?;
    cache.borrow_mut()[i] = Some((values, terms.clone()));
    Some(terms)
}
