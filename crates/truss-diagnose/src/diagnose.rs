//! The stepwise selection: find the strongest missing effect, add it, look again at what is
//! left, and repeat until nothing significant remains ([`diagnose`]).
//!
//! Each step ([`crate::step`]) compares the current model (the baseline with the effects
//! added so far) with the measurements, fits and tests every remaining candidate against it
//! ([`crate::score`]), decides from the tests and BIC ([`decide`]; the named candidate and
//! those indistinguishable from it get profile-likelihood intervals, [`crate::profile`], and
//! should a profile find a higher maximum the verdict is decided again on the new fits), and
//! adds the named effect at its fitted values; then every effect of the model is re-fitted
//! jointly, the effects added earlier are tested for removal given the others and tried
//! swapped for a rival ([`crate::stepwise`]). The selection stops at the first step that
//! names nothing (no candidate both significant at α/K and better by ΔBIC ≤ −2), at a named
//! effect that makes the fit worse where the likelihood does not look (the model agreed in
//! distribution, and with the effect the discrepancy, the energy distance of the
//! displacement vectors, grows beyond its noise or turns significant: then it is not
//! added; [`crate::step`]), or when no candidate is left. The false discovery rate over the
//! steps is controlled by [`forward_stop`] on the steps' Bonferroni-adjusted p-values: named
//! effects beyond its k̂ are not kept, and the final model is the one after the k̂-th kept
//! step, with the removals and swaps of the steps up to it.

use crate::baseline::{Baseline, CaseEdit};
use crate::candidates::library_for;
use crate::compare::Comparison;
use crate::errors::DiagnoseError;
use crate::measured::Measured;
pub use crate::score::{CandidateScore, FittedParameter, SCAN};
use crate::simulate::{Noise, Simulation, top_indices};
use crate::step::{Added, Context, ModelEffect, Step, compare_model, run_step};
use serde::Serialize;
use std::time::Instant;

/// Evidence that counts as a clear improvement and as "as good": a BIC difference of 2
/// (Kass & Raftery 1995: below 2 "not worth more than a bare mention").
pub const DELTA_BIC: f64 = 2.0;
/// Vuong's z below which the named candidate is not shown closer to the data's distribution
/// than another significant candidate (two-sided 5 %): the other is listed as
/// indistinguishable.
pub const VUONG_Z: f64 = 1.96;
/// Fewest specimens for the verdict `unexplained`: below it the large-sample intervals of
/// single statistics (covariances above all) are not trusted to show a disagreement that no
/// candidate explains, and the verdict is `cannot_tell`.
pub const MIN_FOR_DISAGREEMENT: usize = 30;
/// Seed of the simulated instrument noise.
pub const NOISE_SEED: u64 = 0x006e_6f69_7365;

/// How to diagnose.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Simulated samples per evaluation; `None`: max(2000, 20·n), at most 10 000.
    pub samples: Option<usize>,
    /// The instrument's standard deviation σ_m \[mm\].
    pub measurement_sigma: f64,
    /// The false-positive rate of the whole verdict on data that miss nothing. Half of it,
    /// [`Settings::candidate_level`], goes to the candidates' likelihood-ratio tests
    /// (Bonferroni over the candidates within a step, ForwardStop over the steps); the other
    /// half is the comparison's ([`crate::compare::LEVEL`], fixed at 0.025).
    pub alpha: f64,
    /// No progress on stderr.
    pub quiet: bool,
    /// Only these candidates (by name); `None`: every applicable one.
    pub candidates: Option<Vec<String>>,
    /// With member measurements, condition each specimen's node term on its own measured
    /// members ([`crate::conditional`]); `false`: the member measurements only enter as
    /// draws from the case's distributions (the older, distribution-only use, kept for
    /// comparison).
    pub condition_on_members: bool,
}

impl Settings {
    /// The candidates' family-wise level: α/2 (see [`Settings::alpha`]).
    pub fn candidate_level(&self) -> f64 {
        self.alpha / 2.0
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            samples: None,
            measurement_sigma: 0.0,
            alpha: 0.05,
            quiet: false,
            candidates: None,
            condition_on_members: true,
        }
    }
}

impl Settings {
    /// N for `n` specimens.
    pub fn samples_for(&self, n: usize) -> usize {
        self.samples.unwrap_or_else(|| (20 * n).clamp(2000, 10_000))
    }
}

/// Progress lines on stderr with the elapsed time.
pub struct Progress {
    quiet: bool,
    start: Instant,
}

impl Progress {
    /// Starts the clock.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            start: Instant::now(),
        }
    }
    /// Prints a line.
    pub fn note(&self, message: &str) {
        if !self.quiet {
            eprintln!("[{:6.1} s] {message}", self.start.elapsed().as_secs_f64());
        }
    }
    /// Seconds since the start.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// The verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// A candidate explains the disagreement and is named.
    Named,
    /// The baseline agrees within tolerance and no candidate improves it significantly.
    None,
    /// The data cannot decide (see the crate doc).
    CannotTell,
    /// The baseline disagrees but no candidate in the library explains it.
    Unexplained,
}

impl Verdict {
    /// The verdict as `diagnosis.json` writes it (`named`, `none`, `cannot_tell`,
    /// `unexplained`).
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Named => "named",
            Verdict::None => "none",
            Verdict::CannotTell => "cannot_tell",
            Verdict::Unexplained => "unexplained",
        }
    }

    /// The verdict in words.
    pub fn words(self) -> &'static str {
        match self {
            Verdict::Named => "a missing effect is named",
            Verdict::None => "the model agrees; no effect is missing",
            Verdict::CannotTell => "the data cannot tell",
            Verdict::Unexplained => "the model disagrees, and no candidate explains it",
        }
    }
}

/// A complete diagnosis: the steps of the stepwise selection and the final model.
pub struct Diagnosis {
    /// The overall verdict: `named` when an effect was added, else step 1's.
    pub verdict: Verdict,
    /// Why, in a sentence or two.
    pub reason: String,
    /// The steps, in order; the last one named nothing, or its effect was not kept, or no
    /// candidate was left.
    pub steps: Vec<Step>,
    /// Candidates not applicable to this case, with why.
    pub skipped: Vec<(String, String)>,
    /// ℓ₀ of the baseline.
    pub baseline_log_likelihood: f64,
    /// The baseline's comparison.
    pub before: Comparison,
    /// The final model's comparison, when an effect was added.
    pub after: Option<Comparison>,
    /// The final case: the baseline with every kept effect (the baseline's when none).
    pub updated: CaseEdit,
    /// The final model's effects at their final values (after the re-fits).
    pub effects: Vec<ModelEffect>,
    /// Simulated samples per evaluation N.
    pub samples: usize,
    /// The simulations behind `before` and `after` (for plots).
    pub simulations: (Simulation, Option<Simulation>),
    /// Top-surface coordinate indices.
    pub top: [[usize; 3]; 3],
    /// Total simulations run, solves, and seconds.
    pub work: (usize, usize, f64),
}

impl Diagnosis {
    /// The effects of the final model in the order they entered it: each kept step's named
    /// effect, less those a kept step removed, a swapped one's replacement in its place.
    pub fn named_effects(&self) -> Vec<&str> {
        final_effects(&self.steps)
    }

    /// The first added effect's name, or `none`.
    pub fn named_effect(&self) -> &str {
        self.named_effects().first().copied().unwrap_or("none")
    }

    /// The step that added the first effect (or step 1).
    pub fn first_step(&self) -> &Step {
        &self.steps[0]
    }
}

/// The effects of the final model in the order they entered it ([`Diagnosis::named_effects`]).
fn final_effects(steps: &[Step]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for s in steps.iter().filter(|s| s.kept) {
        names.extend(s.named_effect());
        for r in &s.removed {
            match &r.replaced_by {
                Some(by) => {
                    for n in names.iter_mut().filter(|n| **n == r.name) {
                        *n = by.as_str();
                    }
                }
                None => names.retain(|n| *n != r.name),
            }
        }
    }
    names
}

/// The verdict, why, the named candidate and those indistinguishable from it (indices).
#[derive(Debug, Clone)]
pub struct Decision {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence or two.
    pub reason: String,
    /// The named candidate.
    pub named: Option<usize>,
    /// Candidates within ΔBIC 2 of the named one.
    pub indistinguishable: Vec<usize>,
}

/// Vuong's (1989) statistic for two non-nested models fitted to the same data: with
/// `a` and `b` the per-unit terms of their maximised ℓ and `d_u` their difference summed
/// over each cluster u (a specimen with its member observations), of n_u clusters,
/// `z = Σ d_u / √(c·n_u·var(d))`, c = 1 + n/N for the simulation's own noise in both fits.
/// Positive: `a` closer. Zero when the two predict the same for every unit.
pub fn vuong(a: &[f64], b: &[f64], clusters: &[usize], inflation: f64) -> f64 {
    let units = clusters.iter().max().map_or(0, |m| m + 1);
    let mut d = vec![0.0; units];
    for ((x, y), &u) in a.iter().zip(b).zip(clusters) {
        d[u] += x - y;
    }
    if units < 2 {
        return 0.0;
    }
    let n = units as f64;
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    if var > 0.0 {
        sum / (inflation * n * var).sqrt()
    } else {
        0.0
    }
}

/// The verdict from the candidates' scores and the baseline's comparison (crate doc):
/// `level` is the per-candidate significance level α/K; `closeness(i, j)` is Vuong's z of
/// candidate i against j ([`vuong`]), asked only of significant candidates.
pub fn decide(
    scores: &[&CandidateScore],
    before: &Comparison,
    n: usize,
    level: f64,
    closeness: &dyn Fn(usize, usize) -> f64,
) -> Decision {
    let before_disagrees = before.statistics.iter().any(|s| s.disagrees);
    let best = (0..scores.len())
        .filter(|&i| scores[i].error.is_none())
        .min_by(|&a, &b| scores[a].delta_bic.total_cmp(&scores[b].delta_bic));
    let clear = best.filter(|&i| scores[i].significant && scores[i].delta_bic <= -DELTA_BIC);
    let (verdict, reason, named, indistinguishable) = if let Some(i) = clear {
        let candidates = (0..scores.len()).filter(|&j| j != i && scores[j].error.is_none());
        let by_bic: Vec<usize> = candidates
            .clone()
            .filter(|&j| scores[j].delta_bic < scores[i].delta_bic + DELTA_BIC)
            .collect();
        let by_vuong: Vec<(usize, f64)> = candidates
            .filter(|&j| !by_bic.contains(&j) && scores[j].significant)
            .map(|j| (j, closeness(i, j)))
            .filter(|&(_, z)| z < VUONG_Z)
            .collect();
        let names = |js: &mut dyn Iterator<Item = usize>| {
            js.map(|j| scores[j].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut reason = format!(
            "{} improves the likelihood significantly ({} < α/K = {level:.4}) and is the best by BIC",
            scores[i].name,
            crate::report::p_is(scores[i].p_value),
        );
        if by_bic.is_empty() && by_vuong.is_empty() {
            reason += &format!(
                " by at least {DELTA_BIC} over every other candidate, and fits significantly closer than every other significant one (Vuong z ≥ {VUONG_Z})"
            );
        }
        if !by_bic.is_empty() {
            reason += &format!(
                "; {} explain the data as well (ΔBIC within {DELTA_BIC})",
                names(&mut by_bic.iter().copied())
            );
        }
        if !by_vuong.is_empty() {
            reason += &format!(
                "; {} also improve significantly and it does not fit significantly closer than they do ({})",
                names(&mut by_vuong.iter().map(|&(j, _)| j)),
                by_vuong
                    .iter()
                    .map(|&(j, z)| format!("Vuong z = {z:.2} against {}", scores[j].name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if !by_bic.is_empty() || !by_vuong.is_empty() {
            reason += ": the data cannot tell them apart";
        }
        let mut others = by_bic;
        others.extend(by_vuong.iter().map(|&(j, _)| j));
        (Verdict::Named, reason, Some(i), others)
    } else if scores
        .iter()
        .any(|s| s.significant || s.delta_bic < -DELTA_BIC)
    {
        (
            Verdict::CannotTell,
            "some candidates improve the fit, but none both significantly (Bonferroni) and by a clear BIC margin: the data cannot decide".into(),
            None,
            Vec::new(),
        )
    } else if before.tolerance.within {
        (
            Verdict::None,
            "no candidate improves the fit significantly, and the model agrees with the measurements within the stated tolerance".into(),
            None,
            Vec::new(),
        )
    } else if before_disagrees && n >= MIN_FOR_DISAGREEMENT {
        (
            Verdict::Unexplained,
            "the measurements disagree with the model, but no candidate effect of the library explains it significantly".into(),
            None,
            Vec::new(),
        )
    } else {
        (
            Verdict::CannotTell,
            format!(
                "no candidate improves the fit significantly, but with {n} specimens the data cannot show that the model agrees within tolerance either ({} outside){}: more specimens are needed",
                before.tolerance.outside.join(", "),
                if before_disagrees {
                    ", and the few statistics that disagree are too uncertain with so few specimens"
                } else {
                    ""
                }
            ),
            None,
            Vec::new(),
        )
    };
    Decision {
        verdict,
        reason,
        named,
        indistinguishable,
    }
}

/// Most steps of the selection: one per candidate at most.
pub const MAX_STEPS: usize = 6;

/// The number of steps whose named effects are kept: ForwardStop (G'Sell, Wager,
/// Chouldechova & Tibshirani 2016) at level α on the steps' adjusted p-values
/// pₛ = min(1, Kₛ·p) (Bonferroni over the step's Kₛ candidates):
/// k̂ = max{k : −(1/k)·Σ_{s ≤ k} ln(1 − pₛ) ≤ α}, 0 if none. It controls the false
/// discovery rate over the steps at α when the p-values of the effects that are not there
/// are uniform and come after those that are; the first step alone is the Bonferroni test
/// (−ln(1 − p₁) ≤ α is p₁ ≤ 1 − e^(−α) ≈ α).
pub fn forward_stop(adjusted: &[f64], alpha: f64) -> usize {
    let mut sum = 0.0;
    let mut kept = 0;
    for (k, &p) in adjusted.iter().enumerate() {
        sum += -(1.0 - p.min(1.0)).ln();
        if sum / (k + 1) as f64 <= alpha {
            kept = k + 1;
        }
    }
    kept
}

/// The stepwise selection on measured data against the baseline case: step after step
/// ([`crate::step`]), each adding the strongest missing effect to the model, until no
/// candidate is significant and clearly better by BIC, or none is left; then the false
/// discovery rate over the steps decides how many of the named effects are kept
/// ([`forward_stop`]).
pub fn diagnose(
    baseline: &Baseline,
    measured: &Measured,
    settings: &Settings,
    progress: &Progress,
) -> Result<Diagnosis, DiagnoseError> {
    let n = measured.n();
    let samples = settings.samples_for(n);
    let model = baseline.model();
    let top_nodes = model.top_surface().expect("checked when reading").nodes;
    let top = top_indices(&measured.coords, top_nodes).expect("top nodes are measured");
    let ctx = Context {
        baseline,
        measured,
        settings,
        samples,
        noise: Noise {
            sigma: settings.measurement_sigma,
            seed: NOISE_SEED,
        },
        top,
        progress,
        simulations: std::cell::Cell::new(0),
    };
    progress.note(&format!(
        "{n} specimens, {} coordinates; simulating the baseline case {:?} ({samples} samples)",
        measured.d(),
        baseline.case_name
    ));
    let mut models = vec![compare_model(&ctx, baseline.derived_case())?];
    let (mut remaining, mut skipped) = library_for(baseline, measured.members.is_some());
    if let Some(only) = &settings.candidates {
        for name in only {
            if !remaining.iter().any(|c| c.name() == name)
                && !skipped.iter().any(|(n, _)| n == name)
            {
                return Err(DiagnoseError::Usage(format!(
                    "--candidates: no candidate effect {name:?} (the library: backlash, gravity, thermal_gradient, length_bias, length_sigma, diagonal_pretension)"
                )));
            }
        }
        let (asked, left): (Vec<_>, Vec<_>) = remaining
            .into_iter()
            .partition(|c| only.iter().any(|n| n == c.name()));
        skipped.extend(left.iter().map(|c| {
            (
                c.name().to_string(),
                "not asked for (--candidates)".to_string(),
            )
        }));
        remaining = asked;
    }
    if remaining.is_empty() {
        return Err(DiagnoseError::Usage(
            "no candidate effect applies to this case (see the skipped reasons with --candidates unset)".into(),
        ));
    }
    let mut steps: Vec<Step> = Vec::new();
    let mut added: Vec<Added> = Vec::new();
    while steps.len() < MAX_STEPS && !remaining.is_empty() {
        let current = models.last().expect("the baseline is there");
        let (step, next) = run_step(&ctx, steps.len() + 1, current, &remaining, &added)?;
        let named = step.named;
        let now = step.effects.clone();
        steps.push(step);
        match (named, next) {
            (Some(i), Some(model)) => {
                let step = steps.last_mut().expect("just pushed");
                let named = &step.candidates[i];
                let rivals = step
                    .candidates
                    .iter()
                    .enumerate()
                    .filter(|&(j, c)| {
                        j != i
                            && c.significant
                            && c.error.is_none()
                            && c.delta_bic <= 0.5 * named.delta_bic
                    })
                    .map(|(_, c)| {
                        (
                            c.name.clone(),
                            c.parameters.iter().map(|p| p.value).collect(),
                        )
                    })
                    .collect();
                let candidate = remaining.remove(i);
                added.push(Added {
                    candidate,
                    values: Vec::new(),
                    step: step.number,
                    rivals,
                });
                for r in &step.removed {
                    let Some(by) = &r.replaced_by else { continue };
                    let e = added
                        .iter()
                        .position(|a| a.candidate.name() == r.name)
                        .expect("a swapped effect is in the model");
                    let j = remaining
                        .iter()
                        .position(|c| c.name() == by)
                        .expect("a swapped-in candidate was remaining");
                    added[e] = Added {
                        candidate: remaining.remove(j),
                        values: Vec::new(),
                        step: step.number,
                        rivals: Vec::new(),
                    };
                }
                added.retain(|a| {
                    !step
                        .removed
                        .iter()
                        .any(|r| r.replaced_by.is_none() && r.name == a.candidate.name())
                });
                for (a, e) in added.iter_mut().zip(now) {
                    debug_assert_eq!(a.candidate.name(), e.name);
                    a.values = e.parameters.iter().map(|p| p.2).collect();
                }
                let taken_over: Vec<(String, String)> = step
                    .removed
                    .iter()
                    .filter_map(|r| r.explained_by.clone().map(|x| (x, r.name.clone())))
                    .collect();
                for (by, name) in taken_over {
                    if let Some(s) = steps
                        .iter_mut()
                        .find(|s| s.kept && s.named_effect() == Some(by.as_str()))
                        && !s.indistinguishable.contains(&name)
                    {
                        s.indistinguishable.push(name);
                    }
                }
                models.push(model);
            }
            _ => break,
        }
    }
    let adjusted: Vec<f64> = steps
        .iter()
        .filter(|s| s.kept)
        .filter_map(|s| s.adjusted_p)
        .collect();
    let kept = forward_stop(&adjusted, settings.candidate_level());
    for s in steps.iter_mut().filter(|s| s.kept).skip(kept) {
        s.kept = false;
        s.verdict = Verdict::CannotTell;
        s.reason += &format!(
            "; not kept: over the steps, the false discovery rate at α = {} keeps only the first {kept} named effects (ForwardStop on the steps' adjusted p-values {})",
            settings.candidate_level(),
            adjusted
                .iter()
                .map(|p| crate::report::p_text(*p))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let (verdict, reason) = overall(&steps, kept);
    let effects = steps
        .iter()
        .filter(|s| s.kept)
        .nth(kept.max(1) - 1)
        .filter(|_| kept > 0)
        .map_or_else(Vec::new, |s| s.effects.clone());
    progress.note(&format!("{}: {reason}", verdict.words()));
    let sims = ctx.simulations.get();
    let mut models = models.into_iter();
    let base = models.next().expect("the baseline is there");
    let last = models.nth(kept.max(1) - 1).filter(|_| kept > 0);
    Ok(Diagnosis {
        verdict,
        reason,
        steps,
        skipped,
        baseline_log_likelihood: base.log_likelihood,
        before: base.comparison,
        updated: last.as_ref().map_or(base.edit, |m| m.edit.clone()),
        effects,
        after: last.as_ref().map(|m| m.comparison.clone()),
        simulations: (base.simulation, last.map(|m| m.simulation)),
        samples,
        top,
        work: (sims, sims * samples, progress.seconds()),
    })
}

/// The overall verdict and reason from the steps, `kept` of whose named effects are kept.
fn overall(steps: &[Step], kept: usize) -> (Verdict, String) {
    if kept == 0 {
        let first = &steps[0];
        return (first.verdict, first.reason.clone());
    }
    let added: Vec<String> = steps
        .iter()
        .filter(|s| s.kept)
        .map(|s| {
            format!(
                "step {}: {} ({})",
                s.number,
                s.named_effect().unwrap_or("none"),
                s.reason
            )
        })
        .collect();
    let last = steps.last().expect("at least one step");
    let end = if last.kept {
        "no candidate is left to try".to_string()
    } else {
        format!("step {}: {}", last.number, last.reason)
    };
    let names = final_effects(steps);
    let model = if names.len() == kept {
        String::new()
    } else {
        format!(
            " (the final model has {}: the others were removed or replaced on the way)",
            names.join(" and ")
        )
    };
    (
        Verdict::Named,
        format!(
            "{kept} effect{} added in turn{model}. {}. Finally, {end}",
            if kept == 1 { "" } else { "s" },
            added.join(". ")
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::Tolerance;

    fn score(name: &str, k: usize, delta_bic: f64, significant: bool) -> CandidateScore {
        CandidateScore {
            name: name.into(),
            mechanism: String::new(),
            k,
            parameters: Vec::new(),
            log_likelihood: 0.0,
            lr_statistic: 0.0,
            adjustment: 1.0,
            p_value: if significant { 1e-6 } else { 0.5 },
            significant,
            delta_bic,
            evaluations: 0,
            profile_evaluations: 0,
            seconds: 0.0,
            vuong_z: None,
            error: None,
        }
    }

    fn comparison() -> Comparison {
        Comparison {
            specimens: 200,
            samples: 4000,
            statistics: Vec::new(),
            energy: 0.0,
            energy_p: 1.0,
            energy_noise: 0.0,
            tolerance: Tolerance {
                within: true,
                outside: Vec::new(),
                bands: String::new(),
            },
        }
    }

    /// The best by BIC is named; a significant candidate 3 BIC worse that it does not fit
    /// significantly closer than (z = 1.0) is indistinguishable, one it does (z = 4.0) is
    /// not, and a candidate that is not significant is not asked about.
    #[test]
    fn indistinguishable_by_bic_or_by_closeness() {
        let s = [
            score("a", 1, -14.0, true),
            score("b", 2, -11.0, true),
            score("c", 2, -10.5, true),
            score("d", 1, -12.5, true),
            score("e", 3, 5.0, false),
        ];
        let refs: Vec<&CandidateScore> = s.iter().collect();
        let asked = std::cell::RefCell::new(Vec::new());
        let z = |i: usize, j: usize| {
            asked.borrow_mut().push((i, j));
            if j == 1 { 1.0 } else { 4.0 }
        };
        let d = decide(&refs, &comparison(), 200, 0.01, &z);
        assert_eq!(d.verdict, Verdict::Named);
        assert_eq!(d.named, Some(0));
        assert_eq!(d.indistinguishable, vec![3, 1]);
        assert_eq!(*asked.borrow(), vec![(0, 1), (0, 2)]);
        assert!(
            d.reason.contains("Vuong z = 1.00 against b"),
            "{}",
            d.reason
        );
        let clear = decide(&refs[..3], &comparison(), 200, 0.01, &|_, _| 4.0);
        assert!(clear.indistinguishable.is_empty());
        assert!(
            clear.reason.contains("closer than every other"),
            "{}",
            clear.reason
        );
    }

    /// The final model's effects from the steps: each kept step's named effect in turn, a
    /// removed one taken out, a swapped one's replacement in its place, and nothing of a
    /// step that is not kept (its removals included).
    #[test]
    fn final_effects_follow_removals_and_swaps() {
        use crate::stepwise::Removal;
        let removal = |name: &str, by: Option<&str>| Removal {
            name: name.into(),
            replaced_by: by.map(String::from),
            added_in_step: 1,
            lr_statistic: 0.0,
            p_value: None,
            delta_bic: 0.0,
            explained_by: None,
            separate_by: String::new(),
        };
        let step = |number: usize, named: &str, kept: bool, removed: Vec<Removal>| Step {
            number,
            verdict: Verdict::Named,
            reason: String::new(),
            named: Some(0),
            kept,
            indistinguishable: Vec::new(),
            candidates: vec![score(named, 1, -10.0, true)],
            log_likelihood_before: 0.0,
            adjusted_p: Some(0.0),
            before: comparison(),
            after: None,
            refitted: Vec::new(),
            removed,
            effects: Vec::new(),
            seconds: 0.0,
        };
        let steps = vec![
            step(1, "length_bias", true, Vec::new()),
            step(
                2,
                "length_sigma",
                true,
                vec![removal("length_bias", Some("diagonal_pretension"))],
            ),
            step(
                3,
                "thermal_gradient",
                true,
                vec![removal("length_sigma", None)],
            ),
            step(4, "gravity", false, vec![removal("thermal_gradient", None)]),
        ];
        assert_eq!(
            final_effects(&steps),
            ["diagonal_pretension", "thermal_gradient"]
        );
        assert_eq!(
            final_effects(&steps[..2]),
            ["diagonal_pretension", "length_sigma"]
        );
        assert!(final_effects(&steps[3..]).is_empty());
    }

    /// ForwardStop by hand: −ln(1 − p) for p = 0.01, 0.04, 0.2 is 0.01005, 0.04082, 0.22314;
    /// running means 0.01005, 0.02544, 0.09134: at α = 0.05 the first two are kept; a first
    /// step at p = 0.06 keeps none even though a later one is tiny (mean 0.0309 ≤ 0.05 at
    /// k = 2 keeps both: ForwardStop is about the rate, not each step); none for no steps.
    #[test]
    fn forward_stop_keeps_the_longest_prefix_within_alpha() {
        assert_eq!(forward_stop(&[0.01, 0.04, 0.2], 0.05), 2);
        assert_eq!(forward_stop(&[0.06], 0.05), 0);
        assert_eq!(forward_stop(&[0.06, 1e-9], 0.05), 2);
        assert_eq!(forward_stop(&[1.0, 0.0], 0.05), 0);
        assert_eq!(forward_stop(&[], 0.05), 0);
    }

    /// p-values for people: below what a double tells from 0, `< 1e-16`, never `0.00e0`.
    #[test]
    fn p_values_read_plainly() {
        use crate::report::{p_is, p_text};
        assert_eq!(p_text(0.0), "< 1e-16");
        assert_eq!(p_is(1e-20), "p < 1e-16");
        assert_eq!(p_is(0.034), "p = 0.03");
        assert_eq!(p_text(2.5e-7), "2.5e-7");
    }

    /// Vuong's z by hand: units 0, 1, 2 with differences 1, 3, 2 (unit 2's split over two
    /// terms, as a specimen's member observations are): sum 6, variance 1, z = 6/√3; and
    /// with c = 4 half that. Identical fits give 0, and swapping the models changes the sign.
    #[test]
    fn vuong_sums_clusters_and_scales_by_their_spread() {
        let a = [1.0, 3.0, 1.5, 0.5];
        let b = [0.0, 0.0, 0.0, 0.0];
        let clusters = [0, 1, 2, 2];
        let z = vuong(&a, &b, &clusters, 1.0);
        assert!((z - 6.0 / 3f64.sqrt()).abs() < 1e-12, "{z}");
        assert!((vuong(&a, &b, &clusters, 4.0) - z / 2.0).abs() < 1e-12);
        assert_eq!(vuong(&b, &a, &clusters, 1.0), -z);
        assert_eq!(vuong(&a, &a, &clusters, 1.0), 0.0);
    }
}
