//! The constant "distribution": every draw the same value (its two words unused).

use super::kind::{Kind, finite};
use serde::{Deserialize, Serialize};

/// Always the same value: `{"constant": {"value": -0.01}}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constant {
    /// The value \[mm\].
    pub value: f64,
}

impl Kind for Constant {
    fn check(&self) -> Result<(), String> {
        finite("value", self.value)
    }

    #[inline]
    fn draw(&self, _w1: u64, _w2: u64) -> f64 {
        self.value
    }

    fn mean(&self) -> f64 {
        self.value
    }

    fn std_dev(&self) -> f64 {
        0.0
    }

    fn lowest(&self) -> f64 {
        self.value
    }

    fn highest(&self) -> f64 {
        self.value
    }

    fn reach(&self) -> f64 {
        self.value.abs()
    }

    fn reach_in_words(&self) -> String {
        format!("a value of {} mm", truss_core::readable(self.reach()))
    }

    fn shifted(&self, shift: f64) -> Self {
        Constant {
            value: self.value + shift,
        }
    }

    /// No spread to scale: the constant itself.
    fn spread_scaled(&self, _ratio: f64) -> Self {
        *self
    }

    fn with_sigma(&self, _sigma: f64) -> Result<Option<Self>, String> {
        Err("its length error is a constant: a tolerance study needs random errors".into())
    }

    fn series_marker(&self) -> Option<(&'static str, f64)> {
        None
    }
}
