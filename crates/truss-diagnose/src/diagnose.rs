//! Steps 2 to 4: fit every candidate, choose, add the effect, compare again.

use crate::baseline::{Baseline, CaseEdit};
use crate::candidates::{Candidate, library};
use crate::compare::{Comparison, compare};
use crate::errors::DiagnoseError;
use crate::fit::sandwich;
use crate::fit::{Interval, intervals, maximise};
use crate::likelihood::{Gaussian, member_log_likelihood};
use crate::measured::Measured;
use crate::simulate::{Noise, Simulation, simulate, top_indices};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};
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

/// A fitted parameter.
#[derive(Debug, Clone, Serialize)]
pub struct FittedParameter {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: &'static str,
    /// Maximum-likelihood value.
    pub value: f64,
    /// 95 % Wald interval.
    pub interval: Interval,
    /// The plausible range searched.
    pub range: [f64; 2],
    /// The value at which the candidate is the baseline.
    pub null: f64,
}

/// One candidate's fit and score.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateScore {
    /// Name.
    pub name: String,
    /// The mechanism in words.
    pub mechanism: String,
    /// Number of parameters k.
    pub k: usize,
    /// Fitted parameters.
    pub parameters: Vec<FittedParameter>,
    /// Maximised ℓ (Gaussian synthetic likelihood, plus the member term when given).
    pub log_likelihood: f64,
    /// Λ = 2(ℓ − ℓ₀)/((1 + n/N)·λ̄), the adjusted likelihood-ratio statistic against the
    /// baseline.
    pub lr_statistic: f64,
    /// λ̄ = max(1, tr(A⁻¹B)/k), the misspecification adjustment.
    pub adjustment: f64,
    /// P(χ²_k ≥ Λ).
    pub p_value: f64,
    /// Whether p < α/K.
    pub significant: bool,
    /// ΔBIC = k ln n − Λ against the baseline (negative: better).
    pub delta_bic: f64,
    /// Likelihood evaluations (each a simulation of N samples).
    pub evaluations: usize,
    /// Wall time of the fit \[s\].
    pub seconds: f64,
    /// Why the fit failed, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
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

/// ℓ of the measured data under an edited case.
struct Evaluator<'a> {
    baseline: &'a Baseline,
    measured: &'a Measured,
    samples: usize,
    sigma_m: f64,
    simulations: std::cell::Cell<usize>,
}

impl Evaluator<'_> {
    fn job(&self, edit: &CaseEdit) -> Result<mc_shard::Job, DiagnoseError> {
        self.baseline.job_of(edit, self.samples as u64, None)
    }

    fn log_likelihood(&self, edit: &CaseEdit) -> Result<Vec<f64>, DiagnoseError> {
        let job = self.job(edit)?;
        let sim = simulate(&job, &self.measured.coords, self.samples, None)?;
        self.simulations.set(self.simulations.get() + 1);
        self.score(&job, &sim)
    }

    /// The terms of ℓ: each specimen's, then each member observation's.
    fn score(&self, job: &mc_shard::Job, sim: &Simulation) -> Result<Vec<f64>, DiagnoseError> {
        let g = Gaussian::from_simulation(sim, self.sigma_m)?;
        let mut terms = g.log_densities(&self.measured.y);
        if let Some(m) = &self.measured.members {
            terms.extend(member_log_likelihood(&job.cases[0], m, self.sigma_m));
        }
        Ok(terms)
    }

    fn edit(&self, c: &dyn Candidate, values: &[f64]) -> Result<CaseEdit, DiagnoseError> {
        let mut edit = self.baseline.derived_case();
        c.apply(values, &mut edit)?;
        Ok(edit)
    }
}

fn values_of(c: &dyn Candidate, t: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = c
        .parameters()
        .iter()
        .zip(t)
        .map(|(p, &x)| p.value(x))
        .collect();
    c.project(&mut v);
    v
}

/// The internal coordinates scanned along each parameter axis (the others at their null) for
/// a start: a candidate's likelihood need not be unimodal between the null and the truth (a
/// pretension that stiffens the truss predicts a much smaller scatter, so half of the true
/// pretension can fit worse than none).
pub const SCAN: [f64; 8] = [0.0, 0.125, 0.25, 0.375, 0.625, 0.75, 0.875, 1.0];

/// The best of the null and the axis scan ([`SCAN`]).
fn best_start(
    null: &[f64],
    project: &dyn Fn(&mut [f64]),
    f: &mut dyn FnMut(&[f64]) -> Result<crate::fit::Terms, DiagnoseError>,
) -> Result<Vec<f64>, DiagnoseError> {
    let mut best = (f(null)?.iter().sum::<f64>(), null.to_vec());
    for i in 0..null.len() {
        for &x in &SCAN {
            let mut t = null.to_vec();
            t[i] = x;
            project(&mut t);
            if t == null {
                continue;
            }
            if let Ok(terms) = f(&t) {
                let l: f64 = terms.iter().sum();
                if l > best.0 {
                    best = (l, t);
                }
            }
        }
    }
    Ok(best.1)
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
    let mut scores = Vec::new();
    for c in &candidates {
        let clock = Instant::now();
        let params = c.parameters();
        let start: Vec<f64> = params.iter().map(|p| p.internal(p.null)).collect();
        let count = std::cell::Cell::new(0usize);
        let mut objective = |t: &[f64]| -> Result<Vec<f64>, DiagnoseError> {
            count.set(count.get() + 1);
            let v: Vec<f64> = params.iter().zip(t).map(|(p, &x)| p.value(x)).collect();
            ev.log_likelihood(&ev.edit(c.as_ref(), &v)?)
        };
        let project = |t: &mut [f64]| {
            let mut v = values_of(c.as_ref(), t);
            c.project(&mut v);
            for (x, (p, val)) in t.iter_mut().zip(params.iter().zip(&v)) {
                *x = p.internal(*val);
            }
        };
        progress.note(&format!(
            "fitting {} ({} parameters)…",
            c.name(),
            params.len()
        ));
        let k = params.len();
        let start = best_start(&start, &project, &mut objective).unwrap_or(start);
        let score = match maximise(&start, &project, &mut objective) {
            Ok(fit) => {
                let values = values_of(c.as_ref(), &fit.internal);
                let iv = intervals(&fit, params, inflation);
                // Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄), λ̄ = max(1, tr(A⁻¹B)/k) (crate doc).
                let mean_eig = sandwich(&fit, 1.0).map_or(1.0, |(_, m)| m).max(1.0);
                let lr = (2.0 * (fit.log_likelihood - l0) / (inflation * mean_eig)).max(0.0);
                let p = 1.0 - ChiSquared::new(k as f64).expect("k ≥ 1").cdf(lr);
                CandidateScore {
                    name: c.name().into(),
                    mechanism: c.mechanism().into(),
                    k,
                    parameters: params
                        .iter()
                        .zip(values.iter().zip(iv))
                        .map(|(p, (&value, interval))| FittedParameter {
                            name: p.name.clone(),
                            unit: p.unit,
                            value,
                            interval,
                            range: [p.low, p.high],
                            null: p.null,
                        })
                        .collect(),
                    log_likelihood: fit.log_likelihood,
                    lr_statistic: lr,
                    adjustment: mean_eig,
                    p_value: p,
                    significant: p < settings.alpha / kk,
                    delta_bic: k as f64 * (n as f64).ln() - lr,
                    evaluations: fit.evaluations,
                    seconds: clock.elapsed().as_secs_f64(),
                    error: None,
                }
            }
            Err(e) => CandidateScore {
                name: c.name().into(),
                mechanism: c.mechanism().into(),
                k,
                parameters: Vec::new(),
                log_likelihood: f64::NEG_INFINITY,
                lr_statistic: 0.0,
                adjustment: 1.0,
                p_value: 1.0,
                significant: false,
                delta_bic: f64::INFINITY,
                evaluations: count.get(),
                seconds: clock.elapsed().as_secs_f64(),
                error: Some(e.to_string()),
            },
        };
        progress.note(&format!(
            "  {}: ΔBIC {:.1}, Λ {:.1}, p {:.2e}, {} evaluations in {:.1} s",
            score.name,
            score.delta_bic,
            score.lr_statistic,
            score.p_value,
            score.evaluations,
            score.seconds
        ));
        scores.push(score);
    }
    // Decision.
    let before_disagrees = before.statistics.iter().any(|s| s.disagrees);
    let best = (0..scores.len())
        .filter(|&i| scores[i].error.is_none())
        .min_by(|&a, &b| scores[a].delta_bic.total_cmp(&scores[b].delta_bic));
    let clear = best.filter(|&i| scores[i].significant && scores[i].delta_bic <= -DELTA_BIC);
    let (verdict, reason, named, indistinguishable) = if let Some(i) = clear {
        let others: Vec<String> = (0..scores.len())
            .filter(|&j| j != i && scores[j].error.is_none())
            .filter(|&j| scores[j].delta_bic < scores[i].delta_bic + DELTA_BIC)
            .map(|j| scores[j].name.clone())
            .collect();
        let reason = if others.is_empty() {
            format!(
                "{} improves the likelihood significantly (p = {:.2e} < α/K = {:.4}) and is the best by BIC by at least {DELTA_BIC} over every other candidate",
                scores[i].name,
                scores[i].p_value,
                settings.alpha / kk
            )
        } else {
            format!(
                "{} improves the likelihood significantly (p = {:.2e}) and is best by BIC, but {} explain the data as well (ΔBIC within {DELTA_BIC}): the data cannot tell them apart",
                scores[i].name,
                scores[i].p_value,
                others.join(", ")
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
