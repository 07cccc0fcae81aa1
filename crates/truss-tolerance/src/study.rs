//! The whole study: sensitivity run, allocation, verification with one homogeneity rescale,
//! the uniform σ for comparison, the job's alignment budget, and the output files (see the
//! crate doc for the method).
//!
//! ## The budget
//!
//! Where the job states a budget (`truss_job::budget`), the allocation is also held to every
//! line: a run at the allocated σ (the last verification run's job, so its samples) gives
//! each line's percentile `q` at the budget's percentile (θ_P, decenter, |despace|, with
//! their 95 % BCa intervals; a line passes when the interval's upper end is within its
//! limit), and by homogeneity the common factor
//!
//! ```text
//! c = min over lines of limit / q,      σ_g ← c · σ_g for every group
//! ```
//!
//! meets them all, the line attaining the minimum binding. As for θ_P, homogeneity is only
//! approximate (the pretension, the slack set), so a run at `c·σ` is made and `c`
//! corrected by the secant of `ln(min limit/q)` against `ln c` through the last two runs
//! (the allocation's at `c = 1` first), up to [`BUDGET_RUNS`] runs in all, until the binding
//! line is at or below its limit by at most [`BUDGET_BAND`] (`1 ≤ min limit/q ≤ 1.02`); the last run's lines are reported beside the allocation's. The σ ratios stay
//! θ_P's optimum; `c` is reported, not applied to `allocated-job.json`.

use crate::allocate::{self, AllocationError, GroupModel};
use crate::errors::ToleranceError;
use crate::options::{Options, bad};
use crate::outcome::{BudgetCheck, GroupResult, Tolerance};
use crate::sensitivity::{LotColumns, sensitivity};
use crate::setup::Study;
use crate::simulate::run_case;
use crate::verify::{Percentile, percentile};
use crate::{plot, report};
use truss_units::ARCSEC_PER_RAD;

/// The target's margin: the rescale aims the interval's upper end at θ*(1 − MARGIN), so that
/// the residual non-homogeneity (see the crate doc) rarely tips a rescaled run over θ*.
pub const MARGIN: f64 = 3e-3;

/// Least share of the variance a free group must have to be allocated.
pub const LEAST_SHARE: f64 = 1e-9;

/// Budget runs at most: the allocation's, then rescaled ones (see the module doc).
pub const BUDGET_RUNS: usize = 5;

/// How far below its limit the binding line may end, as a fraction of the limit's ratio:
/// the rescale stops when `1 ≤ min limit/q ≤ 1 + BUDGET_BAND`.
pub const BUDGET_BAND: f64 = 0.02;

/// Verification runs at most (the first, then rescaled ones).
const MAX_RUNS: usize = 3;

fn say(quiet: bool, message: &str) {
    if !quiet {
        eprintln!("tolerance: {message}");
    }
}

/// Runs σ values from `sigmas_for(model target)` until one verifies (at most [`MAX_RUNS`]
/// runs): first at the target, then at `θ*(1 − MARGIN)/f` with `f` the last run's
/// `θ_Pq,upper(MC) / θ_Pq(model)`. Returns every run: (σ, θ_Pq, model θ_Pq).
fn meet_target(
    target: f64,
    models: &[GroupModel],
    q: f64,
    sigmas_for: impl Fn(f64) -> Result<Vec<f64>, ToleranceError>,
    run: impl Fn(&[f64]) -> Result<Percentile, ToleranceError>,
) -> Result<Vec<(Vec<f64>, Percentile, f64)>, ToleranceError> {
    let aim = target * (1.0 - MARGIN);
    let mut sigmas = sigmas_for(target)?;
    let mut runs: Vec<(Vec<f64>, Percentile, f64)> = Vec::new();
    loop {
        let p = run(&sigmas)?;
        let m = allocate::model_theta(models, &sigmas, q);
        runs.push((sigmas.clone(), p, m));
        if (runs.len() > 1 && p.verifies(target)) || runs.len() == MAX_RUNS {
            return Ok(runs);
        }
        sigmas = sigmas_for(aim * m / p.interval.1)?;
    }
}

/// The writer's name in its output directory's manifest (crate `run-dir`).
pub const WRITER: &str = "truss-tolerance";

/// Runs the study and writes its files (see the crate doc): each through a temporary file,
/// never through a link (a link or a non-file at any of their names is refused before the
/// work), with the directory locked while they are written and a manifest of them kept.
/// Returns [`ToleranceError::Verification`] (after writing the files) if the allocation
/// does not verify.
pub fn run(options: &Options) -> Result<Tolerance, ToleranceError> {
    let o = options;
    o.check()?;
    // Before any work: no output may go through a link.
    let outputs: Vec<&str> = report::FILES.iter().chain(&plot::PLOTS).copied().collect();
    run_dir::OutputDir::check(&o.out, WRITER, &outputs)?;
    let study = Study::read(&o.job, &o.case, &o.costs, &o.fixes)?;
    let mut result = analyse(o, &study)?;
    let last = result.verified_run().1;
    let mut out = run_dir::OutputDir::open(&o.out, WRITER)?;
    out.check_names(&outputs)?;
    result.files = report::write_all(&study, &result, &mut out, o.plots)?;
    out.finish()?;
    if !result.verified {
        return Err(ToleranceError::Verification {
            percentile: o.percentile,
            theta: last.theta,
            lower: last.interval.0,
            upper: last.interval.1,
            target: o.target,
        });
    }
    Ok(result)
}

/// The study's work, between reading the case and writing the files: 1. the sensitivity run
/// at the input σ and the member shares; 2. the groups' model, its derivatives and the
/// allocation; 3. verification with the homogeneity rescale; 4. the uniform σ the same way.
fn analyse(o: &Options, study: &Study) -> Result<Tolerance, ToleranceError> {
    let job_id = truss_job::Job::new(&study.spec, &study.base)?.id;
    let target = o.target.rad();
    let q = o.percentile / 100.0;
    let threads = truss_threads::or_available(o.threads).max(1);
    let seed = study.spec.seed;

    // 1. Sensitivity at the input σ.
    let input_sigmas = study.input_sigmas();
    let probe = study.job_with(&input_sigmas, 1)?;
    let model = probe.cases[0].model.clone();
    let names: Vec<&str> = study.groups.iter().map(|g| g.name.as_str()).collect();
    let (columns, group_of): (Vec<usize>, Vec<usize>) = model
        .members()
        .iter()
        .enumerate()
        .filter_map(|(i, m)| names.iter().position(|n| *n == m.group).map(|g| (i, g)))
        .unzip();
    let least = 10 * (columns.len() + 1);
    if o.sensitivity_samples < least.max(1000) {
        return Err(bad(
            "--sensitivity-samples",
            format!(
                "{} samples: the regression on {} members needs at least {}",
                o.sensitivity_samples,
                columns.len(),
                least.max(1000)
            ),
        ));
    }
    say(
        o.quiet,
        &format!(
            "sensitivity: {} samples of case {:?}",
            o.sensitivity_samples, o.case
        ),
    );
    let sens_job = study.job_with(&input_sigmas, o.sensitivity_samples as u64)?;
    let sens_run = run_case(&sens_job, &columns, threads, "sensitivity")?;
    let column_sigma: Vec<f64> = group_of.iter().map(|&g| input_sigmas[g]).collect();
    // Each lot part's lots as columns (a group's members all have errors, so all are columns).
    let column_of = |i: usize| columns.iter().position(|&c| c == i);
    let lots: Vec<LotColumns> = study
        .groups
        .iter()
        .enumerate()
        .filter_map(|(g, group)| {
            let (_, lots) = group.lots.as_ref()?;
            Some(LotColumns {
                group: g,
                lots: lots
                    .iter()
                    .map(|lot| lot.iter().filter_map(|&i| column_of(i)).collect())
                    .collect(),
                sigma: group.sigma,
            })
        })
        .collect();
    let sens = sensitivity(
        &sens_run,
        &column_sigma,
        &group_of,
        study.groups.len(),
        &lots,
        seed,
        threads,
    )?;
    let input = percentile(&sens_run.theta_p, q, seed, threads)?;

    // 2. The groups' model, derivatives, allocation.
    let mut models: Vec<GroupModel> = study
        .groups
        .iter()
        .map(|g| GroupModel {
            covariance: [0.0; 3],
            members: g.members,
            weight: g.weight,
            fixed: g.fixed,
            shared: g.is_lot(),
        })
        .collect();
    for (j, &g) in group_of.iter().enumerate() {
        for k in 0..3 {
            models[g].covariance[k] += sens.fit.covariance[j][k];
        }
    }
    for lot in &lots {
        models[lot.group].covariance = lot.covariance(&sens.fit);
    }
    for ((g, m), &(share, _)) in study.groups.iter().zip(&models).zip(&sens.group_share) {
        if m.fixed.is_none() && (share < LEAST_SHARE || m.sensitivity() <= 0.0) {
            return Err(ToleranceError::ZeroSensitivity {
                group: g.name.clone(),
                share,
            });
        }
    }
    let input_model = allocate::model_theta(&models, &input_sigmas, q);
    let calibration = input.theta / input_model;
    let derivative = |g: usize| {
        // A lot part of σ 0: θ_Pq is even in σ, so the symmetric difference gives 0.
        let h = if input_sigmas[g] > 0.0 {
            1e-4 * input_sigmas[g]
        } else {
            1e-7
        };
        let mut up = input_sigmas.clone();
        let mut down = input_sigmas.clone();
        up[g] += h;
        down[g] -= h;
        calibration
            * (allocate::model_theta(&models, &up, q) - allocate::model_theta(&models, &down, q))
            / (2.0 * h)
    };
    let unreachable = |theta_fixed: f64| {
        let fixed: Vec<&str> = study
            .groups
            .iter()
            .filter(|g| g.fixed.is_some())
            .map(|g| g.name.as_str())
            .collect();
        ToleranceError::Unreachable {
            groups: fixed.join(", "),
            percentile: o.percentile,
            theta_fixed,
            arcsec: theta_fixed * ARCSEC_PER_RAD,
            target: o.target,
        }
    };
    let allocate_for = |model_target: f64| {
        allocate::allocate(&models, model_target, q).map_err(|e| match e {
            AllocationError::Unreachable { theta_fixed } => {
                // Said in measured terms: the model's value times the calibration.
                unreachable(theta_fixed * target / model_target)
            }
        })
    };

    // 3. Verification, with the homogeneity rescale; 4. the uniform σ the same way.
    let verify_run = |stage: &'static str, sigmas: &[f64]| -> Result<Percentile, ToleranceError> {
        say(o.quiet, &format!("{stage} run: {} samples", o.samples));
        let job = study.job_with(sigmas, o.samples as u64)?;
        let r = run_case(&job, &[], threads, stage)?;
        percentile(&r.theta_p, q, seed, threads)
    };
    let runs = meet_target(target, &models, q, allocate_for, |s| {
        verify_run("verification", s)
    })?;
    let (last_sigmas, last, _) = runs.last().expect("one run").clone();
    let (l1, l2) = crate::percentile::eigenvalues(&allocate::covariance(&models, &last_sigmas));
    let isotropy = if l1 > 0.0 { l2 / l1 } else { 1.0 };
    let uniform_runs = meet_target(
        target,
        &models,
        q,
        |t| {
            let u = allocate::uniform(&models, t, q);
            Ok(models
                .iter()
                .map(|m| match (m.shared, m.fixed) {
                    (true, Some(s)) => s,
                    _ => u,
                })
                .collect())
        },
        |s| verify_run("uniform", s),
    )?;
    let (u_sigmas, u_p, _) = uniform_runs.last().expect("one run").clone();
    let uniform_sigma = u_sigmas[0];
    let uniform_cost = allocate::cost(&models, &u_sigmas);
    let cost = (allocate::cost(&models, &last_sigmas), uniform_cost);

    // 5. The job's alignment budget, if it states one: every line at the allocation, on the
    // samples of the last verification run (the same job, so the same draws).
    let budget = match study.spec.budget.as_ref().map(|b| b.budget()) {
        None => None,
        Some(b) => {
            let lines_at = |stage: &'static str, sigmas: &[f64]| {
                say(o.quiet, &format!("{stage} run: {} samples", o.samples));
                let job = study.job_with(sigmas, o.samples as u64)?;
                let r = run_case(&job, &[], threads, stage)?;
                let despace: Vec<f64> = r.despace.iter().map(|d| d.abs()).collect();
                let mut lines = Vec::new();
                for (quantity, limit) in b.lines() {
                    let values = match quantity {
                        "theta_p" => &r.theta_p,
                        "decenter" => &r.decenter,
                        _ => &despace,
                    };
                    let q = percentile(values, b.percentile / 100.0, seed, threads)?;
                    lines.push((quantity, limit, q, q.interval.1 <= limit));
                }
                Ok::<_, ToleranceError>(lines)
            };
            let least = |lines: &[(&'static str, f64, Percentile, bool)]| {
                lines
                    .iter()
                    .map(|(quantity, limit, q, _)| (limit / q.theta, *quantity))
                    .fold((f64::INFINITY, ""), |a, b| if b.0 < a.0 { b } else { a })
            };
            let lines = lines_at("budget", &last_sigmas)?;
            let (first, binding) = least(&lines);
            // The rescale by homogeneity, checked by a run and corrected by the secant of
            // ln(least ratio) against ln c through the last two runs, up to BUDGET_RUNS runs
            // in all, until the binding line is within BUDGET_BAND below its limit.
            let (mut before, mut scale) =
                ((0.0f64, first.ln() - (0.5 * BUDGET_BAND).ln_1p()), first);
            let mut scaled = lines.clone();
            for _ in 1..BUDGET_RUNS {
                let sigmas: Vec<f64> = last_sigmas.iter().map(|s| s * scale).collect();
                scaled = lines_at("budget rescale", &sigmas)?;
                let (r, _) = least(&scaled);
                if (1.0..=1.0 + BUDGET_BAND).contains(&r) {
                    break;
                }
                // Aim at the middle of the band.
                let now = (scale.ln(), r.ln() - (0.5 * BUDGET_BAND).ln_1p());
                let slope = (now.1 - before.1) / (now.0 - before.0);
                let next = if slope.is_finite() && slope < 0.0 {
                    now.0 - now.1 / slope
                } else {
                    now.0 + now.1
                };
                before = now;
                scale = next.exp();
            }
            Some(BudgetCheck {
                percentile: b.percentile,
                lines,
                scale,
                binding,
                sigmas: last_sigmas.iter().map(|s| s * scale).collect(),
                scaled,
            })
        }
    };

    let groups = study
        .groups
        .iter()
        .enumerate()
        .map(|(g, s)| GroupResult {
            name: s.name.clone(),
            sigma: last_sigmas[g],
            input_sigma: s.sigma,
            share: sens.group_share[g],
            sensitivity: models[g].sensitivity(),
            derivative: derivative(g),
            members: s.members,
            weight: s.weight,
            fixed: s.fixed.is_some(),
            lot: s.is_lot(),
        })
        .collect();
    let members = columns
        .iter()
        .zip(&group_of)
        .map(|(&i, &g)| (model.members()[i].id.clone(), g))
        .collect();
    Ok(Tolerance {
        case: o.case.clone(),
        job_id,
        target_rad: target,
        target_set: o.target,
        percentile: o.percentile,
        groups,
        members,
        sensitivity: sens,
        input,
        input_model,
        uniform_sigma,
        uniform_run: (uniform_runs.len(), u_p),
        cost,
        runs,
        isotropy,
        verified: last.verifies(target),
        budget,
        files: Vec::new(),
    })
}
