//! A job's alignment budget: the percentile each measured quantity must stay within, as an
//! optical engineer writes it ("tilt ≤ 20″, decenter ≤ 50 µm, despace ≤ 30 µm at 95 %").
//!
//! ## Format
//!
//! ```json
//! "budget": {"theta_p": {"arcsec": 20}, "decenter": {"mm": 0.05}, "despace": {"mm": 0.03},
//!            "percentile": 95}
//! ```
//!
//! | line | limit on | units |
//! |---|---|---|
//! | `theta_p` | θ_P's percentile | `{"arcsec": a}` or `{"rad": r}` |
//! | `decenter` | decenter's percentile (the top centroid's shift in the bottom plane) | `{"mm": d}` or `{"um": d}` |
//! | `despace` | the percentile of \|despace\| (the shift along the bottom's normal, either way) | `{"mm": d}` or `{"um": d}` |
//! | `percentile` | the percentile every line is read at, in %; default 95 | |
//!
//! At least one line. A limit must be a finite positive number (θ_P's below 90°); an unknown
//! quantity, an unknown unit, or two units for one line are refused, each naming its JSON
//! path (`budget.decenter.mm: the limit must be a positive number of mm, got -0.05`).
//! The budget is part of the job (its canonical form, so its id): it travels to the merge
//! in the shards' begin lines, and `truss tolerance` allocates against it. Canonically it is
//! held in rad and mm ([`Budget`]), with 1″ = π/648000 rad and 1 µm = 10⁻³ mm.

use crate::errors::JobError;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The quantities a budget may name, in the order the reports list them.
pub const QUANTITIES: [&str; 3] = ["theta_p", "decenter", "despace"];

/// The default percentile of a budget, in %.
pub const DEFAULT_PERCENTILE: f64 = 95.0;

/// A budget line's limit as written: a number in a unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Limit {
    /// Arcseconds (θ_P).
    Arcsec(f64),
    /// Radians (θ_P).
    Rad(f64),
    /// Millimetres (decenter, despace).
    Mm(f64),
    /// Micrometres (decenter, despace).
    Um(f64),
}

impl Limit {
    /// The limit in the canonical unit: rad for an angle, mm for a length.
    pub fn canonical(self) -> f64 {
        match self {
            Limit::Arcsec(a) => a * std::f64::consts::PI / 648_000.0,
            Limit::Rad(r) | Limit::Mm(r) => r,
            Limit::Um(u) => u * 1e-3,
        }
    }

    fn value(self) -> f64 {
        match self {
            Limit::Arcsec(v) | Limit::Rad(v) | Limit::Mm(v) | Limit::Um(v) => v,
        }
    }
}

/// A budget as a job file writes it (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BudgetSpec {
    /// θ_P's line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_p: Option<Limit>,
    /// Decenter's line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decenter: Option<Limit>,
    /// |despace|'s line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub despace: Option<Limit>,
    /// The percentile, in %.
    pub percentile: f64,
}

/// A validated budget in canonical units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Budget {
    /// The percentile every line is read at, in %.
    pub percentile: f64,
    /// θ_P's limit \[rad\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_p: Option<f64>,
    /// Decenter's limit \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decenter: Option<f64>,
    /// The limit of |despace| \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub despace: Option<f64>,
}

impl Budget {
    /// The lines in the order of [`QUANTITIES`]: (quantity, limit in rad or mm).
    pub fn lines(&self) -> Vec<(&'static str, f64)> {
        QUANTITIES
            .iter()
            .zip([self.theta_p, self.decenter, self.despace])
            .filter_map(|(q, l)| Some((*q, l?)))
            .collect()
    }
}

impl BudgetSpec {
    /// Parses a budget as written, naming faults by their JSON path under `at`.
    pub fn parse(value: &Value, at: &str) -> Result<Self, JobError> {
        let Value::Object(map) = value else {
            return Err(JobError::at(
                at,
                "expected an object of lines, e.g. {\"theta_p\": {\"arcsec\": 20}, \
                 \"decenter\": {\"mm\": 0.05}, \"despace\": {\"mm\": 0.03}, \"percentile\": 95}",
            ));
        };
        let mut spec = BudgetSpec {
            theta_p: None,
            decenter: None,
            despace: None,
            percentile: DEFAULT_PERCENTILE,
        };
        for (key, v) in map {
            let path = format!("{at}.{key}");
            match key.as_str() {
                "percentile" => {
                    spec.percentile =
                        v.as_f64()
                            .filter(|p| *p > 0.0 && *p < 100.0)
                            .ok_or_else(|| {
                                JobError::at(
                                    &path,
                                    &format!(
                                        "must be a percentage strictly between 0 and 100, got {v}"
                                    ),
                                )
                            })?;
                }
                "theta_p" => spec.theta_p = Some(limit(v, &path, &["arcsec", "rad"])?),
                "decenter" => spec.decenter = Some(limit(v, &path, &["mm", "um"])?),
                "despace" => spec.despace = Some(limit(v, &path, &["mm", "um"])?),
                other => {
                    return Err(JobError::at(
                        &path,
                        &format!(
                            "unknown quantity {other:?}: a budget's lines are {} (and \
                             \"percentile\")",
                            QUANTITIES.join(", ")
                        ),
                    ));
                }
            }
        }
        let budget = spec.budget();
        if budget.lines().is_empty() {
            return Err(JobError::at(
                at,
                &format!(
                    "a budget needs at least one line of {}",
                    QUANTITIES.join(", ")
                ),
            ));
        }
        if let Some(t) = budget.theta_p.filter(|t| *t >= std::f64::consts::FRAC_PI_2) {
            return Err(JobError::at(
                &format!("{at}.theta_p"),
                &format!("the limit is {t} rad, not an angle below 90°"),
            ));
        }
        Ok(spec)
    }

    /// The budget in canonical units.
    pub fn budget(&self) -> Budget {
        Budget {
            percentile: self.percentile,
            theta_p: self.theta_p.map(Limit::canonical),
            decenter: self.decenter.map(Limit::canonical),
            despace: self.despace.map(Limit::canonical),
        }
    }
}

/// One line's limit `{"unit": value}` with a unit among `units`.
fn limit(v: &Value, path: &str, units: &[&str]) -> Result<Limit, JobError> {
    let expected = || {
        units
            .iter()
            .map(|u| format!("{{\"{u}\": …}}"))
            .collect::<Vec<_>>()
            .join(" or ")
    };
    let map: &Map<String, Value> = v.as_object().filter(|m| m.len() == 1).ok_or_else(|| {
        JobError::at(
            path,
            &format!("expected one limit with its unit, {}", expected()),
        )
    })?;
    let (unit, number) = map.iter().next().expect("one entry");
    let at = format!("{path}.{unit}");
    if !units.contains(&unit.as_str()) {
        return Err(JobError::at(
            &at,
            &format!("unknown unit {unit:?}: give {}", expected()),
        ));
    }
    let value = number
        .as_f64()
        .filter(|x| x.is_finite() && *x > 0.0)
        .ok_or_else(|| {
            JobError::at(
                &at,
                &format!("the limit must be a positive number of {unit}, got {number}"),
            )
        })?;
    let written: Limit = serde_json::from_value(serde_json::json!({ unit: value }))
        .expect("a known unit with a number");
    debug_assert_eq!(written.value(), value);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<BudgetSpec, String> {
        let v: Value = serde_json::from_str(text).unwrap();
        BudgetSpec::parse(&v, "budget").map_err(|e| e.to_string())
    }

    /// The issue's three-line budget in canonical units: 20″ = 20π/648000 rad.
    #[test]
    fn the_three_line_budget_in_canonical_units() {
        let b = parse(
            r#"{"theta_p": {"arcsec": 20}, "decenter": {"mm": 0.05}, "despace": {"um": 30},
                "percentile": 95}"#,
        )
        .unwrap()
        .budget();
        assert_eq!(b.theta_p, Some(20.0 * std::f64::consts::PI / 648_000.0));
        assert!((b.theta_p.unwrap() - 9.696_273_6e-5).abs() < 1e-12);
        assert_eq!(b.decenter, Some(0.05));
        assert!((b.despace.unwrap() - 0.03).abs() < 1e-17);
        assert_eq!(b.lines().len(), 3);
        let one = parse(r#"{"decenter": {"mm": 0.05}}"#).unwrap();
        assert_eq!(one.percentile, 95.0);
        assert_eq!(one.budget().lines(), vec![("decenter", 0.05)]);
    }

    /// Every bad line is refused naming its JSON path.
    #[test]
    fn bad_budgets_are_refused_by_path() {
        for (text, said) in [
            (
                r#"{"decenter": {"mm": -0.05}}"#,
                "budget.decenter.mm: the limit must be a positive",
            ),
            (
                r#"{"decenter": {"mm": 0}}"#,
                "budget.decenter.mm: the limit must be a positive",
            ),
            (
                r#"{"despace": {"mm": "x"}}"#,
                "budget.despace.mm: the limit must be a positive",
            ),
            (
                r#"{"theta_p": {"arcsec": -20}}"#,
                "budget.theta_p.arcsec: the limit must be",
            ),
            (
                r#"{"theta_p": {"rad": 2}}"#,
                "budget.theta_p: the limit is 2 rad, not an angle",
            ),
            (
                r#"{"tilt": {"arcsec": 20}}"#,
                "budget.tilt: unknown quantity \"tilt\"",
            ),
            (
                r#"{"theta_p": {"deg": 1}}"#,
                "budget.theta_p.deg: unknown unit \"deg\"",
            ),
            (
                r#"{"decenter": {"mm": 1, "um": 2}}"#,
                "budget.decenter: expected one limit",
            ),
            (
                r#"{"percentile": 100, "decenter": {"mm": 1}}"#,
                "budget.percentile: must be",
            ),
            (
                r#"{"percentile": 95}"#,
                "budget: a budget needs at least one line",
            ),
            (r#"[1]"#, "budget: expected an object"),
        ] {
            let m = parse(text).unwrap_err();
            assert!(m.starts_with(said), "{text}: {m}");
        }
    }
}
