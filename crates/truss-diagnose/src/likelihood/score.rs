//! One candidate at a time: ℓ of the data under an edited case, the candidate's maximum, its
//! likelihood-ratio test against the baseline, and its intervals (Wald for every candidate,
//! profile likelihood for those the verdict rests on).

use crate::candidates::candidate::Candidate;
use crate::candidates::parameter::Parameter;
use crate::comparison::baseline::{Baseline, CaseEdit};
use crate::comparison::measured::Measured;
use crate::comparison::simulate::{Simulation, simulate};
use crate::errors::DiagnoseError;
use crate::likelihood::conditional::GaugeNoise;
use crate::likelihood::derivatives::Terms;
use crate::likelihood::fit::{Fit, Interval, Options, adjustments, maximise, wald_intervals};
use crate::likelihood::gaussian::{Gaussian, member_log_likelihood};
use crate::likelihood::power::{DetectionLimit, detection_limit};
use crate::likelihood::profile::{Intervals, Problem, Profile, profile_intervals};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::time::Instant;

/// A fitted parameter.
#[derive(Debug, Clone, Serialize)]
pub struct FittedParameter {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: &'static str,
    /// Maximum-likelihood value.
    pub value: f64,
    /// The 95 % interval the report and the checks use: the profile-likelihood interval
    /// where it was computed, else the Wald interval.
    pub interval: Interval,
    /// The 95 % sandwich Wald interval, for comparison.
    pub wald_interval: Interval,
    /// Where profiled: the projection of the joint 95 % profile-likelihood region of all
    /// the candidate's k parameters (threshold χ²_k(0.95)·c·λ̄), so that every parameter
    /// lies in its joint interval at once with 95 % confidence ([`crate::likelihood::profile`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_interval: Option<Interval>,
    /// The plausible range searched.
    pub range: [f64; 2],
    /// The value at which the candidate is the baseline.
    pub null: f64,
    /// Whether the data determine it: `false` where its 95 % interval, or its Wald
    /// interval, covers at least [`UNDETERMINED`] of its plausible range
    /// ([`FittedParameter::coverage`]). An undetermined parameter's value is the best fit,
    /// with no physical reading.
    pub determined: bool,
}

/// The share of its plausible range that a parameter's 95 % interval must cover for the
/// parameter to be reported "not determined by these data": most of it.
pub const UNDETERMINED: f64 = 0.5;

/// The share of `p`'s plausible range that `interval` covers, on the fit's scale
/// ([`Parameter::internal`]); an end not found counts as the range's.
pub fn coverage(p: &Parameter, interval: &Interval) -> f64 {
    let lower = interval.lower.map_or(0.0, |v| p.internal(v));
    let upper = interval.upper.map_or(1.0, |v| p.internal(v));
    (upper.min(1.0) - lower.max(0.0)).max(0.0)
}

impl FittedParameter {
    /// The share of the plausible range of parameter `p` (this one's) that the data leave
    /// open: the larger of its interval's and its Wald interval's [`coverage`]. The Wald
    /// interval is the likelihood's own curvature, without the feasible set: where a
    /// profile's ends are set by a constraint that couples the parameter to others
    /// (backlash's spread held below a small mean clearance), the interval
    /// is narrow while the data say nothing of the parameter itself. A Wald interval with an
    /// end not found (the curvature not positive definite, as at a fit on the range's edge:
    /// backlash's spread at 0) says nothing either way, and the interval decides alone
    /// where both its ends were found.
    pub fn coverage(&self, p: &Parameter) -> f64 {
        let found = |i: &Interval| i.lower.is_some() && i.upper.is_some();
        let own = coverage(p, &self.interval);
        if found(&self.interval) && !found(&self.wald_interval) {
            own
        } else {
            own.max(coverage(p, &self.wald_interval))
        }
    }

    /// Sets the interval the report uses, and whether the parameter is determined.
    pub fn set_interval(&mut self, p: &Parameter, interval: Interval) {
        self.interval = interval;
        self.determined = self.coverage(p) < UNDETERMINED;
    }
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
    /// ΔBIC = k·λ̄·ln n − 2(ℓ − ℓ₀)/(1 + n/N) = λ̄·(k ln n − Λ) against the baseline
    /// (negative: better): the BIC of a misspecified likelihood, whose penalty counts the
    /// effective number of parameters tr(A⁻¹B) = k·λ̄ (crate doc).
    pub delta_bic: f64,
    /// Likelihood evaluations (each a simulation of N samples), profiles included.
    pub evaluations: usize,
    /// Of which for the profile intervals.
    pub profile_evaluations: usize,
    /// Wall time of the fit and the profiles \[s\].
    pub seconds: f64,
    /// Vuong's z of the named candidate against this one, for significant candidates when
    /// one is named (positive: the named one fits closer; below 1.96 they are
    /// indistinguishable).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vuong_z: Option<f64>,
    /// Why the fit failed, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// The smallest effect of each parameter this test detects with 80 % power, from the
    /// curvature at the fit ([`crate::likelihood::power`]); `None` where the fit failed or
    /// has no curvature.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detection_limit: Option<DetectionLimit>,
}

/// A p-value for people: `p < 1e-16` below what a double can tell from 0 after
/// `1 − CDF`, else two significant digits.
pub fn p_text(p: f64) -> String {
    if p < 1e-16 {
        "< 1e-16".into()
    } else if p >= 0.01 {
        format!("{p:.2}")
    } else {
        format!("{p:.1e}")
    }
}

/// `p = 0.03` or `p < 1e-16`.
pub fn p_is(p: f64) -> String {
    let t = p_text(p);
    if t.starts_with('<') {
        format!("p {t}")
    } else {
        format!("p = {t}")
    }
}

/// ℓ's terms of the cases already simulated, by job id (the SHA-256 of the derived job's
/// canonical form: its case, N and seed), so that a case met again (the current model at
/// every candidate's null, a point a later fit passes through) is not simulated again.
/// With common random numbers a case's terms are a function of its job alone, so a
/// remembered value is exactly the one a new simulation would give. At most
/// [`MEMO_CASES`] are kept, the oldest forgotten first.
#[derive(Default)]
pub(crate) struct Memo {
    terms: std::cell::RefCell<(
        std::collections::HashMap<String, Terms>,
        std::collections::VecDeque<String>,
    )>,
}

/// Most cases the memo of ℓ's terms keeps (each n + member-observation values).
pub const MEMO_CASES: usize = 512;

impl Memo {
    /// The terms of job `id`, if remembered.
    pub fn get(&self, id: &str) -> Option<Terms> {
        self.terms.borrow().0.get(id).cloned()
    }

    /// Remembers the terms of job `id`.
    pub fn put(&self, id: &str, terms: &Terms) {
        let (map, order) = &mut *self.terms.borrow_mut();
        if map.insert(id.to_string(), terms.clone()).is_none() {
            order.push_back(id.to_string());
        }
        while order.len() > MEMO_CASES {
            if let Some(old) = order.pop_front() {
                map.remove(&old);
            }
        }
    }
}

/// ℓ of the measured data under an edited case: the current model of a forward-selection
/// step (`start`: the baseline with the effects added so far) with one candidate applied.
pub(crate) struct Evaluator<'a> {
    pub baseline: &'a Baseline,
    pub start: CaseEdit,
    pub measured: &'a Measured,
    pub samples: usize,
    pub sigma_m: f64,
    /// Condition the node terms on the specimens' measured members.
    pub condition: bool,
    /// Worker threads of each simulation.
    pub threads: usize,
    /// Simulations run (cases found in `memo` not counted).
    pub simulations: std::cell::Cell<usize>,
    /// The terms of cases already simulated, if shared.
    pub memo: Option<&'a Memo>,
    /// The simulated gauge noise of the member measurements, of `samples` samples.
    pub gauge: &'a GaugeNoise,
}

impl Evaluator<'_> {
    /// The one-case job of an edit, N samples, the baseline's seed.
    pub fn job(&self, edit: &CaseEdit) -> Result<truss_job::Job, DiagnoseError> {
        self.baseline.job_of(edit, self.samples as u64, None)
    }

    fn log_likelihood(&self, edit: &CaseEdit) -> Result<Terms, DiagnoseError> {
        let job = self.job(edit)?;
        if let Some(terms) = self.memo.and_then(|m| m.get(&job.id)) {
            return Ok(terms);
        }
        let sim = simulate(
            &job,
            &self.measured.coords,
            self.samples,
            None,
            self.threads,
        )?;
        self.simulations.set(self.simulations.get() + 1);
        let terms = self.score(&job, &sim)?;
        if let Some(m) = self.memo {
            m.put(&job.id, &terms);
        }
        Ok(terms)
    }

    /// Whether ℓ with candidate `c` applied to the current model is rough on the scale of
    /// its standard error: the model's joints have free play (the baseline's model has pin
    /// joints, or the current case gives it clearances), or `c` gives them some
    /// ([`Candidate::free_play`]; [`crate::likelihood::fit`]).
    pub fn rough(&self, c: &dyn Candidate) -> bool {
        !self.baseline.model().joints().is_empty()
            || self.start.case.backlash.is_some()
            || c.free_play()
    }

    /// The terms of ℓ: each specimen's, then each member observation's.
    /// With member measurements, each specimen's node term is conditioned on its own
    /// measured members ([`crate::likelihood::conditional`]).
    pub fn score(&self, job: &truss_job::Job, sim: &Simulation) -> Result<Terms, DiagnoseError> {
        let mut terms = if self.condition && self.measured.members.is_some() {
            crate::likelihood::conditional::log_densities(
                job,
                self.baseline.model(),
                sim,
                self.measured,
                self.sigma_m,
                self.gauge,
            )?
        } else {
            Gaussian::from_simulation(sim, self.sigma_m)?.log_densities(&self.measured.y)
        };
        if let Some(m) = &self.measured.members {
            terms.extend(member_log_likelihood(
                &job.cases[0],
                self.baseline.model(),
                m,
                self.sigma_m,
            ));
        }
        Ok(terms)
    }

    /// ℓ's per-unit terms with the candidate at `values` (one simulation).
    pub fn terms_at(&self, c: &dyn Candidate, values: &[f64]) -> Result<Terms, DiagnoseError> {
        self.log_likelihood(&self.edit(c, values)?)
    }

    /// The current model's case with the candidate applied at `values`.
    pub fn edit(&self, c: &dyn Candidate, values: &[f64]) -> Result<CaseEdit, DiagnoseError> {
        let mut edit = self.start.clone();
        c.apply(values, &mut edit)?;
        Ok(edit)
    }
}

/// The parameter values at internal coordinates `t`, on the feasible set.
fn values_of(c: &dyn Candidate, t: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = c
        .parameters()
        .iter()
        .zip(t)
        .map(|(p, &x)| p.value(x))
        .collect();
    c.project(&mut v, None);
    v
}

/// The internal coordinates scanned along each parameter axis (the others at their null) for
/// a start: a candidate's likelihood need not be unimodal between the null and the truth (a
/// pretension that stiffens the truss predicts a much smaller scatter, so half of the true
/// pretension can fit worse than none).
pub const SCAN: [f64; 8] = [0.0, 0.125, 0.25, 0.375, 0.625, 0.75, 0.875, 1.0];

/// The best of the null and the axis scan ([`SCAN`]).
///
/// An axis the scan from the null cannot move (every point of it projected back onto the null:
/// the backlash spread, held ≤ the clearance, which is 0 at the null) is scanned again from
/// the best point the other axes found. Such a parameter's ℓ is even about the null (U\[m −
/// h, m + h\] is the same distribution for ±h), so its gradient there is 0 and its
/// curvature may be upward: a fit started on it stays there, though ℓ rises by hundreds
/// away from it (the backlash check `paper-backlash+mm` of `scripts/diagnose-check.sh`:
/// spread 0.1 µm, ℓ 1,250 below the true 6.5 µm's).
fn best_start(
    null: &[f64],
    project: &dyn Fn(&mut [f64], Option<usize>),
    f: &mut dyn FnMut(&[f64]) -> Result<Terms, DiagnoseError>,
) -> Result<Vec<f64>, DiagnoseError> {
    let mut best = (f(null)?.iter().sum::<f64>(), null.to_vec());
    let mut scan = |from: &[f64], i: usize, best: &mut (f64, Vec<f64>)| -> bool {
        let mut seen: Vec<Vec<f64>> = vec![from.to_vec()];
        for &x in &SCAN {
            let mut t = from.to_vec();
            t[i] = x;
            project(&mut t, None);
            if seen.contains(&t) {
                continue;
            }
            seen.push(t.clone());
            if let Ok(terms) = f(&t) {
                let l: f64 = terms.iter().sum();
                if l > best.0 {
                    *best = (l, t);
                }
            }
        }
        seen.len() == 1
    };
    let unscanned: Vec<usize> = (0..null.len())
        .filter(|&i| scan(null, i, &mut best))
        .collect();
    if best.1 != null {
        for i in unscanned {
            let from = best.1.clone();
            scan(&from, i, &mut best);
        }
    }
    Ok(best.1)
}

/// What scoring needs to know about the data and the test.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Test {
    /// ℓ₀ of the baseline.
    pub l0: f64,
    /// Specimens n.
    pub n: usize,
    /// `c = 1 + n/N`.
    pub inflation: f64,
    /// The per-candidate level α/K.
    pub level: f64,
}

/// A candidate's fit, kept for its profile.
pub(crate) struct Fitted {
    pub score: CandidateScore,
    pub fit: Option<Fit>,
    pub profiled: bool,
}

/// A candidate's objective: ℓ's terms at internal coordinates.
fn objective<'a>(
    ev: &'a Evaluator<'a>,
    c: &'a dyn Candidate,
) -> impl FnMut(&[f64]) -> Result<Terms, DiagnoseError> + 'a {
    let params = c.parameters();
    move |t: &[f64]| {
        let v: Vec<f64> = params.iter().zip(t).map(|(p, &x)| p.value(x)).collect();
        ev.log_likelihood(&ev.edit(c, &v)?)
    }
}

/// A candidate's projection of internal coordinates onto its feasible set, leaving the
/// coordinate given (if any) where it is.
pub(crate) fn projection(c: &dyn Candidate) -> impl Fn(&mut [f64], Option<usize>) + '_ {
    let params = c.parameters();
    move |t: &mut [f64], fixed: Option<usize>| {
        let mut v: Vec<f64> = params
            .iter()
            .zip(t.iter())
            .map(|(p, &x)| p.value(x))
            .collect();
        c.project(&mut v, fixed);
        for (i, (x, (p, val))) in t.iter_mut().zip(params.iter().zip(&v)).enumerate() {
            if Some(i) != fixed {
                *x = p.internal(*val);
            }
        }
    }
}

/// The score of a fit: the test against the baseline and the Wald intervals.
pub(crate) fn score_of(c: &dyn Candidate, fit: &Fit, test: &Test) -> CandidateScore {
    let params = c.parameters();
    let k = params.len();
    let values = values_of(c, &fit.internal);
    let wald = wald_intervals(fit, params, test.inflation);
    // Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄), λ̄ = max(1, tr(A⁻¹B)/k) (crate doc).
    let mean_eig = adjustments(fit).map_or(1.0, |(m, _)| m).max(1.0);
    let lr = (2.0 * (fit.log_likelihood - test.l0) / (test.inflation * mean_eig)).max(0.0);
    let p = 1.0 - ChiSquared::new(k as f64).expect("k ≥ 1").cdf(lr);
    CandidateScore {
        name: c.name().into(),
        mechanism: c.mechanism().into(),
        k,
        parameters: params
            .iter()
            .zip(values.iter().zip(wald))
            .map(|(p, (&value, wald))| FittedParameter {
                name: p.name.clone(),
                unit: p.unit,
                value,
                determined: coverage(p, &wald) < UNDETERMINED,
                interval: wald.clone(),
                wald_interval: wald,
                joint_interval: None,
                range: [p.low, p.high],
                null: p.null,
            })
            .collect(),
        log_likelihood: fit.log_likelihood,
        lr_statistic: lr,
        adjustment: mean_eig,
        p_value: p,
        significant: p < test.level,
        delta_bic: mean_eig * (k as f64 * (test.n as f64).ln() - lr),
        evaluations: fit.evaluations,
        profile_evaluations: 0,
        seconds: 0.0,
        vuong_z: None,
        error: None,
        detection_limit: detection_limit(
            params,
            &fit.curvature,
            test.n,
            test.level,
            test.inflation,
            mean_eig,
        ),
    }
}

/// Fits a candidate: the best start of the axis scan, then the trust-region Newton method.
pub(crate) fn fit_candidate(ev: &Evaluator, c: &dyn Candidate, test: &Test) -> Fitted {
    let clock = Instant::now();
    let params = c.parameters();
    let null: Vec<f64> = params.iter().map(|p| p.internal(p.null)).collect();
    let count = std::cell::Cell::new(0usize);
    let (mut objective, project) = (objective(ev, c), projection(c));
    let mut counted = |t: &[f64]| {
        count.set(count.get() + 1);
        objective(t)
    };
    let start = best_start(&null, &project, &mut counted).unwrap_or(null);
    let clusters = ev.measured.clusters();
    let options = Options {
        clusters: Some(&clusters),
        rough: ev.rough(c),
        ..Options::default()
    };
    let fit = maximise(&start, options, &|t| project(t, None), &mut counted);
    let (mut score, fit) = match fit {
        Ok(fit) => (score_of(c, &fit, test), Some(fit)),
        Err(e) => (
            CandidateScore {
                name: c.name().into(),
                mechanism: c.mechanism().into(),
                k: params.len(),
                parameters: Vec::new(),
                log_likelihood: f64::NEG_INFINITY,
                lr_statistic: 0.0,
                adjustment: 1.0,
                p_value: 1.0,
                significant: false,
                delta_bic: f64::INFINITY,
                evaluations: 0,
                profile_evaluations: 0,
                seconds: 0.0,
                vuong_z: None,
                error: Some(e.to_string()),
                detection_limit: None,
            },
            None,
        ),
    };
    score.evaluations = count.get();
    score.seconds = clock.elapsed().as_secs_f64();
    Fitted {
        score,
        fit,
        profiled: false,
    }
}

/// Profile-likelihood intervals for a fitted candidate ([`crate::likelihood::profile`]); where a profile
/// finds a higher point the candidate is fitted again from there and scored anew (see
/// [`profile_and_refit`]). A profile that fails, or still finds a higher point after two
/// new fits, leaves the Wald intervals (at the highest fit) and says why in the progress
/// notes.
pub(crate) fn profile_candidate(
    ev: &Evaluator,
    c: &dyn Candidate,
    fitted: &mut Fitted,
    test: &Test,
    note: &dyn Fn(&str),
) {
    fitted.profiled = true;
    let Some(fit) = fitted.fit.take() else {
        return;
    };
    let clock = Instant::now();
    let (mut objective, project) = (objective(ev, c), projection(c));
    let clusters = ev.measured.clusters();
    let settled = profile_and_refit(
        fit,
        &mut objective,
        |fit, objective| {
            let problem = Problem {
                parameters: c.parameters(),
                project: &project,
                inflation: test.inflation,
            };
            profile_intervals(fit, &problem, objective, true)
        },
        |t, fit, objective| {
            let options = Options {
                steps: Some(&fit.steps),
                curvature: true,
                clusters: Some(&clusters),
                rough: ev.rough(c),
            };
            maximise(t, options, &|t| project(t, None), objective)
        },
        c.name(),
        note,
    );
    let Settled {
        fit,
        outcome,
        refitted,
        spent,
    } = settled;
    let (evaluations, seconds) = (fitted.score.evaluations, fitted.score.seconds);
    if refitted {
        fitted.score = score_of(c, &fit, test);
    }
    if let Some(Intervals {
        marginal, joint, ..
    }) = outcome
    {
        let joint = joint.into_iter().map(Some).chain(std::iter::repeat(None));
        for (((p, q), i), jt) in fitted
            .score
            .parameters
            .iter_mut()
            .zip(c.parameters())
            .zip(marginal)
            .zip(joint)
        {
            p.set_interval(q, i);
            p.joint_interval = jt;
        }
    }
    fitted.score.evaluations = evaluations + spent;
    fitted.score.profile_evaluations = spent;
    fitted.score.seconds = seconds + clock.elapsed().as_secs_f64();
    fitted.fit = Some(fit);
}

/// What [`profile_and_refit`] settled on.
struct Settled {
    /// The highest fit reached.
    fit: Fit,
    /// The profile intervals at that fit, where a profile completed there.
    outcome: Option<Intervals>,
    /// Whether `fit` is a new fit (to be scored anew).
    refitted: bool,
    /// Evaluations of ℓ spent in profiles and new fits.
    spent: usize,
}

/// The profile step of [`profile_candidate`]: profiles `fit` (`profile`); where a profile
/// finds a point higher than the fit, fits again from it (`refit`) and, if that fit is
/// higher, profiles the new fit, at most three profiles in all. A higher point found by the
/// third profile is still fitted from, and the higher fit kept with its Wald intervals: a
/// fit that its own profile showed lower is never the answer. Both run on `objective` (ℓ);
/// `name` and `note` as for the progress notes.
fn profile_and_refit<O: ?Sized>(
    mut fit: Fit,
    objective: &mut O,
    mut profile: impl FnMut(&Fit, &mut O) -> Result<Profile, DiagnoseError>,
    mut refit: impl FnMut(&[f64], &Fit, &mut O) -> Result<Fit, DiagnoseError>,
    name: &str,
    note: &dyn Fn(&str),
) -> Settled {
    const PROFILES: usize = 3;
    let mut spent = 0;
    let mut refitted = false;
    let mut outcome = None;
    for attempt in 0..PROFILES {
        match profile(&fit, objective) {
            Ok(Profile::Intervals(iv)) => {
                spent += iv.evaluations;
                outcome = Some(iv);
                break;
            }
            Ok(Profile::Higher(t, n)) => {
                spent += n;
                let last = attempt + 1 == PROFILES;
                note(&format!(
                    "  {name}: the profile found a higher point; fitting again from there"
                ));
                match refit(&t, &fit, objective) {
                    Ok(better) if better.log_likelihood > fit.log_likelihood => {
                        spent += better.evaluations;
                        fit = better;
                        refitted = true;
                        if last {
                            note(&format!(
                                "  {name}: the profile still found higher points after two new fits; the highest fit kept, with Wald intervals"
                            ));
                        }
                    }
                    Ok(other) => {
                        spent += other.evaluations;
                        note(&format!(
                            "  {name}: fitting again found no higher maximum; Wald intervals kept"
                        ));
                        break;
                    }
                    Err(e) => {
                        note(&format!(
                            "  {name}: fitting again failed ({e}); Wald intervals kept"
                        ));
                        break;
                    }
                }
            }
            Err(e) => {
                note(&format!(
                    "  {name}: profile failed ({e}); Wald intervals kept"
                ));
                break;
            }
        }
    }
    Settled {
        fit,
        outcome,
        refitted,
        spent,
    }
}

/// A score of `k` parameters with ΔBIC `delta_bic`, significant (p = 1e-6) or not (p = 0.5),
/// nothing else filled in: the selection's tests of its rules.
#[cfg(test)]
impl CandidateScore {
    pub(crate) fn of_test(name: &str, k: usize, delta_bic: f64, significant: bool) -> Self {
        Self {
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
            detection_limit: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which fits are rough: a length bias on a rigid baseline is not; the backlash
    /// candidate on it is; any candidate on a baseline whose model has pin joints is
    /// (section 4.2.3's backlash case), as on a rigid one given clearances by an earlier
    /// step. No simulation is run.
    #[test]
    fn fits_with_joints_in_free_play_are_rough() {
        let job =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
        // Data only to make an evaluator with: five specimens of the rigid case.
        let dir = tempfile::tempdir().unwrap();
        let nodes = dir.path().join("nodes.csv");
        let mut csv = Vec::new();
        crate::synth::synth(
            &crate::synth::SynthOptions {
                job: job.clone(),
                case: "rigid-sigma-0.033".into(),
                specimens: 5,
                seed: 1,
                effect: "none".into(),
                measurement_sigma: 0.001,
                all_nodes: false,
                members_out: None,
            },
            &mut csv,
        )
        .unwrap();
        std::fs::write(&nodes, csv).unwrap();
        let rigid = Baseline::read(&job, "rigid-sigma-0.033").unwrap();
        let measured = crate::comparison::measured::read(rigid.model(), &nodes, None, 5).unwrap();
        let gauge = GaugeNoise::new(0, &measured);
        let verdicts = |case: &str| {
            let baseline = Baseline::read(&job, case).unwrap();
            let (library, _) = crate::candidates::library_for(&baseline, false);
            let ev = Evaluator {
                baseline: &baseline,
                start: baseline.derived_case(),
                measured: &measured,
                samples: 0,
                sigma_m: 0.001,
                condition: false,
                threads: 1,
                simulations: Default::default(),
                memo: None,
                gauge: &gauge,
            };
            let pick = |name: &str| library.iter().find(|c| c.name() == name);
            let bias = pick("length_bias").expect("a length bias applies to both");
            let backlash = pick("backlash");
            // Rough at the start; for the backlash candidate; for a length bias once an
            // earlier step has given the model clearances.
            let later = backlash.map(|c| ev.edit(c.as_ref(), &[0.01]).unwrap());
            (
                ev.rough(bias.as_ref()),
                backlash.map(|c| ev.rough(c.as_ref())),
                later.map(|start| Evaluator { start, ..ev }.rough(bias.as_ref())),
            )
        };
        assert_eq!(
            verdicts("rigid-sigma-0.033"),
            (false, Some(true), Some(true))
        );
        // With joints already, the backlash candidate does not apply.
        assert_eq!(verdicts("backlash-sigma-0.033"), (true, None, None));
    }

    /// A fit at `x` with ℓ = `l` (one parameter), as a profile's tests need it.
    fn fit_at(x: f64, l: f64) -> Fit {
        Fit {
            internal: vec![x],
            log_likelihood: l,
            curvature: nalgebra::DMatrix::zeros(0, 0),
            variability: nalgebra::DMatrix::zeros(0, 0),
            steps: vec![0.01],
            evaluations: 10,
            iterations: 3,
        }
    }

    /// A profile that finds a higher point every time (ℓ rising along a ridge that each fit
    /// stops short of): the candidate is fitted again after each of the three profiles, and
    /// the highest fit, the third, is kept with its Wald intervals. Before, the point the
    /// third profile found was dropped and the second fit kept, although its own profile had
    /// shown it lower (the fault of `paper-backlash+mm` before the spread's start scan).
    #[test]
    fn a_higher_point_from_the_last_profile_is_fitted_from_and_kept() {
        let mut profiles = 0;
        let settled = profile_and_refit(
            fit_at(0.0, 0.0),
            &mut profiles,
            |fit, profiles| {
                *profiles += 1;
                Ok(Profile::Higher(vec![fit.internal[0] + 1.0], 5))
            },
            |t, _, _| Ok(fit_at(t[0], 10.0 * t[0])),
            "test",
            &|_| {},
        );
        assert_eq!(profiles, 3);
        assert!(settled.refitted && settled.outcome.is_none());
        assert_eq!(settled.fit.internal, vec![3.0]);
        assert_eq!(settled.fit.log_likelihood, 30.0);
        // Three profiles of 5 evaluations, three fits of 10.
        assert_eq!(settled.spent, 45);
    }

    /// A new fit that is not higher than the old one ends the step with the old fit.
    #[test]
    fn a_new_fit_no_higher_leaves_the_old_one() {
        let settled = profile_and_refit(
            fit_at(0.0, 1.0),
            &mut (),
            |_, _| Ok(Profile::Higher(vec![1.0], 5)),
            |t, _, _| Ok(fit_at(t[0], 0.5)),
            "test",
            &|_| {},
        );
        assert!(!settled.refitted && settled.outcome.is_none());
        assert_eq!(settled.fit.internal, vec![0.0]);
        assert_eq!(settled.spent, 15);
    }

    /// A parameter held to another (h ≤ m, as the backlash spread to its clearance) whose ℓ
    /// is even about its null and rises away from it: ℓ = −100(m − 0.4)² + 50h² − 200h⁴
    /// (maximum h = 0.354 at m = 0.4; at h = 0, ∂ℓ/∂h = 0 and ℓ curves upward). The axis scan
    /// from the null cannot move h (m = 0 holds it at 0); the start scans it again from the
    /// best m, so h starts away from 0. Fails with that second scan taken out (h = 0).
    #[test]
    fn a_held_parameter_is_scanned_from_the_best_point() {
        let project = |t: &mut [f64], _fixed: Option<usize>| t[1] = t[1].min(t[0]);
        let mut calls = 0;
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            calls += 1;
            let (m, h) = (t[0], t[1]);
            Ok(vec![
                -100.0 * (m - 0.4).powi(2) + 50.0 * h * h - 200.0 * h.powi(4),
            ])
        };
        let start = best_start(&[0.0, 0.0], &project, &mut f).unwrap();
        assert_eq!(start[0], 0.375, "{start:?}");
        assert_eq!(start[1], 0.375, "{start:?}");
        // The null, m's 7 points, h's 3 (0.125, 0.25, 0.375: those above project onto
        // 0.375, not evaluated again).
        assert_eq!(calls, 1 + 7 + 3, "{calls}");
    }

    /// p-values for people: below what a double tells from 0, `< 1e-16`, never `0.00e0`.
    #[test]
    fn p_values_read_plainly() {
        assert_eq!(p_text(0.0), "< 1e-16");
        assert_eq!(p_is(1e-20), "p < 1e-16");
        assert_eq!(p_is(0.034), "p = 0.03");
        assert_eq!(p_text(2.5e-7), "2.5e-7");
    }

    /// A profile interval of 0.11 µm out of a 0.05 mm range is determined, also where the
    /// Wald interval was not found (a backlash fit with its spread at 0: the curvature not
    /// positive definite); a Wald interval over most of the range makes it undetermined
    /// (a parameter held small by a constraint); with neither interval found, nothing is.
    #[test]
    fn an_unfound_wald_interval_leaves_the_decision_to_the_profile() {
        let p = Parameter::linear("clearance", "mm", 0.0, 0.05, 0.0);
        let interval = |lower: Option<f64>, upper: Option<f64>, method| Interval {
            lower,
            upper,
            lower_at_range_end: false,
            upper_at_range_end: false,
            method,
            threshold: None,
        };
        let mut fitted = FittedParameter {
            name: p.name.clone(),
            unit: p.unit,
            value: 0.01049,
            interval: interval(None, None, "wald"),
            wald_interval: interval(None, None, "wald"),
            joint_interval: None,
            range: [p.low, p.high],
            null: p.null,
            determined: false,
        };
        assert_eq!(fitted.coverage(&p), 1.0);
        fitted.set_interval(&p, interval(Some(0.010444), Some(0.010554), "profile"));
        assert!(
            fitted.determined && fitted.coverage(&p) < 0.01,
            "{fitted:?}"
        );
        fitted.wald_interval = interval(Some(0.0), Some(0.04), "wald");
        fitted.set_interval(&p, interval(Some(0.010444), Some(0.010554), "profile"));
        assert!(!fitted.determined, "{fitted:?}");
    }
}
