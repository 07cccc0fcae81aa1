//! How the diagnosis's numbers read in words, for `diagnosis.md` and the verdicts' reasons:
//! p-values, numbers and intervals to a few significant digits, and a fitted parameter
//! with its 95 % interval and what its value means for the hardware (a temperature
//! difference across the truss, a member-length error in µm, a joint's clearance).

use crate::baseline::Baseline;
use crate::diagnose::FittedParameter;

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

pub(super) fn g(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if v.abs() >= 1e-3 && v.abs() < 1e4 {
        format!("{:.4}", v)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{v:.3e}")
    }
}

/// `[lo, hi]`, or `—` where the interval is degenerate or missing.
pub(super) fn interval_text(lower: f64, upper: f64) -> String {
    if !(lower.is_finite() && upper.is_finite()) || lower == upper {
        "—".into()
    } else {
        format!("[{}, {}]", g(lower), g(upper))
    }
}

pub(super) fn parameter_text(p: &FittedParameter) -> String {
    let i = &p.interval;
    let end = |v: Option<f64>| v.map_or("?".to_string(), g);
    // The joint region's projection, where it differs from the parameter's own interval
    // (k > 1).
    let joint = match &p.joint_interval {
        Some(j) if *j != p.interval && (j.lower.is_some() || j.upper.is_some()) => {
            format!(
                "; all parameters jointly {}–{} {}",
                end(j.lower),
                end(j.upper),
                p.unit
            )
        }
        _ => String::new(),
    };
    let iv = if i.lower.is_none() && i.upper.is_none() || i.lower == i.upper {
        format!(" (interval undetermined{joint})")
    } else {
        format!(
            " (95 % {} CI {}–{} {}{}{joint})",
            i.method,
            end(i.lower),
            end(i.upper),
            p.unit,
            match (i.lower_at_range_end, i.upper_at_range_end) {
                (true, true) => ", both ends cut at the plausible range",
                (true, false) => ", lower end cut at the plausible range",
                (false, true) => ", upper end cut at the plausible range",
                (false, false) => "",
            }
        )
    };
    // Backlash's spread (the half-width of the joints' clearances): where its interval
    // reaches 0 the data cannot tell scattered clearances from equal ones.
    let unresolved = if p.name == "spread"
        && (i.lower.is_none_or(|l| l <= 0.0) || i.lower_at_range_end)
    {
        " — spread: not resolved by these data (its interval reaches 0: the joints may all have the same clearance, which the fitted `clearance` then stands for)"
    } else {
        ""
    };
    format!("{} = {} {}{iv}{unresolved}", p.name, g(p.value), p.unit)
}

/// The size of the model along x, y, z \[mm\], for the plain reading of gradients.
pub(super) fn spans(baseline: &Baseline) -> [f64; 3] {
    let nodes = baseline.model().nodes();
    let mut out = [0.0; 3];
    for (a, o) in out.iter_mut().enumerate() {
        let lo = nodes.iter().map(|n| n.xyz[a]).fold(f64::INFINITY, f64::min);
        let hi = nodes
            .iter()
            .map(|n| n.xyz[a])
            .fold(f64::NEG_INFINITY, f64::max);
        *o = hi - lo;
    }
    out
}

/// A fitted parameter in plain words: what it means for the hardware.
pub(super) fn plain_reading(effect: &str, p: &FittedParameter, span: [f64; 3]) -> String {
    let v = p.value;
    let um = |mm: f64| format!("{:.1} µm", mm * truss_units::MICROMETRE_PER_MM);
    let name = p.name.as_str();
    match (effect, name) {
        ("thermal_gradient", "offset") => format!(
            "the whole truss about {:.2} K {} than the stated conditions",
            v.abs(),
            if v >= 0.0 { "warmer" } else { "cooler" }
        ),
        ("thermal_gradient", _) => {
            let a = match name {
                "gradient_x" => 0,
                "gradient_y" => 1,
                _ => 2,
            };
            format!(
                "about {:.2} K of temperature difference across the {:.0} mm the truss spans along {}",
                (v * span[a]).abs(),
                span[a],
                ["x", "y", "z"][a]
            )
        }
        ("gravity", _) => format!(
            "self-weight of {:.2} g along {}{} (a ground test's gravity direction)",
            v.abs(),
            if v >= 0.0 { "+" } else { "−" },
            &name[2..]
        ),
        ("length_bias", _) => format!(
            "the {} members are on average {} {} than nominal",
            name.trim_start_matches("bias."),
            um(v.abs()),
            if v >= 0.0 { "longer" } else { "shorter" }
        ),
        ("length_sigma", _) => format!(
            "the {} members' lengths scatter by {} (1 SD), {:.2} times the stated {}",
            name.trim_start_matches("sigma."),
            um(v),
            v / p.null,
            um(p.null)
        ),
        ("diagonal_pretension", _) => format!(
            "the diagonals are on average {} shorter than nominal, pretensioning the frame",
            um(v.abs())
        ),
        ("backlash", "spread") => format!(
            "the joints' clearances scatter uniformly within ±{} of their mean (some joints tighter, some looser)",
            um(v)
        ),
        ("backlash", _) => format!(
            "each pin joint has on average about {} of radial clearance (free play of its shaft in the hole)",
            um(v)
        ),
        _ => String::new(),
    }
}

/// Names in code spans, joined by `separator`: `` `a`, `b` ``.
pub(super) fn code_list(names: &[impl std::fmt::Display], separator: &str) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(separator)
}
