//! `diagnosis.json` and `diagnosis.md`, the diagnosis's two reports. This module holds the
//! JSON document (its schema below, the types it serialises and [`json`]) and the method
//! in words that both reports carry; [`markdown()`] renders `diagnosis.md`, and [`p_text`]
//! and [`p_is`] write p-values as the reports and the verdicts' reasons show them.
//!
//! ## diagnosis.json (format `truss-diagnose`, version 11)
//!
//! ```text
//! format, format_version, program_version
//! job {path, id, case, seed}, samples (N per simulation), measurement_sigma [mm]
//! data        {file, rows, specimens_in_file, specimens_used, left_out_count, left_out[],
//!              outliers[] {specimen, line, node, axis, displacement [mm], robust_z},
//!              nodes[], unknown_nodes[], rare_nodes[], supports[], member_rows, unknown_members[],
//!              checks[] {check ("scatter_below_noise" | "specimens_closer_than_noise"),
//!              flagged (coordinates or pairs), p_value (the smallest), words}: the data
//!              checks' warnings against the stated noise (crate::comparison::checks)}
//! verdict     "named" | "none" | "cannot_tell" | "unexplained";  reason (words)
//! answer      {verdict, missing[] {effect, parameters[] {name, unit (the hardware's: µm
//!              for a length fitted in mm), value, lower, upper (95 % interval; null where
//!              not found), determined, shown (the interval excludes the null)}},
//!              cannot_tell_apart[] {effect, rivals[], separate_by[]}, could_not_have_seen[]
//!              (words), specimens, next[] (words), lines[] (Markdown)}: the answer
//!              diagnosis.md opens with and the console prints (report::answer), written
//!              from this record once
//!              ("named" when an effect was added, else step 1's verdict)
//! named_effect "none" or the first added effect's name
//! named_effects [names]   every effect added, in order; [] when none
//! steps       [{number, verdict, reason, named_effect ("none" when nothing was named; for
//!               a pair named together, its first member: both are in `named_effects`),
//!               kept (added to the model: significant, better by BIC, not spoiling a
//!               model that agreed in distribution, and kept by the false discovery rate
//!               over the steps; a later step may still remove or replace it),
//!               parameters[] (the named effect's, as below; a pair's first member's
//!               from the pair's joint fit), indistinguishable[] (a pair listed as an
//!               alternative reading is one entry `a + b`),
//!               adjusted_p (min(1, K·p) of the named one), log_likelihood_before,
//!               candidates[] (as below, against the model of the step's start),
//!               refitted[] {name, parameters[]} (every effect of the model after this
//!               step, this one last, re-fitted jointly: Wald intervals of the joint fit;
//!               empty when the model has one effect),
//!               removed_effects[] {name, added_in_step, lr_statistic, p_value, delta_bic,
//!               explained_by?, separate_by} (earlier effects this step removed: given the
//!               others they no longer improve the fit; `explained_by` took over what they
//!               explained and is indistinguishable from them on these data),
//!               pair? {effects [a, b], k (k_a + k_b), parameters [[…], […]] (each
//!               member's, Wald intervals of the joint fit), log_likelihood, lr_statistic,
//!               adjustment, p_value, significant, delta_bic (against the step's model),
//!               decision_delta_bic (the named candidate's, 0 when none), outcome
//!               ("named" | "alternative" | "not_better"), evaluations, seconds}: two
//!               candidates whose effects interact, one of them significant at the step and
//!               neither named, fitted jointly (crate::selection::pair); absent when no
//!               pair was fitted,
//!               discrepancy_before, discrepancy_after, discrepancy_noise_before,
//!               discrepancy_noise_after (the energy distances' permutation noise), seconds}]
//! effects     [{name, parameters [[name, unit, value]]}]   the final model's effects at
//!              their final values (after the re-fits): what updated-job.json holds
//! final_fit   [{name, parameters[]}]   the same effects fitted jointly, each parameter (as
//!              below) with the joint fit's interval: Wald, profile where the Wald one is
//!              cut at the range; for a model of one effect, its step's fit (profile
//!              intervals); empty when no effect was added
//! confounding [{effect, rival, parameters[] {name, unit, value, with_rival, interval,
//!              moved, widening}, lr_statistic, p_value, delta_bic, separate_by,
//!              along_ridge}]   rivals that, added to the final model and fitted jointly,
//!              move an effect's parameters out of their intervals (moved) or widen their
//!              Wald intervals two-fold or more (widening; listed for a widening alone only
//!              where the rival is significant given the model, p < α/2); or, where the
//!              joint maximum moves nothing, open a flat direction along which a fit ends as
//!              good as the model with a parameter outside its interval (along_ridge; its
//!              with_rival is that fit's value): the data cannot tell how that part of the
//!              signal divides between the two; the rival is also listed in the
//!              effect's record of `indistinguishable_by_effect` (and so in the
//!              `indistinguishable` of the step that named it, or the top-level one)
//! unseen      [{name, step, significant, p_value, specimens, limit}]   every candidate
//!              not in the final model, with the smallest effect its test against the
//!              final model (step `step`: the one after the last kept step, or step 1)
//!              detects with 80 % power; the verdict `none` means: no effect above these
//!              sizes is missing (`significant`: that test was significant, and the limit
//!              says nothing of what is there)
//!   limit      {power (0.8), level (α_K, the test's Bonferroni-adjusted level),
//!              critical_value (χ²_k's 1 − α_K quantile), noncentrality (λ₈₀), inflation
//!              (c), adjustment (λ̄), most_visible (index into parameters, or null: not
//!              detectable at any size within the plausible range), parameters[] {name,
//!              unit, value (at the limit), size (|value − null|, the parameter's unit),
//!              share_of_range, direction ("±", "+", "-"), information_per_specimen
//!              [1/unit²], naming_value, naming_size (the naming limit, below)}} (one
//!              parameter at a time, the others at their null; size and value null where
//!              not detectable within the range), naming_critical_value (q_name =
//!              max(q, k·ln n + 2/λ̄): a step names only at ΔBIC ≤ −2), naming_noncentrality;
//!              or null where the fit failed. Each of `candidates[]` (and the steps')
//!              carries the same as `detection_limit` against its step's model, without
//!              the naming fields
//! parameters  [{name, unit, value, interval, wald_interval, joint_interval?, range, null,
//!              determined}]
//!              (the first named effect's, as fitted in its step; for an effect swapped in,
//!              the last joint re-fit's, Wald intervals)
//!   interval   {lower, upper, lower_at_range_end, upper_at_range_end, method, threshold?}:
//!              method "profile" (2(ℓ̂ − ℓ_p) ≤ threshold) for the first step's named
//!              effect and those indistinguishable from it, and for a later step's where its
//!              update left it alone in the model; else "wald"; lower/upper null when not found;
//!              an end at the range end is the range's (the interval is cut there)
//!   determined false where the interval, or the Wald interval, covers at least half of the
//!              plausible range (on the fit's scale): "not determined by these data", no
//!              physical reading
//!   joint_interval  where profiled: the joint 95 % region of all k parameters projected on
//!              this one (same fields, threshold χ²_k(0.95)·c·λ̄): every parameter inside its
//!              joint interval at once with 95 % confidence
//! indistinguishable [names]   the first effect of the final model's (`named_effect`): as
//!              the record of `indistinguishable_by_effect` where it last entered the model
//!              at a kept step, named or swapped in; empty when clear
//! indistinguishable_by_effect [{effect, step, swapped_in, kept, rivals[]}]   the one
//!              record every `indistinguishable` field (and diagnosis.md) reads: per step's
//!              named effect, and per effect swapped in at a kept step (`swapped_in`), the
//!              rivals the data cannot tell from it: the step's own (explain the data as
//!              well: ΔBIC within 2, or significant and not shown further from the data than
//!              the named one, Vuong z < 1.96; none for an effect swapped in), then effects a
//!              kept step removed because it took over what they explained, then rivals
//!              `confounding[]` lists against it (added to its latest kept record)
//! baseline    {log_likelihood}
//! candidates  (step 1's) [{name, mechanism, k, parameters[], log_likelihood, lr_statistic, adjustment,
//!               p_value, significant, delta_bic, evaluations, profile_evaluations, seconds,
//!               vuong_z?, error?}]   (vuong_z: the named one's Vuong z against this one,
//!               for significant candidates when one is named)
//! skipped     [{name, reason}]
//! statistics  {before: Comparison (the baseline's), after: Comparison | null (the final
//!              model's, with every added effect)}
//!   Comparison {specimens, samples, energy, energy_p, energy_noise, tolerance {within, outside[], bands},
//!               statistics[] {id, kind, unit, measured, simulated, comparison, estimate
//!               {value, lower, upper}, p_value, p_holm, disagrees, words}}
//! discrepancy_before, discrepancy_after   (energy distance of the baseline and of the final
//!              model; after = before when no effect is added)
//! method      {likelihood, fit, intervals, selection, verdicts, steps, statistics, discrepancy}
//!             (in words)
//! timing      {simulations, solves, seconds, final_fit_seconds, threads (of the
//!              simulations), stages [{stage, seconds, simulations}] (each stage in order:
//!              the baseline's simulation and comparison; per step, fitting the
//!              candidates, deciding with the profiles, updating the model, profiling the
//!              model's effect where the update left it alone (later steps only), comparing
//!              the updated model; the final fit; the confounding tests)}
//! ```
//!
//! Version 12 (from 11): a step after the first profiles its named effect (and the
//! candidates indistinguishable from it) only where its update leaves that effect alone in
//! the model, in a stage of its own (`step N: profile the model's effect`); elsewhere those
//! candidates' `interval` is the Wald one (`method` "wald"), since the final numbers of a
//! model of several effects are the joint re-fit's. The shape is unchanged.
//!
//! Version 11 (from 10): `steps[].pair`, the pair of interacting candidates fitted jointly
//! at a step; a step that names a pair has both in `named_effects` and the verdicts'
//! reasons, its `named_effect` the first; `indistinguishable` fields may list a pair as
//! `a + b`.
//!
//! Version 10 (from 9): `answer`, the answer the reports share; diagnosis.md opens with
//! its lines and its `## Next step` section became the answer's `next` lines; the naming
//! limits in `unseen[].limit`. The `gravity` candidate's `g_x`, `g_y`, `g_z` are each
//! fitted within their range \[−1, 1\] g and free of one another (before: within
//! \|g\| ≤ 1): the shape is unchanged, but a fit's \|g\| may exceed 1, and an interval
//! end that reaches ±1 is flagged at the range end where the ball cut it unflagged. A
//! parameter the final fit leaves not `determined` is never in `confounding[].parameters`
//! (a rival that moves only such parameters is not listed).
//!
//! Version 9 (from 8): `indistinguishable_by_effect`; the `data.checks[]` warnings;
//! `unseen` (detection limits) and `candidates[].detection_limit`. An
//! effect swapped in (never named by a step) now has its rivals too: those removed because
//! it took over and those confounded with it, which were before in `confounding[]` and the
//! markdown but in no `indistinguishable` field; `steps[].indistinguishable` and the
//! top-level one read the record.
//!
//! Version 8 (from 7): `confounding[].along_ridge`; a rival that moves nothing at the joint
//! maximum is listed where the ridge probe finds a fit as good as the model's with an
//! effect's parameter outside its interval.
//!
//! Version 7 (from 6): `timing.threads` and `timing.stages`; a rival whose only confounded
//! parameters widen (none moved) is listed under `confounding` only where it is
//! significant given the model.
//!
//! Version 6 (from 5): `final_fit`, `confounding`, each parameter's `determined`,
//! `timing.final_fit_seconds`; a confounded rival is also in its effect's step's
//! `indistinguishable`.
//!
//! Within version 5, the `backlash` candidate's `parameters` became `clearance` (the
//! joints' mean clearance) and `spread` (the half-width of their uniform scatter; before:
//! `clearance` only): the shape is unchanged, so the version stays.
//!
//! Version 5 (from 4): stepwise selection: `steps[].refitted` is the joint re-fit
//! ({name, parameters}), `steps[].removed_effects`, `named_effects` leaves removed effects
//! out; `energy_noise` and the steps' `discrepancy_noise_*`.
//!
//! Version 4 (from 3): the forward selection: `named_effects`, `steps[]`, `effects`,
//! `data.outliers`,
//! `method.steps`; `statistics.after` and `discrepancy_after` are the final model's.
//!
//! Version 3 (from 2): `candidates[].vuong_z`, and `indistinguishable` also lists
//! significant candidates the named one does not fit significantly better than (Vuong).
//!
//! Version 2 (from 1): intervals are profile-likelihood intervals for the named effect, with
//! the Wald interval beside them (`wald_interval`), the joint region's projection
//! (`joint_interval`), `method` and `threshold`; the one `at_range_end` flag became one per
//! end; `adjustment`, `profile_evaluations` and `method.intervals` are new; `delta_bic`
//! charges the misspecification adjustment λ̄ in the penalty (k·λ̄·ln n) instead of dividing
//! the likelihood ratio by it.

use crate::comparison::baseline::Baseline;
use crate::comparison::measured::{DataReport, Measured};
use crate::comparison::statistics::Comparison;
use crate::likelihood::power::Unseen;
use crate::likelihood::score::{CandidateScore, FittedParameter};
use crate::selection::confound::Confounding;
use crate::selection::decide::Verdict;
use crate::selection::eliminate::Removal;
use crate::selection::model::{ModelEffect, RefitEffect};
use crate::selection::pair::PairScore;
use crate::selection::step::Step;
use crate::selection::{Diagnosis, Indistinguishable};
use method::{METHOD, Method};
use serde::Serialize;

pub mod answer;
mod markdown;
mod method;
pub mod plot;
mod wording;

pub use crate::likelihood::score::{p_is, p_text};
pub use answer::Answer;
pub use markdown::markdown;

/// Format name.
pub const FORMAT: &str = "truss-diagnose";
/// Format version.
pub const FORMAT_VERSION: u32 = 12;

#[derive(Serialize)]
struct JobRef<'a> {
    path: String,
    id: &'a str,
    case: &'a str,
    seed: u64,
}

#[derive(Serialize)]
struct Statistics<'a> {
    before: &'a Comparison,
    after: Option<&'a Comparison>,
}

#[derive(Serialize)]
struct Skipped<'a> {
    name: &'a str,
    reason: &'a str,
}

#[derive(Serialize)]
struct Baseline0 {
    log_likelihood: f64,
}

#[derive(Serialize)]
struct Timing<'a> {
    simulations: usize,
    solves: usize,
    seconds: f64,
    final_fit_seconds: f64,
    threads: usize,
    stages: &'a [crate::selection::model::StageTime],
}

#[derive(Serialize)]
struct Report<'a> {
    format: &'static str,
    format_version: u32,
    program_version: &'static str,
    job: JobRef<'a>,
    samples: usize,
    measurement_sigma: f64,
    data: &'a DataReport,
    verdict: Verdict,
    answer: &'a Answer,
    reason: &'a str,
    named_effect: &'a str,
    named_effects: Vec<&'a str>,
    parameters: &'a [FittedParameter],
    indistinguishable: &'a [String],
    indistinguishable_by_effect: &'a [Indistinguishable],
    baseline: Baseline0,
    candidates: &'a [CandidateScore],
    skipped: Vec<Skipped<'a>>,
    steps: Vec<StepReport<'a>>,
    effects: &'a [ModelEffect],
    final_fit: &'a [RefitEffect],
    confounding: &'a [Confounding],
    unseen: &'a [Unseen],
    statistics: Statistics<'a>,
    discrepancy_before: f64,
    discrepancy_after: f64,
    method: Method,
    timing: Timing<'a>,
}

#[derive(Serialize)]
struct StepReport<'a> {
    number: usize,
    verdict: Verdict,
    reason: &'a str,
    named_effect: &'a str,
    kept: bool,
    parameters: &'a [FittedParameter],
    indistinguishable: &'a [String],
    adjusted_p: Option<f64>,
    log_likelihood_before: f64,
    candidates: &'a [CandidateScore],
    refitted: &'a [RefitEffect],
    removed_effects: &'a [Removal],
    #[serde(skip_serializing_if = "Option::is_none")]
    pair: Option<&'a PairScore>,
    discrepancy_before: f64,
    discrepancy_noise_before: f64,
    discrepancy_after: f64,
    discrepancy_noise_after: f64,
    seconds: f64,
}

impl<'a> StepReport<'a> {
    fn of(s: &'a Step, d: &'a Diagnosis) -> Self {
        Self {
            number: s.number,
            verdict: s.verdict,
            reason: &s.reason,
            named_effect: s.named_effect().unwrap_or("none"),
            kept: s.kept,
            parameters: s.named_parameters(),
            indistinguishable: s
                .named_effect()
                .map_or(&[][..], |e| d.indistinguishable_of(e, s.number)),
            adjusted_p: s.adjusted_p,
            log_likelihood_before: s.log_likelihood_before,
            candidates: &s.candidates,
            refitted: &s.refitted,
            removed_effects: &s.removed,
            pair: s.pair.as_ref(),
            discrepancy_before: s.before.energy,
            discrepancy_noise_before: s.before.energy_noise,
            discrepancy_after: s.after.as_ref().map_or(s.before.energy, |a| a.energy),
            discrepancy_noise_after: s
                .after
                .as_ref()
                .map_or(s.before.energy_noise, |a| a.energy_noise),
            seconds: s.seconds,
        }
    }
}

/// The first named effect's name, or `none`.
pub fn named_effect(d: &Diagnosis) -> &str {
    d.named_effect()
}

/// diagnosis.json, with `answer` (the one [`Answer::of`] `d`).
pub fn json(
    baseline: &Baseline,
    measured: &Measured,
    d: &Diagnosis,
    answer: &Answer,
    sigma_m: f64,
) -> String {
    let first = d.first_step();
    let first_named = d
        .steps
        .iter()
        .find(|s| s.kept && s.named_effect() == Some(d.named_effect()))
        .unwrap_or(first);
    let report = Report {
        format: FORMAT,
        format_version: FORMAT_VERSION,
        program_version: env!("CARGO_PKG_VERSION"),
        job: JobRef {
            path: baseline.path.display().to_string(),
            id: &baseline.job.id,
            case: &baseline.case_name,
            seed: baseline.seed,
        },
        samples: d.samples,
        measurement_sigma: sigma_m,
        data: &measured.report,
        verdict: d.verdict,
        answer,
        reason: &d.reason,
        named_effect: d.named_effect(),
        named_effects: d.named_effects(),
        parameters: if first_named.kept && first_named.named_effect() == Some(d.named_effect()) {
            first_named.named_parameters()
        } else {
            // Swapped in: the last joint re-fit's.
            d.steps
                .iter()
                .filter(|s| s.kept)
                .flat_map(|s| &s.refitted)
                .rfind(|r| r.name == d.named_effect())
                .map_or(&[][..], |r| &r.parameters)
        },
        indistinguishable: d.indistinguishable_of_final(d.named_effect()),
        indistinguishable_by_effect: &d.indistinguishable,
        baseline: Baseline0 {
            log_likelihood: d.baseline_log_likelihood,
        },
        candidates: &first.candidates,
        skipped: d
            .skipped
            .iter()
            .map(|(n, r)| Skipped { name: n, reason: r })
            .collect(),
        steps: d.steps.iter().map(|s| StepReport::of(s, d)).collect(),
        effects: &d.effects,
        final_fit: &d.final_fit,
        confounding: &d.confounding,
        unseen: &d.unseen,
        statistics: Statistics {
            before: &d.before,
            after: d.after.as_ref(),
        },
        discrepancy_before: d.before.energy,
        discrepancy_after: d.after.as_ref().map_or(d.before.energy, |a| a.energy),
        method: METHOD,
        timing: Timing {
            simulations: d.work.0,
            solves: d.work.1,
            seconds: d.work.2,
            final_fit_seconds: d.final_seconds,
            threads: d.threads,
            stages: &d.stages,
        },
    };
    let mut s = serde_json::to_string_pretty(&report).expect("the report serialises");
    s.push('\n');
    s
}
