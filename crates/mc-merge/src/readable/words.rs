//! How the report's numbers read in the readable report: angles in rad to four significant
//! digits and in arcsec to two decimals (1 rad = 648000/π arcsec), intervals in brackets,
//! fractions in percent, and a dash with the reason where a figure could not be computed.
//! Every number shown comes from the report (a [`Real`], finite by construction), so no
//! `NaN` or `inf` can be printed.

use crate::report::{CaseReport, Figure, Interval, Real, short};
use truss_units::ARCSEC_PER_RAD;

/// What a cell shows for a figure that could not be computed.
pub const NONE: &str = "—";

/// An angle in rad: `4.123e-5` (and `0`).
pub fn rad(x: f64) -> String {
    sci(x)
}

/// An angle in arcsec: `8.50`.
pub fn arcsec(x: f64) -> String {
    format!("{:.2}", x * ARCSEC_PER_RAD)
}

/// A number to four significant digits: `2.007e-2` (and `0`).
pub fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.3e}")
    }
}

/// A parameter, percentile or σ in its shortest form: `0.0063`, `95`.
pub fn plain(x: f64) -> String {
    short(x)
}

/// `[lo, hi]` with each end written by `f`.
pub fn bracket(lo: f64, hi: f64, f: impl Fn(f64) -> String) -> String {
    format!("[{}, {}]", f(lo), f(hi))
}

/// A dash, with the reason if there is one: `— (too few samples)`.
pub fn none(reason: Option<&str>) -> String {
    match reason {
        Some(r) if !r.is_empty() => format!("{NONE} ({r})"),
        _ => NONE.to_string(),
    }
}

/// An optional value written by `f`, or a dash with the reason.
pub fn value(x: Option<Real>, reason: Option<&str>, f: impl Fn(f64) -> String) -> String {
    x.map_or_else(|| none(reason), |x| f(x.0))
}

/// A figure's value written by `f`, or a dash with its reason.
pub fn figure_value(fig: &Figure, f: impl Fn(f64) -> String) -> String {
    value(fig.value, fig.reason.as_deref(), f)
}

/// A figure's interval written by `f`, or a dash (with the reason when the value exists,
/// since a missing value already shows it).
pub fn figure_interval(fig: &Figure, f: impl Fn(f64) -> String) -> String {
    match fig.interval() {
        Some((lo, hi)) => bracket(lo, hi, f),
        None if fig.value.is_some() => none(fig.reason.as_deref()),
        None => NONE.to_string(),
    }
}

/// A figure as `value [lo, hi]`, each written by `f`; without an interval, the value with
/// the reason: `0 (fixed at 0 by construction)`.
pub fn figure(fig: &Figure, f: impl Fn(f64) -> String) -> String {
    match (fig.get(), fig.interval(), fig.reason.as_deref()) {
        (Some(v), Some((lo, hi)), _) => format!("{} {}", f(v), bracket(lo, hi, &f)),
        (Some(v), None, Some(r)) if !r.is_empty() => format!("{} ({r})", f(v)),
        (Some(v), None, _) => f(v),
        (None, _, reason) => none(reason),
    }
}

/// An interval written by `f`, or a dash with its reason.
pub fn interval(i: &Interval, f: impl Fn(f64) -> String) -> String {
    match i.get() {
        Some((lo, hi)) => bracket(lo, hi, f),
        None => none(i.reason.as_deref()),
    }
}

/// A fraction in percent to one decimal: `64.4 %`.
pub fn percent(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// A relative difference in percent with its sign: `+1.2 %`, `−0.4 %`.
pub fn signed_percent(x: f64) -> String {
    let p = 100.0 * x;
    if p < 0.0 {
        format!("−{:.1} %", -p)
    } else {
        format!("+{p:.1} %")
    }
}

/// A fraction figure in percent: `64.4 % [63.5 %, 65.4 %]`.
pub fn percent_figure(fig: &Figure) -> String {
    figure(fig, percent)
}

/// The `n`th percentile in words: `95th`, `50th`, `99.9th`.
pub fn ordinal(p: f64) -> String {
    let s = plain(p);
    let suffix = if s.contains('.') {
        "th"
    } else {
        match (p as u64 % 100, p as u64 % 10) {
            (11..=13, _) => "th",
            (_, 1) => "st",
            (_, 2) => "nd",
            (_, 3) => "rd",
            _ => "th",
        }
    };
    format!("{s}{suffix}")
}

/// A case's parameters with their units: `sigma = 0.0063 mm, stages = 5`.
pub fn parameters(case: &CaseReport) -> String {
    if case.parameters.is_empty() {
        return NONE.into();
    }
    case.parameters
        .iter()
        .map(|(k, v)| {
            let unit = if k == shard_record::parameters::SIGMA {
                " mm"
            } else {
                ""
            };
            format!("{k} = {}{unit}", plain(v.0))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The Rayleigh law's verdict in a few words.
pub fn verdict(case: &CaseReport) -> String {
    match case.gof.verdict {
        Some(v) => v.to_string(),
        None => none(case.gof.reason.as_deref()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_in_rad_and_arcsec() {
        assert_eq!(rad(9.696273622190944e-5), "9.696e-5");
        assert_eq!(rad(0.0), "0");
        // 20 arcsec is 9.696e-5 rad.
        assert_eq!(arcsec(20.0 / ARCSEC_PER_RAD), "20.00");
        assert_eq!(plain(0.0063), "0.0063");
        assert_eq!(plain(95.0), "95");
        assert_eq!(signed_percent(-0.0123), "−1.2 %");
        assert_eq!(signed_percent(0.0), "+0.0 %");
        assert_eq!(percent(0.6442), "64.4 %");
        for (p, w) in [(95.0, "95th"), (1.0, "1st"), (2.0, "2nd"), (3.0, "3rd")] {
            assert_eq!(ordinal(p), w);
        }
        for (p, w) in [
            (11.0, "11th"),
            (12.0, "12th"),
            (99.9, "99.9th"),
            (50.0, "50th"),
        ] {
            assert_eq!(ordinal(p), w);
        }
    }

    #[test]
    fn figures_show_their_interval_or_their_reason() {
        let f = Figure::new(1e-4, 0.9e-4, 1.1e-4);
        assert_eq!(figure(&f, rad), "1.000e-4 [9.000e-5, 1.100e-4]");
        assert_eq!(figure_interval(&f, arcsec), "[18.56, 22.69]");
        let f = Figure::without_interval(1e-4, "too few samples");
        assert_eq!(figure(&f, rad), "1.000e-4 (too few samples)");
        assert_eq!(figure_interval(&f, rad), "— (too few samples)");
        let f = Figure::null("no converged sample");
        assert_eq!(figure(&f, rad), "— (no converged sample)");
        assert_eq!(figure_value(&f, rad), "— (no converged sample)");
        assert_eq!(figure_interval(&f, rad), NONE);
        // A non-finite value never reaches the text: the report holds it as null.
        let f = Figure::new(f64::NAN, 0.0, f64::INFINITY);
        assert_eq!(figure(&f, rad), "— (not finite)");
    }
}
