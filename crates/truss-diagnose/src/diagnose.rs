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
use crate::derivatives::Terms;
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
            "{} improves the likelihood significantly (p = {:.2e} < α/K = {level:.4}) and is the best by BIC",
            scores[i].name, scores[i].p_value,
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
    let terms = std::cell::RefCell::new(vec![None; candidates.len()]);
    let decision = loop {
        let scores: Vec<&CandidateScore> = fitted.iter().map(|f| &f.score).collect();
        let closeness = |i: usize, j: usize| {
            closeness_of(&ev, &candidates, &fitted, &terms, test.inflation, (i, j))
                .unwrap_or(f64::INFINITY)
        };
        let d = decide(&scores, &before, n, test.level, &closeness);
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
    let mut scores: Vec<CandidateScore> = fitted.iter().map(|f| f.score.clone()).collect();
    if let Some(i) = decision.named {
        for (j, s) in scores.iter_mut().enumerate() {
            if j != i && s.significant && s.error.is_none() {
                s.vuong_z = closeness_of(&ev, &candidates, &fitted, &terms, test.inflation, (i, j));
            }
        }
    }
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

/// Vuong's z of fitted candidate i against j ([`vuong`]), `inflation` = c = 1 + n/N;
/// `None` if a simulation failed.
fn closeness_of(
    ev: &Evaluator,
    candidates: &[Box<dyn crate::candidates::Candidate>],
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
type TermsCache = std::cell::RefCell<Vec<Option<(Vec<f64>, Terms)>>>;

/// ℓ's per-unit terms at a candidate's fit, computed once per fitted point (one simulation).
fn fitted_terms(
    ev: &Evaluator,
    c: &dyn crate::candidates::Candidate,
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
