//! The study's files: `allocated-job.json`, `tolerance.json`, `tolerance.md` (and the plots,
//! [`crate::plot`]).
//!
//! ## `tolerance.json` (σ in mm, angles in rad; arcsec only in fields named so)
//!
//! | field | meaning |
//! |---|---|
//! | `format`, `version` | `"truss-tolerance"`, 1 |
//! | `job_id`, `case` | the input job's id and the case studied |
//! | `target_rad`, `target_arcsec`, `percentile` | θ* and the percentile q (in %) |
//! | `groups` | map group → `{"sigma", "share", "share_interval": [lo, hi], "members" (a lot part: its lots), "fixed", "lot" (a production lot's shared part, `GROUP.lot`, held at its σ), "input_sigma", "weight", "sensitivity" (S_g, mm⁻²), "dtheta_dsigma" (∂θ_Pq/∂σ_g at the input σ, rad/mm)}` |
//! | `members` | per member with a length error: `{"id", "group", "share", "share_interval", "share_x", "share_y"}` |
//! | `nonlinear_share`, `nonlinear_interval` | the variance share no linear model explains |
//! | `input` | θ_Pq at the input σ: `{"theta_p", "interval", "samples", "model_theta_p"}` |
//! | `uniform_sigma` | the common σ that meets the target (found as the allocation is) |
//! | `uniform_verified` | its run: `{"theta_p", "interval", "samples"}` |
//! | `cost`, `uniform_cost`, `cost_ratio` | `Σ w_g n_g/σ_g` \[mm⁻¹\] of the allocation and of the uniform σ, and their ratio |
//! | `verified` | the last run: `{"theta_p", "interval", "samples", "passed"}` |
//! | `runs` | every verification run: `{"sigma": {group: σ}, "theta_p", "interval", "model_theta_p"}` |
//! | `isotropy` | λ₂/λ₁ of the tilt's model covariance at the allocation (1: Rayleigh) |
//! | `budget` | `null`, or where the job states an alignment budget, the allocation against it (see [`crate::study`]): `{"percentile", "lines": [{"quantity", "limit" (rad, mm), "value", "interval", "passes"}], "scale" (c: min limit/value, corrected by runs), "binding", "sigma": {group: c·σ}, "at_sigma": the lines at c·σ}` |
//!
//! Intervals are 95 %: Poisson bootstrap, percentile method (B = 200) for shares, BCa
//! (B = 2000) for θ_Pq.

use crate::errors::ToleranceError;
use crate::outcome::Tolerance;
use crate::plot;
use crate::setup::Study;
use run_dir::OutputDir;
use serde_json::{Map, Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;
use truss_units::ARCSEC_PER_RAD;

/// A finite number, or null.
fn num(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

fn pair(p: (f64, f64)) -> Value {
    json!([num(p.0), num(p.1)])
}

/// The `tolerance.json` document.
pub fn json(t: &Tolerance) -> Value {
    let mut groups = Map::new();
    for g in &t.groups {
        groups.insert(
            g.name.clone(),
            json!({
                "sigma": num(g.sigma),
                "share": num(g.share.0),
                "share_interval": pair(g.share.1),
                "members": g.members,
                "fixed": g.fixed,
                "lot": g.lot,
                "input_sigma": num(g.input_sigma),
                "weight": num(g.weight),
                "sensitivity": num(g.sensitivity),
                "dtheta_dsigma": num(g.derivative),
            }),
        );
    }
    let fit = &t.sensitivity.fit;
    let members: Vec<Value> = t
        .members
        .iter()
        .enumerate()
        .map(|(j, (id, g))| {
            json!({
                "id": id,
                "group": t.groups[*g].name,
                "share": num(fit.share[j]),
                "share_interval": pair(t.sensitivity.share_interval[j]),
                "share_x": num(fit.share_x[j]),
                "share_y": num(fit.share_y[j]),
            })
        })
        .collect();
    let runs: Vec<Value> = t
        .runs
        .iter()
        .map(|(s, p, m)| {
            let sigma: Map<String, Value> = t
                .groups
                .iter()
                .zip(s)
                .map(|(g, s)| (g.name.clone(), num(*s)))
                .collect();
            json!({"sigma": sigma, "theta_p": num(p.theta), "interval": pair(p.interval),
                   "model_theta_p": num(*m)})
        })
        .collect();
    let (_, last, _) = t.verified_run();
    let budget = t.budget.as_ref().map_or(Value::Null, |b| {
        let lines_of = |lines: &[(&str, f64, crate::verify::Percentile, bool)]| -> Vec<Value> {
            lines
                .iter()
                .map(|(quantity, limit, q, passes)| {
                    json!({"quantity": quantity, "limit": num(*limit), "value": num(q.theta),
                           "interval": pair(q.interval), "passes": passes})
                })
                .collect()
        };
        let lines = lines_of(&b.lines);
        let scaled = lines_of(&b.scaled);
        let sigma: Map<String, Value> = t
            .groups
            .iter()
            .zip(&b.sigmas)
            .map(|(g, s)| (g.name.clone(), num(*s)))
            .collect();
        json!({"percentile": num(b.percentile), "lines": lines, "scale": num(b.scale),
               "binding": b.binding, "sigma": sigma, "at_sigma": scaled})
    });
    json!({
        "format": "truss-tolerance",
        "version": 1,
        "job_id": t.job_id,
        "case": t.case,
        "target_rad": num(t.target_rad),
        "target_arcsec": num(t.target_rad * ARCSEC_PER_RAD),
        "percentile": num(t.percentile),
        "groups": groups,
        "members": members,
        "nonlinear_share": num(t.sensitivity.nonlinear.0),
        "nonlinear_interval": pair(t.sensitivity.nonlinear.1),
        "input": {"theta_p": num(t.input.theta), "interval": pair(t.input.interval),
                  "samples": t.input.samples, "model_theta_p": num(t.input_model)},
        "uniform_sigma": num(t.uniform_sigma),
        "uniform_verified": {"theta_p": num(t.uniform_run.1.theta), "interval": pair(t.uniform_run.1.interval),
                             "samples": t.uniform_run.1.samples},
        "cost": num(t.cost.0),
        "uniform_cost": num(t.cost.1),
        "cost_ratio": num(t.cost_ratio()),
        "verified": {"theta_p": num(last.theta), "interval": pair(last.interval),
                     "samples": last.samples, "passed": t.verified},
        "runs": runs,
        "isotropy": num(t.isotropy),
        "budget": budget,
    })
}

fn arcsec(x: f64) -> f64 {
    x * ARCSEC_PER_RAD
}

/// The `tolerance.md` text.
pub fn markdown(t: &Tolerance) -> String {
    let mut s = String::new();
    let q = t.percentile;
    let (_, last, _) = t.verified_run();
    let _ = writeln!(s, "# Tolerance allocation: case `{}`\n", t.case);
    let _ = writeln!(
        s,
        "Target: θ_P{q} ≤ {}. Job `{}`. Units: σ in mm, angles in rad.\n",
        t.target_set,
        &t.job_id[..12.min(t.job_id.len())]
    );
    let _ = writeln!(
        s,
        "**Verified:** θ_P{q} = {:.4e} rad ({:.2}\"), 95 % BCa interval [{:.4e}, {:.4e}] over {} samples: {}.\n",
        last.theta,
        arcsec(last.theta),
        last.interval.0,
        last.interval.1,
        last.samples,
        if t.verified {
            "meets the target at its upper bound, within 10 % of it"
        } else {
            "**does not verify**"
        }
    );
    if let Some(b) = &t.budget {
        let _ = writeln!(s, "**Budget** at the {}th percentile:\n", b.percentile);
        let _ = writeln!(
            s,
            "| line | limit | value [95 % CI] | passes |\n|---|---|---|---|"
        );
        for (quantity, limit, p, passes) in &b.lines {
            let _ = writeln!(
                s,
                "| {quantity} | {limit:.4e} | {:.4e} [{:.4e}, {:.4e}] | {} |",
                p.theta,
                p.interval.0,
                p.interval.1,
                if *passes { "yes" } else { "**no**" }
            );
        }
        let sigmas: Vec<String> = t
            .groups
            .iter()
            .zip(&b.sigmas)
            .map(|(g, s)| format!("{} {s:.4e} mm", g.name))
            .collect();
        let _ = writeln!(
            s,
            "\nEvery line met at {:.4} × the allocated σ ({}); binds: {}.\n",
            b.scale,
            sigmas.join(", "),
            b.binding
        );
        let at: Vec<String> = b
            .scaled
            .iter()
            .map(|(quantity, limit, p, _)| format!("{quantity} {:.4}", p.theta / limit))
            .collect();
        let _ = writeln!(
            s,
            "There, each line's percentile over its limit: {}.\n",
            at.join(", ")
        );
    }
    let _ = writeln!(s, "## Groups\n");
    let _ = writeln!(
        s,
        "| group | members | input σ | share of Var tan θ [95 %] | ∂θ_P{q}/∂σ [rad/mm] | weight | allocated σ | |\n|---|---|---|---|---|---|---|---|"
    );
    for g in &t.groups {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4e} | {:.4} [{:.4}, {:.4}] | {:.4e} | {} | {:.4e} | {} |",
            g.name,
            g.members,
            g.input_sigma,
            g.share.0,
            g.share.1.0,
            g.share.1.1,
            g.derivative,
            g.weight,
            g.sigma,
            match (g.lot, g.fixed) {
                (true, _) => "lot part, held at its σ",
                (false, true) => "fixed",
                (false, false) => "",
            }
        );
    }
    let nl = &t.sensitivity.nonlinear;
    let _ = writeln!(
        s,
        "\nNot explained by a linear model (slack-set nonlinearity): {:.4} [{:.4}, {:.4}]. Shares: regression of the tilts of {} samples on the drawn errors; intervals: Poisson bootstrap, B = {}.\n",
        nl.0,
        nl.1.0,
        nl.1.1,
        t.sensitivity.samples,
        crate::sensitivity::REPLICATES
    );
    let _ = writeln!(
        s,
        "## Cost\n\nCost Σ w·n/σ: allocated {:.5e}, uniform σ = {:.4e} mm {:.5e}; ratio **{:.4}** (a saving of {:.1} %).\n",
        t.cost.0,
        t.uniform_sigma,
        t.cost.1,
        t.cost_ratio(),
        100.0 * (1.0 - t.cost_ratio())
    );
    let _ = writeln!(
        s,
        "The uniform σ, after {} run(s) (the model's value, then rescaled as the allocation is): θ_P{q} = {:.4e} [{:.4e}, {:.4e}] rad.\n",
        t.uniform_run.0,
        t.uniform_run.1.theta,
        t.uniform_run.1.interval.0,
        t.uniform_run.1.interval.1
    );
    let _ = writeln!(
        s,
        "## Runs\n\nAt the input σ: θ_P{q} = {:.4e} [{:.4e}, {:.4e}] rad (model {:.4e}). Tilt isotropy λ₂/λ₁ = {:.4} at the allocation.\n",
        t.input.theta, t.input.interval.0, t.input.interval.1, t.input_model, t.isotropy
    );
    let _ = writeln!(
        s,
        "| run | σ per group | θ_P{q} [95 %] | model | upper / target |\n|---|---|---|---|---|"
    );
    for (i, (sig, p, m)) in t.runs.iter().enumerate() {
        let sig: Vec<String> = t
            .groups
            .iter()
            .zip(sig)
            .map(|(g, v)| format!("{} {:.4e}", g.name, v))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {:.4e} [{:.4e}, {:.4e}] | {:.4e} | {:.4} |",
            i + 1,
            sig.join(", "),
            p.theta,
            p.interval.0,
            p.interval.1,
            m,
            p.interval.1 / t.target_rad
        );
    }
    let mut order: Vec<usize> = (0..t.members.len()).collect();
    let share = &t.sensitivity.fit.share;
    order.sort_by(|&a, &b| share[b].total_cmp(&share[a]));
    let _ = writeln!(
        s,
        "\n## Members with the largest shares\n\n| member | group | share [95 %] |\n|---|---|---|"
    );
    for &j in order.iter().take(10) {
        let (lo, hi) = t.sensitivity.share_interval[j];
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} [{:.4}, {:.4}] |",
            t.members[j].0, t.groups[t.members[j].1].name, share[j], lo, hi
        );
    }
    s
}

/// The files the study writes besides its plots.
pub const FILES: [&str; 3] = ["allocated-job.json", "tolerance.json", "tolerance.md"];

/// Writes every file into the output directory `out`; returns their paths.
pub fn write_all(
    study: &Study,
    t: &Tolerance,
    out: &mut OutputDir,
    plots: bool,
) -> Result<Vec<PathBuf>, ToleranceError> {
    let (sigmas, _, _) = t.verified_run();
    let mut json_text = serde_json::to_string_pretty(&json(t)).expect("a JSON value serialises");
    json_text.push('\n');
    let mut files = vec![
        out.write(FILES[0], study.allocated_spec(sigmas).to_json().as_bytes())?,
        out.write(FILES[1], json_text.as_bytes())?,
        out.write(FILES[2], markdown(t).as_bytes())?,
    ];
    if plots {
        files.extend(plot::draw_all(t, out)?);
    }
    Ok(files)
}
