//! How the diagnosis's numbers read in words, for `diagnosis.md`: numbers and intervals to
//! a few significant digits, and a fitted parameter with its 95 % interval and what its
//! value means for the hardware, in its candidate's own words (a temperature difference
//! across the truss, a member-length error in µm, a joint's clearance).

use crate::candidates::candidate::Candidate;
use crate::comparison::baseline::Baseline;
use crate::likelihood::score::FittedParameter;
use crate::selection::Diagnosis;

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

/// Parameter `j` of effect `c` with its value and 95 % interval, and what it means where
/// its interval reaches its null, if that is a result of the effect's own
/// ([`Candidate::unresolved`]).
pub(super) fn parameter_text(c: &dyn Candidate, j: usize, p: &FittedParameter) -> String {
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
    let unresolved = c
        .unresolved(j)
        .filter(|_| i.lower.is_none_or(|l| l <= p.null) || i.lower_at_range_end)
        .unwrap_or("");
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

/// Parameter `j` of effect `c` in plain words: what its value means for the hardware
/// ([`Candidate::reading`]); none where the data do not determine it.
pub(super) fn plain_reading(
    c: &dyn Candidate,
    j: usize,
    p: &FittedParameter,
    span: [f64; 3],
) -> String {
    if p.determined {
        c.reading(j, p.value, span)
    } else {
        format!(
            "not determined by these data (its intervals leave up to {:.0} % of its plausible range open): no reading is given",
            100.0 * p.coverage(&c.parameters()[j])
        )
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

/// The effects a rival stands for: itself, or each member of a pair listed as an
/// alternative reading (`a + b`, [`crate::selection::pair::label`]), less `of` (a rival
/// pair that shares a member with the effect it is listed against).
pub(super) fn rival_effects<'a>(d: &'a Diagnosis, rival: &str, of: &str) -> Vec<&'a dyn Candidate> {
    rival
        .split(" + ")
        .filter(|&r| r != of)
        .map(|r| effect(d, r))
        .collect()
}

/// The library's candidate named `name`: every effect a report names is one of them.
pub(super) fn effect<'a>(d: &'a Diagnosis, name: &str) -> &'a dyn Candidate {
    d.candidate(name)
        .expect("every effect the diagnosis names is in its library")
}

/// Appends `s` and a newline.
pub(super) fn push(m: &mut String, s: &str) {
    m.push_str(s);
    m.push('\n');
}
