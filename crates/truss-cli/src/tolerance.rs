//! `truss tolerance`: argument parsing over the `truss_tolerance` library, which does the
//! work (sensitivity shares, the cheapest per-group σ for a θ_P budget, its verification).

use crate::CliError;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Options of `truss tolerance`.
#[derive(Debug, Args)]
pub struct ToleranceArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The case whose groups' tolerances are allocated (its σ values are the starting point).
    #[arg(long)]
    pub case: String,
    /// The budget: θ_P at the percentile must not exceed this angle (rad; mc-merge's
    /// `--target-angle`, so that both answer for the same target, e.g. 9.69e-5).
    #[arg(
        long,
        allow_negative_numbers = true,
        required_unless_present = "target_arcsec",
        conflicts_with = "target_arcsec"
    )]
    pub target_angle: Option<f64>,
    /// The budget in arcsec instead (20 is 9.6963e-5 rad).
    #[arg(long, allow_negative_numbers = true)]
    pub target_arcsec: Option<f64>,
    /// The percentile of θ_P the budget applies to (%).
    #[arg(long, default_value_t = 95.0, allow_negative_numbers = true)]
    pub percentile: f64,
    /// A group's cost weight, `GROUP=WEIGHT` (default 1: cost = members / σ); repeatable.
    #[arg(long = "cost", value_name = "GROUP=WEIGHT")]
    pub costs: Vec<String>,
    /// Pin a group at a supplier's tolerance, `GROUP=SIGMA` (mm); repeatable.
    #[arg(long = "fix", value_name = "GROUP=SIGMA")]
    pub fixes: Vec<String>,
    /// Samples of each verification run.
    #[arg(long, default_value_t = 20_000)]
    pub samples: usize,
    /// Samples of the sensitivity (regression) run.
    #[arg(long, default_value_t = 4_000)]
    pub sensitivity_samples: usize,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output directory (tolerance.json, tolerance.md, allocated-job.json, plots).
    #[arg(long)]
    pub out: PathBuf,
    /// No SVG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `truss tolerance`; prints the allocation and the files written.
pub fn run(args: &ToleranceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let options = truss_tolerance::Options {
        percentile: args.percentile,
        costs: args.costs.clone(),
        fixes: args.fixes.clone(),
        samples: args.samples,
        sensitivity_samples: args.sensitivity_samples,
        plots: !args.no_plots,
        threads: args.threads,
        quiet: args.quiet,
        ..truss_tolerance::Options::new(
            args.job.clone(),
            &args.case,
            match (args.target_angle, args.target_arcsec) {
                (Some(rad), _) => truss_tolerance::TargetAngle::Rad(rad),
                (None, Some(arcsec)) => truss_tolerance::TargetAngle::Arcsec(arcsec),
                (None, None) => unreachable!("clap requires one of the two"),
            },
            args.out.clone(),
        )
    };
    let t = truss_tolerance::run(&options)?;
    let (_, last, _) = t.verified_run();
    for g in &t.groups {
        writeln!(
            out,
            "{}: sigma {:.4e} mm (variance share {:.4} [{:.4}, {:.4}]{})",
            g.name,
            g.sigma,
            g.share.0,
            g.share.1.0,
            g.share.1.1,
            if g.fixed { ", fixed" } else { "" }
        )?;
    }
    writeln!(
        out,
        "theta_p{}: {:.4e} rad [{:.4e}, {:.4e}] over {} samples, target {}\nuniform_sigma: {:.4e} mm\ncost_ratio: {:.4}",
        t.percentile,
        last.theta,
        last.interval.0,
        last.interval.1,
        last.samples,
        t.target_set,
        t.uniform_sigma,
        t.cost_ratio()
    )?;
    if let Some(b) = &t.budget {
        for (quantity, limit, p, passes) in &b.lines {
            writeln!(
                out,
                "budget {quantity}{}: {:.4e} [{:.4e}, {:.4e}], limit {limit:.4e}: {}",
                b.percentile,
                p.theta,
                p.interval.0,
                p.interval.1,
                if *passes { "passes" } else { "FAILS" }
            )?;
        }
        let sigmas: Vec<String> = t
            .groups
            .iter()
            .zip(&b.sigmas)
            .map(|(g, s)| format!("{} {s:.4e} mm", g.name))
            .collect();
        writeln!(
            out,
            "budget: every line met at {:.4} x the allocated sigma ({}); binds: {}",
            b.scale,
            sigmas.join(", "),
            b.binding
        )?;
    }
    for f in &t.files {
        writeln!(out, "wrote {}", f.display())?;
    }
    Ok(())
}
