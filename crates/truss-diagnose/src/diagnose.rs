//! Steps 2 to 4: fit every candidate, choose, add the effect, compare again.
//!
//! Every candidate is fitted and tested ([`crate::score`]); the verdict follows from the
//! tests and BIC ([`decide`]); the named candidate and those indistinguishable from it get
//! profile-likelihood intervals ([`crate::profile`]). Should a profile find a higher maximum,
//! that candidate is scored anew and the verdict decided again (profiling any candidate that
//! newly enters it), so the verdict always rests on the final fits.

use crate::baseline::{Baseline, CaseEdit};
use crate::candidates::library;
use crate::compare::{Comparison, compare};
use crate::errors::DiagnoseError;
use crate::measured::Measured;
pub use crate::score::{CandidateScore, FittedParameter, SCAN};
use crate::score::{Evaluator, Fitted, Test, fit_candidate, profile_candidate};
use crate::simulate::{Noise, Simulation, simulate, top_indices};
use serde::Serialize;
use std::time::Instant;

/// Evidence that counts as a clear improvement and as "as good": a BIC difference of 2
/// (Kass & Raftery 1995: below 2 "not worth more than a bare mention").
pub const DELTA_BIC: f64 = 2.0;
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
    /// Family-wise significance level of the likelihood-ratio tests (Bonferroni over the
    /// candidates).
    pub alpha: f64,
    /// No progress on stderr.
    pub quiet: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            samples: None,
            measurement_sigma: 0.0,
            alpha: 0.05,
            quiet: false,
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

/// A complete diagnosis.
pub struct Diagnosis {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence or two.
    pub reason: String,
    /// The named candidate's index in `candidates`.
    pub named: Option<usize>,
    /// Candidates that explain the data as well as the named one (ΔBIC within 2).
    pub indistinguishable: Vec<String>,
    /// Every candidate's score.
    pub candidates: Vec<CandidateScore>,
    /// Candidates not applicable to this case, with why.
    pub skipped: Vec<(String, String)>,
    /// ℓ₀ of the baseline.
    pub baseline_log_likelihood: f64,
    /// Step 1 (and step 4's "before").
    pub before: Comparison,
    /// Step 4's "after", when an effect was added.
    pub after: Option<Comparison>,
    /// The updated case (the baseline's when no effect was named).
    pub updated: CaseEdit,
    /// Simulated samples per evaluation N.
    pub samples: usize,
    /// The simulations behind `before` and `after` (for plots).
    pub simulations: (Simulation, Option<Simulation>),
    /// Top-surface coordinate indices.
    pub top: [[usize; 3]; 3],
    /// Total simulations run, solves, and seconds.
    pub work: (usize, usize, f64),
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

/// The verdict from the candidates' scores and the baseline's comparison (crate doc):
/// `level` is the per-candidate significance level α/K.
pub fn decide(scores: &[&CandidateScore], before: &Comparison, n: usize, level: f64) -> Decision {
    let before_disagrees = before.statistics.iter().any(|s| s.disagrees);
    let best = (0..scores.len())
        .filter(|&i| scores[i].error.is_none())
        .min_by(|&a, &b| scores[a].delta_bic.total_cmp(&scores[b].delta_bic));
    let clear = best.filter(|&i| scores[i].significant && scores[i].delta_bic <= -DELTA_BIC);
    let (verdict, reason, named, indistinguishable) = if let Some(i) = clear {
        let others: Vec<usize> = (0..scores.len())
            .filter(|&j| j != i && scores[j].error.is_none())
            .filter(|&j| scores[j].delta_bic < scores[i].delta_bic + DELTA_BIC)
            .collect();
        let reason = if others.is_empty() {
            format!(
                "{} improves the likelihood significantly (p = {:.2e} < α/K = {level:.4}) and is the best by BIC by at least {DELTA_BIC} over every other candidate",
                scores[i].name, scores[i].p_value,
            )
        } else {
            format!(
                "{} improves the likelihood significantly (p = {:.2e}) and is best by BIC, but {} explain the data as well (ΔBIC within {DELTA_BIC}): the data cannot tell them apart",
                scores[i].name,
                scores[i].p_value,
                others
                    .iter()
                    .map(|&j| scores[j].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
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
            "no candidate improves the fit significantly, and the baseline agrees with the measurements within the stated tolerance".into(),
            None,
            Vec::new(),
        )
    } else if before_disagrees && n >= MIN_FOR_DISAGREEMENT {
        (
            Verdict::Unexplained,
            "the measurements disagree with the baseline, but no candidate effect of the library explains it significantly".into(),
            None,
            Vec::new(),
        )
    } else {
        (
            Verdict::CannotTell,
            format!(
                "no candidate improves the fit significantly, but with {n} specimens the data cannot show that the baseline agrees within tolerance either ({} outside){}: more specimens are needed",
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

/// Runs steps 1 to 4 on measured data against the baseline case.
pub fn diagnose(
    baseline: &Baseline,
    measured: &Measured,
    settings: &Settings,
    progress: &Progress,
) -> Result<Diagnosis, DiagnoseError> {
    let n = measured.n();
    let samples = settings.samples_for(n);
    let sigma_m = settings.measurement_sigma;
    let model = baseline.model();
    let top_nodes = model.top_surface().expect("checked when reading").nodes;
    let top = top_indices(&measured.coords, top_nodes).expect("top nodes are measured");
    let noise = Noise {
        sigma: sigma_m,
        seed: NOISE_SEED,
    };
    let ev = Evaluator {
        baseline,
        measured,
        samples,
        sigma_m,
        simulations: std::cell::Cell::new(0),
    };
    // Step 1.
    progress.note(&format!(
        "{n} specimens, {} coordinates; simulating the baseline case {:?} ({samples} samples)",
        measured.d(),
        baseline.case_name
    ));
    let base_edit = baseline.derived_case();
    let base_job = ev.job(&base_edit)?;
    let base_sim = simulate(&base_job, &measured.coords, samples, Some((noise, top)))?;
    ev.simulations.set(1);
    let l0: f64 = ev.score(&base_job, &base_sim)?.iter().sum();
    let before = compare(measured, &base_sim, top, sigma_m);
    progress.note(&format!(
        "baseline: ℓ₀ = {l0:.1}; {} of {} statistics disagree; energy distance {:.3} (p = {:.3})",
        before.statistics.iter().filter(|s| s.disagrees).count(),
        before.statistics.len(),
        before.energy,
        before.energy_p
    ));
    // Step 2.
    let (candidates, skipped) = library(baseline);
    let inflation = 1.0 + n as f64 / samples as f64;
    let kk = candidates.len().max(1) as f64;
    let test = Test {
        l0,
        n,
        inflation,
        level: settings.alpha / kk,
    };
    let mut fitted: Vec<Fitted> = Vec::new();
    for c in &candidates {
        progress.note(&format!(
            "fitting {} ({} parameters)…",
            c.name(),
            c.parameters().len()
        ));
        let f = fit_candidate(&ev, c.as_ref(), &test);
        let s = &f.score;
        progress.note(&format!(
            "  {}: ΔBIC {:.1}, Λ {:.1}, p {:.2e}, {} evaluations in {:.1} s",
            s.name, s.delta_bic, s.lr_statistic, s.p_value, s.evaluations, s.seconds
        ));
        fitted.push(f);
    }
    // Decision, and profiles of the candidates it rests on.
    let note = |m: &str| progress.note(m);
    let decision = loop {
        let scores: Vec<&CandidateScore> = fitted.iter().map(|f| &f.score).collect();
        let d = decide(&scores, &before, n, test.level);
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
            progress.note(&format!(
                "profile-likelihood intervals of {}…",
                candidates[i].name()
            ));
            profile_candidate(&ev, candidates[i].as_ref(), &mut fitted[i], &test, &note);
            let s = &fitted[i].score;
            progress.note(&format!(
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
    let scores: Vec<CandidateScore> = fitted.into_iter().map(|f| f.score).collect();
    let Decision {
        verdict,
        reason,
        named,
        indistinguishable,
    } = decision;
    let indistinguishable: Vec<String> = indistinguishable
        .iter()
        .map(|&i| scores[i].name.clone())
        .collect();
    progress.note(&format!("verdict: {verdict:?}: {reason}"));
    // Steps 3 and 4.
    let (updated, after, after_sim) = match named {
        Some(i) => {
            let values: Vec<f64> = scores[i].parameters.iter().map(|p| p.value).collect();
            let edit = ev.edit(candidates[i].as_ref(), &values)?;
            let job = ev.job(&edit)?;
            let sim = simulate(&job, &measured.coords, samples, Some((noise, top)))?;
            ev.simulations.set(ev.simulations.get() + 1);
            let after = compare(measured, &sim, top, sigma_m);
            progress.note(&format!(
                "with {}: energy distance {:.3} (p = {:.3}), was {:.3}",
                scores[i].name, after.energy, after.energy_p, before.energy
            ));
            (edit, Some(after), Some(sim))
        }
        None => (base_edit, None, None),
    };
    let sims = ev.simulations.get();
    Ok(Diagnosis {
        verdict,
        reason,
        named,
        indistinguishable,
        candidates: scores,
        skipped,
        baseline_log_likelihood: l0,
        before,
        after,
        updated,
        samples,
        simulations: (base_sim, after_sim),
        top,
        work: (sims, sims * samples, progress.seconds()),
    })
}
