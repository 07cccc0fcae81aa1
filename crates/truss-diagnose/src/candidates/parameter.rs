//! One parameter of a candidate effect and its plausible range, with the map onto the unit
//! interval on which the fits work (linear, or logarithmic for a scale).

/// The decimals that show a positive finite `v` to two significant digits (0.0183 → 3,
/// 18.3 → 0, never fewer than 0); `None` for zero, a negative or a non-finite `v`. The
/// reports' sizes and readings round with it.
pub(crate) fn two_digit_decimals(v: f64) -> Option<usize> {
    (v > 0.0 && v.is_finite()).then(|| (1 - v.log10().floor() as i32).max(0) as usize)
}

/// One parameter of a candidate and its plausible range.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Parameter {
    /// Name, as in reports and `--effect NAME:PARAM=VALUE`.
    pub name: String,
    /// Unit.
    pub unit: &'static str,
    /// Lower end of the plausible range.
    pub low: f64,
    /// Upper end of the plausible range.
    pub high: f64,
    /// The value at which the candidate is the baseline.
    pub null: f64,
    /// Whether the fit works on its logarithm (a scale parameter; `low > 0`).
    pub log: bool,
}

impl Parameter {
    /// A parameter on a linear scale.
    pub fn linear(
        name: impl Into<String>,
        unit: &'static str,
        low: f64,
        high: f64,
        null: f64,
    ) -> Self {
        Self {
            name: name.into(),
            unit,
            low,
            high,
            null,
            log: false,
        }
    }

    /// The value at internal coordinate `t ∈ [0, 1]`.
    pub fn value(&self, t: f64) -> f64 {
        if self.log {
            (self.low.ln() + t * (self.high.ln() - self.low.ln())).exp()
        } else {
            self.low + t * (self.high - self.low)
        }
    }

    /// The internal coordinate of `v`.
    pub fn internal(&self, v: f64) -> f64 {
        if self.log {
            (v.ln() - self.low.ln()) / (self.high.ln() - self.low.ln())
        } else {
            (v - self.low) / (self.high - self.low)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_and_linear_parameters_map_the_unit_interval_onto_their_range() {
        let p = Parameter {
            name: "s".into(),
            unit: "mm",
            low: 0.001,
            high: 0.1,
            null: 0.01,
            log: true,
        };
        assert!((p.value(0.5) - 0.01).abs() < 1e-15);
        assert!((p.internal(0.01) - 0.5).abs() < 1e-12);
        let q = Parameter::linear("b", "mm", -0.1, 0.1, 0.0);
        assert!((q.value(0.75) - 0.05).abs() < 1e-15);
    }
}
