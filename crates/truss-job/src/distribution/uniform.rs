//! The uniform distribution: `low + (high − low)·u₂`.

use super::kind::{Kind, finite, half_open_unit};
use serde::{Deserialize, Serialize};

/// Uniform on [low, high], low ≤ high: `{"uniform": {"low": -0.2, "high": 0.2}}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Uniform {
    /// Lower end \[mm\].
    pub low: f64,
    /// Upper end \[mm\].
    pub high: f64,
}

impl Kind for Uniform {
    fn check(&self) -> Result<(), String> {
        finite("low", self.low)?;
        finite("high", self.high)?;
        if self.low > self.high {
            return Err(format!(
                "low ({}) must not exceed high ({})",
                self.low, self.high
            ));
        }
        Ok(())
    }

    /// `low + (high − low)·u₂` (`w1` unused).
    #[inline]
    fn draw(&self, _w1: u64, w2: u64) -> f64 {
        self.low + (self.high - self.low) * half_open_unit(w2)
    }

    fn mean(&self) -> f64 {
        0.5 * (self.low + self.high)
    }

    /// `(high − low)/√12`.
    fn std_dev(&self) -> f64 {
        (self.high - self.low) / 12f64.sqrt()
    }

    fn lowest(&self) -> f64 {
        self.low
    }

    fn highest(&self) -> f64 {
        self.high
    }

    /// `max(|low|, |high|)`.
    fn reach(&self) -> f64 {
        self.low.abs().max(self.high.abs())
    }

    fn reach_in_words(&self) -> String {
        format!("a bound of {} mm", truss_core::readable(self.reach()))
    }

    fn shifted(&self, shift: f64) -> Self {
        Uniform {
            low: self.low + shift,
            high: self.high + shift,
        }
    }

    /// About the midpoint `m`, half-width `h·ratio`: `[m − h·ratio, m + h·ratio]`.
    fn spread_scaled(&self, ratio: f64) -> Self {
        let (m, h) = (
            0.5 * (self.low + self.high),
            0.5 * (self.high - self.low) * ratio,
        );
        Uniform {
            low: m - h,
            high: m + h,
        }
    }

    /// Half-width `√3·σ`.
    fn with_sigma(&self, sigma: f64) -> Result<Option<Self>, String> {
        if self.low != -self.high {
            return Err(format!(
                "its uniform length error on [{}, {}] mm is not centred on 0: a tolerance \
                 study needs zero-mean errors",
                self.low, self.high
            ));
        }
        Ok(Some(Uniform {
            low: -3f64.sqrt() * sigma,
            high: 3f64.sqrt() * sigma,
        }))
    }

    /// `uniform`: 1.
    fn series_marker(&self) -> Option<(&'static str, f64)> {
        Some(("uniform", 1.0))
    }
}
