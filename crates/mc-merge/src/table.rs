//! The readable summary printed on stdout: the alignment budget when the job states one, one
//! row per case, then the sweeps and the allowable σ.
//! Angles in rad and arcsec.

use crate::report::{Figure, Report, short};
use std::fmt::Write;
use truss_units::ARCSEC_PER_RAD;

fn rad(x: f64) -> String {
    format!("{x:.3e}")
}

/// `9.690e-5 (19.99″) [19.82, 20.16]`: rad, then arcsec with the interval in arcsec.
fn angle(f: &Figure) -> String {
    match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!(
            "{} ({:.2}″) [{:.2}, {:.2}]",
            rad(v),
            v * ARCSEC_PER_RAD,
            lo * ARCSEC_PER_RAD,
            hi * ARCSEC_PER_RAD
        ),
        (Some(v), None) => format!("{} ({:.2}″) [no interval]", rad(v), v * ARCSEC_PER_RAD),
        _ => format!("- ({})", f.reason.as_deref().unwrap_or("undefined")),
    }
}

/// Like [`angle`], with the interval also in rad (for the sweeps, where there is room).
fn angle_full(f: &Figure) -> String {
    match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!(
            "{} [{}, {}] rad = {:.2} [{:.2}, {:.2}] arcsec",
            rad(v),
            rad(lo),
            rad(hi),
            v * ARCSEC_PER_RAD,
            lo * ARCSEC_PER_RAD,
            hi * ARCSEC_PER_RAD
        ),
        _ => angle(f),
    }
}

fn plain(f: &Figure, digits: usize) -> String {
    match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!("{v:.digits$e} [{lo:.digits$e}, {hi:.digits$e}]"),
        (Some(v), None) => format!("{v:.digits$e}"),
        _ => format!("- ({})", f.reason.as_deref().unwrap_or("undefined")),
    }
}

/// Renders the summary table.
pub fn render(report: &Report, files: usize) -> String {
    let mut s = String::new();
    let c = &report.coverage;
    let pct = report.sweep.percentile.0;
    let _ = writeln!(
        s,
        "job {}: {} shard files, {} of {} samples{}",
        report.job_id,
        files,
        c.present,
        c.expected,
        if c.complete {
            " (complete)".to_string()
        } else {
            format!(
                " — PARTIAL, {} missing ranges; every figure is marked partial",
                c.missing_ranges
            )
        }
    );
    if report.failed.total > 0 {
        let _ = writeln!(
            s,
            "{} failed samples EXCLUDED (--allow-failed); affected figures say so",
            report.failed.total
        );
    }
    let set = &report.settings;
    let _ = writeln!(
        s,
        "percentiles: Hyndman-Fan definition 1; intervals {:.0} % BCa (percentile method where BCa is undefined), Poisson bootstrap B = {}, seed {}; 1 rad = 206265 arcsec\n",
        set.confidence * 100.0,
        set.replicates,
        set.bootstrap_seed
    );
    if let Some(b) = &report.budget {
        s.push_str(&budget(b, set.confidence));
    }
    // One row per case.
    let name_w = report
        .cases
        .iter()
        .map(|c| c.name.chars().count())
        .max()
        .unwrap_or(4)
        .max(4);
    let head_emp = format!(
        "θ_P{pct} rad (arcsec) [{:.0} % CI, arcsec]",
        set.confidence * 100.0
    );
    let head_ray = format!("Rayleigh θ_P{pct} rad (arcsec) [CI]");
    let _ = writeln!(
        s,
        "{:<name_w$}  {:>8}  {:>6}  {:<42}  {:<42}  {:<9}  Rayleigh law",
        "case", "n", "failed", head_emp, head_ray, "σ_t"
    );
    for case in &report.cases {
        let emp = case
            .percentiles
            .iter()
            .find(|p| p.percentile.0 == pct)
            .map(|p| match (p.value, p.bca.lower, p.bca.upper) {
                (Some(v), Some(lo), Some(hi)) => Figure::new(v.0, lo.0, hi.0),
                (Some(v), _, _) => match p.percentile_bootstrap.get() {
                    Some((lo, hi)) => Figure::new(v.0, lo, hi),
                    None => Figure::without_interval(v.0, "no interval"),
                },
                _ => Figure::null(p.reason.clone().unwrap_or_default()),
            })
            .unwrap_or_default();
        let ray = case
            .rayleigh
            .percentiles
            .iter()
            .find(|p| p.percentile.0 == pct)
            .map(|p| p.value.clone())
            .unwrap_or_default();
        let verdict = match (&case.gof.verdict, &case.gof.ks, &case.gof.ad) {
            (Some(v), Some(ks), Some(ad)) => format!(
                "{v} (KS p = {:.3}, AD p = {:.3})",
                ks.p_value.0, ad.p_value.0
            ),
            _ => "not tested".to_string(),
        };
        let _ = writeln!(
            s,
            "{:<name_w$}  {:>8}  {:>6}  {:<42}  {:<42}  {:<9}  {}",
            case.name,
            case.n,
            case.failed.count,
            angle(&emp),
            angle(&ray),
            case.rayleigh
                .sigma_t
                .get()
                .map_or("-".into(), |v| format!("{v:.3e}")),
            verdict
        );
    }
    // What the rows cannot hold: the Rayleigh verdicts in words, loose joints, caveats.
    let _ = writeln!(s);
    for case in &report.cases {
        let _ = writeln!(s, "{}: {}", case.name, case.gof.summary);
        if case.loose_joints.recorded > 0 {
            let _ = writeln!(
                s,
                "{}: loose joints in {} of {} samples ({})",
                case.name,
                case.loose_joints.with_loose,
                case.loose_joints.recorded,
                plain(&case.loose_joints.fraction, 2)
            );
        }
        if case.floating.recorded > 0 {
            let _ = writeln!(
                s,
                "{}: floating stages in {} of {} samples ({})",
                case.name,
                case.floating.floating,
                case.floating.recorded,
                plain(&case.floating.fraction, 2)
            );
        }
        for c in &case.caveats {
            let _ = writeln!(s, "{}: CAVEAT {c}", case.name);
        }
    }
    for ser in &report.sweep.sigma_series {
        let _ = writeln!(s, "\nσ-series [{}]: θ_P{pct} against σ", ser.name);
        let _ = writeln!(s, "  {:>10}  θ_P{pct}", "σ [mm]");
        for p in &ser.points {
            let _ = writeln!(s, "  {:>10}  {}", short(p.x.0), angle_full(&p.value));
        }
        let fit = |name: &str, f: &crate::report::LineFit| {
            format!(
                "  {name}: slope {} rad/mm, intercept {} rad, R² {}",
                plain(&f.slope, 4),
                plain(&f.intercept, 3),
                f.r_squared.get().map_or("-".into(), |r| format!("{r:.5}"))
            )
        };
        let _ = writeln!(s, "{}", fit("line through origin", &ser.through_origin));
        let _ = writeln!(s, "{}", fit("line with intercept", &ser.with_intercept));
        let a = &ser.allowable_sigma;
        let _ = writeln!(
            s,
            "  allowable σ for θ_P{} ≤ {}: {} mm (through origin), {} mm (with intercept){}",
            short(a.percentile.0),
            report.settings.target(),
            plain(&a.through_origin, 3),
            plain(&a.with_intercept, 3),
            if a.extrapolated {
                "  [extrapolated beyond the σ range]"
            } else {
                ""
            }
        );
        if let Some((lo, _)) = a.through_origin.interval() {
            let _ = writeln!(
                s,
                "  conservative choice: σ ≤ {lo:.3e} mm (lower {:.0} % bound)",
                set.confidence * 100.0
            );
        }
    }
    for ser in &report.sweep.stages_series {
        let _ = writeln!(
            s,
            "\nstages-series [{}]: θ_P{pct} normalised to {} stage(s)",
            ser.name, ser.reference_stages.0
        );
        for p in &ser.points {
            let _ = writeln!(
                s,
                "  {:>6}  {}",
                short(p.stages.0),
                match (p.normalised.get(), p.normalised.interval()) {
                    (Some(v), Some((lo, hi))) => format!("{v:.3} [{lo:.3}, {hi:.3}]"),
                    (Some(v), None) => format!("{v:.3}"),
                    _ => "-".into(),
                }
            );
        }
        if let Some(peak) = ser.peak_stages {
            let _ = writeln!(s, "  peak at {} stages", peak.0);
        }
    }
    s
}

/// A budget line's number in its unit: arcsec beside rad for θ_P, µm for lengths.
fn budget_value(quantity: &str, v: f64) -> String {
    if quantity == "theta_p" {
        format!("{:.2}\"", v * ARCSEC_PER_RAD)
    } else {
        format!("{:.2} µm", v * 1e3)
    }
}

/// The budget section, first: the lines, then per case each line's percentile against its
/// limit, the verdict, and the allowable σ meeting every line with the line that binds; per
/// σ-series the same from its lines through the origin (see [`crate::budget`]).
fn budget(b: &crate::report::BudgetReport, confidence: f64) -> String {
    let mut s = String::new();
    let lines: Vec<String> = b
        .lines
        .iter()
        .map(|l| format!("{} ≤ {}", l.of, budget_value(l.quantity, l.limit.0)))
        .collect();
    let _ = writeln!(
        s,
        "budget at the {}th percentile: {}",
        b.percentile.0,
        lines.join(", ")
    );
    let sigma = |f: &Figure| match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!(
            "{v:.4e} mm [{lo:.4e}, {hi:.4e}] ({:.0} % CI)",
            confidence * 100.0
        ),
        (Some(v), None) => format!("{v:.4e} mm"),
        _ => format!("- ({})", f.reason.as_deref().unwrap_or("undefined")),
    };
    let binds = |line: Option<&str>, share: Option<crate::report::Real>| match line {
        Some(l) => format!(
            "binds: {l}{}",
            share.map_or(String::new(), |r| format!(
                " (in {:.0} % of the bootstrap replicates)",
                r.0 * 100.0
            ))
        ),
        None => "binds: -".into(),
    };
    for c in &b.cases {
        let verdicts: Vec<String> = c
            .lines
            .iter()
            .map(|l| {
                let v = l
                    .value
                    .get()
                    .map_or("-".into(), |v| budget_value(l.quantity, v));
                let word = match (l.passes, l.clear) {
                    (Some(true), Some(false)) => "passes (within its interval)",
                    (Some(true), _) => "passes",
                    (Some(false), Some(false)) => "FAILS (within its interval)",
                    (Some(false), _) => "FAILS",
                    (None, _) => "undefined",
                };
                format!("{} {v} {word}", l.quantity)
            })
            .collect();
        let _ = writeln!(
            s,
            "  {}: {}; {}",
            c.case,
            match c.passes {
                Some(true) => "PASSES",
                Some(false) => "FAILS",
                None => "undefined",
            },
            verdicts.join(", ")
        );
        let _ = writeln!(
            s,
            "    allowable σ meeting every line: {}; {}",
            sigma(&c.allowable_sigma),
            binds(c.binding, c.binding_share)
        );
    }
    for ser in &b.series {
        let _ = writeln!(
            s,
            "  σ-series [{}]: allowable σ meeting every line {}; {}{}",
            ser.name,
            sigma(&ser.allowable_sigma),
            binds(ser.binding, ser.binding_share),
            if ser.extrapolated {
                "  [extrapolated beyond the σ range]"
            } else {
                ""
            }
        );
    }
    s.push('\n');
    s
}

/// The answer ([`crate::report::AnswerReport`]), printed last: each case's θ_P at the target
/// percentile against the target angle (above it, or at or below it), each σ-series'
/// allowable σ with its interval and its conservative end, and the Rayleigh-law rejections
/// with their p-values and effect sizes, against what chance alone gives and after Holm's
/// adjustment across the cases.
pub fn answer(report: &Report) -> String {
    let a = &report.answer;
    let pct = short(a.percentile.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nanswer: θ_P{pct} against the target {}:",
        report.settings.target()
    );
    let list = |v: Vec<&crate::report::CaseAgainstTarget>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|c| {
                    let t = c.value.get().unwrap_or(f64::NAN);
                    format!("{} ({:.2}″)", c.case, t * ARCSEC_PER_RAD)
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let _ = writeln!(s, "  above the target: {}", list(a.above().collect()));
    let _ = writeln!(s, "  at or below it: {}", list(a.within().collect()));
    let undefined: Vec<&str> = a.undefined().collect();
    if !undefined.is_empty() {
        let _ = writeln!(s, "  no θ_P{pct}: {}", undefined.join(", "));
    }
    for sigma in &a.allowable_sigma {
        let conservative = sigma
            .sigma
            .interval()
            .map(|(lo, _)| {
                format!(
                    "; conservative σ ≤ {:.3e} mm (lower {:.0} % bound)",
                    lo,
                    report.settings.confidence * 100.0
                )
            })
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "  allowable σ [{}]: {} mm{conservative}{}",
            sigma.series,
            plain(&sigma.sigma, 3),
            if sigma.extrapolated {
                " [extrapolated beyond the σ range]"
            } else {
                ""
            }
        );
    }
    let r = &a.rayleigh;
    if r.tested > 0 {
        let rejected: Vec<String> = r
            .rejected()
            .map(|v| {
                format!(
                    "{} (p = {:.3}; Rayleigh θ_P{pct} against the empirical: {})",
                    v.case,
                    v.p_value.0,
                    relative(&v.relative_difference)
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "  Rayleigh law rejected in {} of {} cases at α = {} ({:.1} expected by chance alone if it held in all){}",
            rejected.len(),
            r.tested,
            short(r.level.0),
            r.expected_by_chance.0,
            if rejected.is_empty() {
                String::new()
            } else {
                format!(": {}", rejected.join(", "))
            },
        );
        let _ = writeln!(
            s,
            "  after Holm's adjustment across the {} cases: {}",
            r.tested,
            if r.holm_rejected.is_empty() {
                format!(
                    "none rejected (smallest adjusted p = {:.3})",
                    r.smallest_holm_p().unwrap_or(1.0)
                )
            } else {
                format!("rejected in {}", r.holm_rejected.join(", "))
            }
        );
    }
    s
}

/// A relative difference with its interval, in percent: `−0.3 % [−1.2, +0.6] %`.
fn relative(f: &Figure) -> String {
    match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!(
            "{:+.1} % [{:+.1}, {:+.1}] %",
            v * 100.0,
            lo * 100.0,
            hi * 100.0
        ),
        (Some(v), None) => format!("{:+.1} %", v * 100.0),
        _ => "no effect size".to_string(),
    }
}
