//! The selection: find the strongest missing effect, add it, look again at what is left,
//! and repeat until nothing significant remains ([`diagnose`]).
//!
//! Each step ([`step`]) passes through four stages in order: it compares the current model
//! (the baseline with the effects added so far) with the measurements, fits and tests every
//! remaining candidate against it ([`crate::likelihood::score`]), decides from the tests and
//! BIC ([`decide`]; at the first step, and at a later one whose update leaves its effect
//! alone in the model, the named candidate and those indistinguishable from it get
//! profile-likelihood intervals, [`crate::likelihood::profile`], and should a profile find a
//! higher maximum at the first step the verdict is decided again on the new fits; then a pair of candidates
//! whose effects interact, one of them significant and neither named, is fitted jointly
//! and named in the step's effect's place when it is significant and better by BIC, or
//! listed as an alternative reading when as good, [`pair`]: forward selection adds one
//! effect at a time, and two effects that show only together would each fit poorly
//! alone), and updates the model
//! ([`update`]): the named effect is added at its fitted values, every effect of the model
//! is re-fitted jointly, the effects added earlier are tested for removal given the others
//! and tried swapped for a rival. The selection stops at the first step that names nothing
//! (no candidate both significant at α/K and better by ΔBIC ≤ −2), at a named effect that
//! makes the fit worse where the likelihood does not look (judged by the next step's
//! comparison: the model agreed in distribution, and with the effect the discrepancy, the
//! energy distance of the displacement vectors, grows beyond its noise or turns
//! significant: then it is not added; [`step`]), or when no candidate is left. The false
//! discovery rate over the steps is controlled by [`forward_stop`] on the steps'
//! Bonferroni-adjusted p-values: named effects beyond its k̂ are not kept, and the final
//! model is the one after the k̂-th kept step, with the removals and swaps of the steps up
//! to it.
//!
//! ## The false discovery rate
//!
//! ForwardStop ([`forward_stop`]) runs on the adjusted p-values of the
//! steps in the order they named effects, whatever was removed later: the number of steps
//! it keeps is decided as without removals, and the final model is that after the last kept
//! step, with the removals of the kept steps. Removal only takes effects out of the model,
//! so the effects finally named are a subset of those ForwardStop accepts: the number of
//! false discoveries among them is never larger, and the probability of any false discovery
//! is at most that of forward selection alone.

pub mod confound;
pub mod decide;
pub mod eliminate;
pub mod model;
pub mod pair;
pub mod ridge;
pub mod step;
pub mod unseen;
pub mod update;

use crate::candidates::{Library, library_for, names};
use crate::comparison::baseline::{Baseline, CaseEdit};
use crate::comparison::measured::Measured;
use crate::comparison::simulate::{Noise, Simulation, top_indices};
use crate::comparison::statistics::Comparison;
use crate::errors::DiagnoseError;
use crate::likelihood::conditional::GaugeNoise;
use crate::likelihood::score::p_text;
use crate::settings::{NOISE_SEED, Progress, Settings};
use confound::Confounding as Confound;
use decide::Verdict;
use model::{ComparedModel, Context, ModelEffect, Pool};
use step::Step;

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
    /// Every candidate the library has for this case (the reports read their words here).
    pub library: Vec<Box<dyn crate::candidates::Candidate>>,
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
    /// The final model's effects fitted jointly, with the joint fit's intervals (profile
    /// where the Wald one is cut at the range; [`confound`]); empty when none was added.
    pub final_fit: Vec<model::RefitEffect>,
    /// Rivals that explain part of what the final model's effects explain ([`confound`]).
    pub confounding: Vec<confound::Confounding>,
    /// What the data cannot tell apart from each effect that entered the model
    /// ([`indistinguishable`]): the one record that `diagnosis.json`'s `indistinguishable`
    /// fields and `diagnosis.md` read.
    pub indistinguishable: Vec<Indistinguishable>,
    /// The candidates not in the final model, with the smallest effect of each these data
    /// would have detected ([`unseen`]).
    pub unseen: Vec<crate::likelihood::power::Unseen>,
    /// Wall time of the final fit and the confounding tests \[s\].
    pub final_seconds: f64,
    /// Each stage's wall time and simulations, in order.
    pub stages: Vec<model::StageTime>,
    /// Worker threads of the simulations.
    pub threads: usize,
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

    /// The rivals indistinguishable from `effect` as it entered the model at step `step`
    /// (named or swapped in; [`indistinguishable`]); empty when there is no such record.
    pub fn indistinguishable_of(&self, effect: &str, step: usize) -> &[String] {
        self.indistinguishable
            .iter()
            .find(|r| r.effect == effect && r.step == step)
            .map_or(&[][..], |r| &r.rivals)
    }

    /// The rivals indistinguishable from the final model's `effect`, where it last entered
    /// the model in a kept step.
    pub fn indistinguishable_of_final(&self, effect: &str) -> &[String] {
        self.indistinguishable
            .iter()
            .rfind(|r| r.effect == effect && r.kept)
            .map_or(&[][..], |r| &r.rivals)
    }

    /// The first added effect's name, or `none`.
    pub fn named_effect(&self) -> &str {
        self.named_effects().first().copied().unwrap_or("none")
    }

    /// The candidate of this name in the library.
    pub fn candidate(&self, name: &str) -> Option<&dyn crate::candidates::Candidate> {
        self.library
            .iter()
            .find(|c| c.name() == name)
            .map(|c| c.as_ref())
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
        names.extend(s.named_effects());
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
/// Runs the stepwise selection (module doc).
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
        memo: Default::default(),
        gauge: GaugeNoise::new(samples, measured),
        stages: Default::default(),
    };
    progress.note(&format!(
        "{n} specimens, {} coordinates; simulating the baseline case {:?} ({samples} samples)",
        measured.d(),
        baseline.case_name
    ));
    let (remaining, skipped) = asked_for(baseline, measured, settings)?;
    let mut pool = Pool {
        remaining,
        added: Vec::new(),
    };
    let mut models: Vec<ComparedModel> = Vec::new();
    let mut steps: Vec<Step> = Vec::new();
    let mut edit = Some(baseline.derived_case());
    while let Some(e) = edit.take() {
        let stage = match steps.len() {
            0 => "baseline: simulate and compare".to_string(),
            k => format!("step {k}: compare the updated model"),
        };
        let previous = steps.last_mut().zip(models.last());
        let Some(current) = ctx.timed(stage, None, || step::compare(&ctx, e, previous))? else {
            break;
        };
        models.push(current);
        if steps.len() == MAX_STEPS || pool.remaining.is_empty() {
            break;
        }
        let current = models.last().expect("just compared");
        let (s, next) = step::run(&ctx, steps.len() + 1, current, &mut pool)?;
        steps.push(s);
        edit = next;
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
                .map(|p| p_text(*p))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let (verdict, reason) = overall(&steps, kept);
    let last = steps
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kept)
        .nth(kept.max(1) - 1)
        .filter(|_| kept > 0)
        .map(|(i, _)| i);
    let effects = last.map_or_else(Vec::new, |i| steps[i].effects.clone());
    progress.note(&format!("{}: {reason}", verdict.words()));
    let library = library_for(baseline, measured.members.is_some()).0;
    let clock = std::time::Instant::now();
    let (final_fit, confounding) = match last {
        Some(i) => {
            let fit = ctx.timed("final fit", None, || {
                confound::final_fit(&ctx, &steps[..=i], &steps[i], &library)
            });
            let found = ctx.timed("confounding", None, || {
                confound::confounding(&ctx, &steps[..=i], &fit, &library)
            });
            (fit.effects, found)
        }
        None => (Vec::new(), Vec::new()),
    };
    let indistinguishable = indistinguishable(&steps, &confounding);
    let final_seconds = clock.elapsed().as_secs_f64();
    let unseen = unseen::unseen(
        &steps,
        last.map_or(0, |i| i + 1),
        &final_effects(&steps),
        n,
        &library,
    );
    let sims = ctx.simulations.get();
    let stages = ctx.stages.take();
    progress.note(&format!(
        "times: {}",
        stages
            .iter()
            .map(|t| format!(
                "{} {:.1} s ({} simulations)",
                t.stage, t.seconds, t.simulations
            ))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    let mut models = models.into_iter();
    let base = models.next().expect("the baseline is there");
    let last = models.nth(kept.max(1) - 1).filter(|_| kept > 0);
    Ok(Diagnosis {
        verdict,
        reason,
        steps,
        skipped,
        library,
        final_fit,
        confounding,
        indistinguishable,
        unseen,
        final_seconds,
        stages,
        threads: settings.thread_count(),
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

/// The candidates to try: the library's for this baseline (backlash's spread only with the
/// members measured), less those `--candidates` leaves out; and the (name, reason) of the
/// others.
fn asked_for(
    baseline: &Baseline,
    measured: &Measured,
    settings: &Settings,
) -> Result<Library, DiagnoseError> {
    let (mut remaining, mut skipped) = library_for(baseline, measured.members.is_some());
    if let Some(only) = &settings.candidates {
        for name in only {
            if !remaining.iter().any(|c| c.name() == name)
                && !skipped.iter().any(|(n, _)| n == name)
            {
                return Err(DiagnoseError::Usage(format!(
                    "--candidates: no candidate effect {name:?} (the library: {})",
                    names()
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
    Ok((remaining, skipped))
}

/// What the data cannot tell apart from an effect as it entered the model at a step.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Indistinguishable {
    /// The effect.
    pub effect: String,
    /// The step it entered the model at: named there, or swapped in for an earlier effect.
    pub step: usize,
    /// Whether it was swapped in (not named by the step's tests).
    pub swapped_in: bool,
    /// Whether that step is kept (its effect added to the model).
    pub kept: bool,
    /// The rivals, in order: the step's own (ΔBIC within 2 or Vuong, [`decide`]; none for
    /// an effect swapped in), then effects removed because it took over what they explained,
    /// then rivals confounded with it in the final model ([`confound`]).
    pub rivals: Vec<String>,
}

/// The one record of what cannot be told apart (each report reads it, none adds to it): a
/// record per step's named effect with the step's own indistinguishable candidates, and
/// per effect swapped in at a kept step; an effect a kept step removed because another
/// took over what it explained (`explained_by`) is added to that other's latest record up
/// to that step; a rival confounded with an effect of the final model, to the effect's
/// latest kept record. (Before this record, the two additions went only to a step that
/// had *named* the effect, so the rivals of an effect swapped in were in the markdown's
/// words and `confounding[]` but in no `indistinguishable` field.)
pub fn indistinguishable(steps: &[Step], confounding: &[Confound]) -> Vec<Indistinguishable> {
    let mut out: Vec<Indistinguishable> = Vec::new();
    let add = |r: &mut Indistinguishable, name: &str| {
        if r.effect != name && !r.rivals.iter().any(|x| x == name) {
            r.rivals.push(name.to_string());
        }
    };
    for s in steps {
        for named in s.named_effects() {
            out.push(Indistinguishable {
                effect: named.to_string(),
                step: s.number,
                swapped_in: false,
                kept: s.kept,
                rivals: s.indistinguishable.clone(),
            });
        }
        if !s.kept {
            continue;
        }
        for by in s.removed.iter().filter_map(|r| r.replaced_by.as_ref()) {
            out.push(Indistinguishable {
                effect: by.clone(),
                step: s.number,
                swapped_in: true,
                kept: true,
                rivals: Vec::new(),
            });
        }
        for r in &s.removed {
            let Some(by) = &r.explained_by else { continue };
            if let Some(e) = out.iter_mut().rfind(|e| e.kept && &e.effect == by) {
                add(e, &r.name);
            }
        }
    }
    for c in confounding {
        if let Some(e) = out.iter_mut().rfind(|e| e.kept && e.effect == c.effect) {
            add(e, &c.rival);
        }
    }
    out
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
                match s.named_effects().join(" and ") {
                    n if n.is_empty() => "none".to_string(),
                    n => n,
                },
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
    let entered: usize = steps
        .iter()
        .filter(|s| s.kept)
        .map(|s| s.named_effects().len())
        .sum();
    let model = if names.len() == entered {
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
            "{entered} effect{} added in {}{model}. {}. Finally, {end}",
            if entered == 1 { "" } else { "s" },
            match kept {
                1 if entered == 1 => "turn".to_string(),
                1 => "one step, as a pair whose effects act together".to_string(),
                k if entered == k => "turn".to_string(),
                k => format!("{k} steps (a pair together in one)"),
            },
            added.join(". ")
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::likelihood::score::CandidateScore;

    use crate::selection::eliminate::Removal;

    fn removal(name: &str, by: Option<&str>, explained_by: Option<&str>) -> Removal {
        Removal {
            name: name.into(),
            replaced_by: by.map(String::from),
            added_in_step: 1,
            lr_statistic: 0.0,
            p_value: None,
            delta_bic: 0.0,
            explained_by: explained_by.map(String::from),
            separate_by: String::new(),
        }
    }

    fn step(number: usize, named: &str, kept: bool, removed: Vec<Removal>) -> Step {
        Step {
            number,
            verdict: Verdict::Named,
            reason: String::new(),
            named: Some(0),
            partner: None,
            pair: None,
            kept,
            indistinguishable: Vec::new(),
            candidates: vec![CandidateScore::of_test(named, 1, -10.0, true)],
            log_likelihood_before: 0.0,
            adjusted_p: Some(0.0),
            before: Comparison::of_energy(0.0, 1.0, 0.0),
            after: None,
            refitted: Vec::new(),
            removed,
            effects: Vec::new(),
            joint: None,
            seconds: 0.0,
        }
    }

    fn confounding(effect: &str, rival: &str) -> Confound {
        Confound {
            effect: effect.into(),
            rival: rival.into(),
            parameters: Vec::new(),
            lr_statistic: 0.0,
            p_value: 1.0,
            delta_bic: 0.0,
            separate_by: String::new(),
            along_ridge: false,
        }
    }

    /// The consistency case: step 1 names `length_bias`, step 2 names `length_sigma` and
    /// swaps `length_bias` for `diagonal_pretension` (which took over what it explained);
    /// the confounding tests then find `thermal_gradient` confounded with the pretension.
    /// The record lists both rivals for `diagonal_pretension` (swapped in at step 2), which
    /// is the final model's first effect, so the top-level `indistinguishable` reads them;
    /// before, both went to a step that *named* the pretension, of which there is none, and
    /// every `indistinguishable` field was empty while `confounding[]` and the markdown said
    /// the two cannot be told apart. Every rival of `confounding[]` and every taken-over
    /// removal of a kept step is in its effect's record; a step's own list comes first; a
    /// step not kept adds nothing.
    #[test]
    fn one_record_of_what_cannot_be_told_apart_covers_effects_swapped_in() {
        let mut first = step(1, "length_bias", true, Vec::new());
        first.indistinguishable = vec!["thermal_gradient".into()];
        let steps = vec![
            first,
            step(
                2,
                "length_sigma",
                true,
                vec![removal(
                    "length_bias",
                    Some("diagonal_pretension"),
                    Some("diagonal_pretension"),
                )],
            ),
            step(
                3,
                "gravity",
                false,
                vec![removal("length_sigma", None, Some("diagonal_pretension"))],
            ),
        ];
        let conf = vec![
            confounding("diagonal_pretension", "thermal_gradient"),
            confounding("length_sigma", "backlash"),
        ];
        let record = indistinguishable(&steps, &conf);
        let of = |e: &str, step: usize| {
            record
                .iter()
                .find(|r| r.effect == e && r.step == step)
                .unwrap_or_else(|| panic!("no record of {e} at step {step}: {record:?}"))
        };
        assert_eq!(final_effects(&steps[..2])[0], "diagonal_pretension");
        let swapped = of("diagonal_pretension", 2);
        assert!(swapped.swapped_in && swapped.kept);
        assert_eq!(swapped.rivals, ["length_bias", "thermal_gradient"]);
        assert_eq!(of("length_bias", 1).rivals, ["thermal_gradient"]);
        assert_eq!(of("length_sigma", 2).rivals, ["backlash"]);
        assert!(of("gravity", 3).rivals.is_empty() && !of("gravity", 3).kept);
        for c in &conf {
            assert!(
                record
                    .iter()
                    .any(|r| r.kept && r.effect == c.effect && r.rivals.contains(&c.rival)),
                "{c:?} not in {record:?}"
            );
        }
    }

    /// The final model's effects from the steps: each kept step's named effect in turn, a
    /// removed one taken out, a swapped one's replacement in its place, and nothing of a
    /// step that is not kept (its removals included).
    #[test]
    fn final_effects_follow_removals_and_swaps() {
        let removal = |name: &str, by: Option<&str>| removal(name, by, None);
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
}
