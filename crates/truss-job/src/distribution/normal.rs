//! The normal distribution: `mean + σ·z`, `z` from the Box–Muller transform of the two words.

use super::kind::{Kind, finite, half_open_unit, open_unit};
use serde::{Deserialize, Serialize};

/// How many standard deviations from its mean a normal draw is taken to reach when a job's
/// σ is checked against [`truss_core::MAX_LENGTH_ERROR_FRACTION`]: `|mean| + 6σ` must stay
/// within the bound. A normal draw lies beyond 6σ with probability 2·10⁻⁹, so of the 2.25
/// million draws of a 50,000-sample case of the paper's truss, the odds are about 1 in 200
/// that even one does; a σ that passes keeps its draws in the elastic range.
pub const NORMAL_REACH: f64 = 6.0;

/// Normal with mean (default 0) and standard deviation σ ≥ 0 (σ = 0: always the mean):
/// `{"normal": {"sigma": 0.0063}}`, `{"normal": {"mean": 0.001, "sigma": 0.0063}}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Normal {
    /// Mean \[mm\].
    #[serde(default)]
    pub mean: f64,
    /// Standard deviation \[mm\].
    pub sigma: f64,
}

impl Kind for Normal {
    fn check(&self) -> Result<(), String> {
        finite("mean", self.mean)?;
        finite("sigma", self.sigma)?;
        if self.sigma < 0.0 {
            return Err(format!("sigma must not be negative, got {}", self.sigma));
        }
        Ok(())
    }

    /// `mean + σ·√(−2 ln u₁)·cos(2π u₂)`.
    #[inline]
    fn draw(&self, w1: u64, w2: u64) -> f64 {
        let (u1, u2) = (open_unit(w1), half_open_unit(w2));
        let radius = (-2.0 * libm::log(u1)).sqrt();
        self.mean + self.sigma * radius * libm::cos(2.0 * std::f64::consts::PI * u2)
    }

    fn mean(&self) -> f64 {
        self.mean
    }

    fn std_dev(&self) -> f64 {
        self.sigma
    }

    fn lowest(&self) -> f64 {
        if self.sigma > 0.0 {
            f64::NEG_INFINITY
        } else {
            self.mean
        }
    }

    fn highest(&self) -> f64 {
        if self.sigma > 0.0 {
            f64::INFINITY
        } else {
            self.mean
        }
    }

    /// `|mean| +` [`NORMAL_REACH`]`·σ`.
    fn reach(&self) -> f64 {
        self.mean.abs() + NORMAL_REACH * self.sigma
    }

    fn reach_in_words(&self) -> String {
        format!(
            "mean {} mm, σ {} mm: |mean| + {NORMAL_REACH}σ = {} mm",
            truss_core::readable(self.mean),
            truss_core::readable(self.sigma),
            truss_core::readable(self.reach())
        )
    }

    fn shifted(&self, shift: f64) -> Self {
        Normal {
            mean: self.mean + shift,
            sigma: self.sigma,
        }
    }

    fn spread_scaled(&self, ratio: f64) -> Self {
        Normal {
            mean: self.mean,
            sigma: self.sigma * ratio,
        }
    }

    fn with_sigma(&self, sigma: f64) -> Result<Option<Self>, String> {
        if self.mean != 0.0 {
            return Err(format!(
                "its length error has mean {} mm: a tolerance study needs zero-mean errors",
                self.mean
            ));
        }
        Ok(Some(Normal { mean: 0.0, sigma }))
    }

    fn series_marker(&self) -> Option<(&'static str, f64)> {
        None
    }
}
