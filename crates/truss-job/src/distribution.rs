//! The distributions a job gives to member length errors (and, later, joint clearances),
//! and exactly how each turns random words into a number.
//!
//! Every draw takes exactly two 64-bit words from the sample's stream, whatever the
//! distribution (see [`crate::sampler`] for which words), so that the draws of one member
//! never shift those of another. From the words `w₁, w₂`:
//!
//! ```text
//! u₁ = ((w₁ >> 11) + ½)·2⁻⁵³ ∈ (0, 1)      u₂ = (w₂ >> 11)·2⁻⁵³ ∈ [0, 1)
//! normal(mean, σ)     = mean + σ·√(−2 ln u₁)·cos(2π u₂)      (Box–Muller, cosine branch)
//! uniform(low, high)  = low + (high − low)·u₂
//! constant(value)     = value
//! ```
//!
//! `ln` and `cos` are the pure-Rust `libm` crate's, not the platform's C library (whose
//! results may differ in the last bit between machines and versions), and `√` is exact in
//! IEEE-754: so a draw has the same bits on every machine. That is also why the normal is
//! not `rand_distr::Normal`, whose ziggurat calls the platform's `exp` and `ln` in its
//! tails; our types implement `rand_distr`'s [`Distribution`] trait all the same.

use rand_core::Rng;
use rand_distr::Distribution;
use serde::{Deserialize, Serialize};

/// How many standard deviations from its mean a normal draw is taken to reach when a job's
/// σ is checked against [`truss_core::MAX_LENGTH_ERROR_FRACTION`]: `|mean| + 6σ` must stay
/// within the bound. A normal draw lies beyond 6σ with probability 2·10⁻⁹, so of the 2.25
/// million draws of a 50,000-sample case of the paper's truss, the odds are about 1 in 200
/// that even one does; a σ that passes keeps its draws in the elastic range.
pub const NORMAL_REACH: f64 = 6.0;

/// A distribution as a job file writes it: `{"normal": {"sigma": 0.0063}}`,
/// `{"normal": {"mean": 0.001, "sigma": 0.0063}}`, `{"uniform": {"low": -0.2, "high": 0.2}}`
/// or `{"constant": {"value": -0.01}}`. Values in mm. Exactly one kind: an object naming two
/// (`{"normal": {…}, "uniform": {…}}`) is refused, naming both.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DistributionSpec {
    /// Normal with mean (default 0) and standard deviation σ ≥ 0.
    Normal {
        /// Mean \[mm\].
        #[serde(default)]
        mean: f64,
        /// Standard deviation \[mm\].
        sigma: f64,
    },
    /// Uniform on [low, high], low ≤ high.
    Uniform {
        /// Lower end \[mm\].
        low: f64,
        /// Upper end \[mm\].
        high: f64,
    },
    /// Always the same value.
    Constant {
        /// The value \[mm\].
        value: f64,
    },
}

/// [`DistributionSpec`] as read, before its one kind is checked.
#[derive(Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum Written {
    Normal {
        #[serde(default)]
        mean: f64,
        sigma: f64,
    },
    Uniform {
        low: f64,
        high: f64,
    },
    Constant {
        value: f64,
    },
}

impl<'de> Deserialize<'de> for DistributionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let value = serde_json::Value::deserialize(d)?;
        if let serde_json::Value::Object(map) = &value
            && map.len() > 1
        {
            let kinds: Vec<&str> = map.keys().map(String::as_str).collect();
            return Err(D::Error::custom(format!(
                "one distribution at a time, got {} ({}): give one of \
                 {{\"normal\": …}}, {{\"uniform\": …}}, {{\"constant\": …}}",
                kinds.len(),
                kinds.join(", ")
            )));
        }
        Ok(
            match Written::deserialize(value).map_err(|e| D::Error::custom(e.to_string()))? {
                Written::Normal { mean, sigma } => DistributionSpec::Normal { mean, sigma },
                Written::Uniform { low, high } => DistributionSpec::Uniform { low, high },
                Written::Constant { value } => DistributionSpec::Constant { value },
            },
        )
    }
}

impl DistributionSpec {
    /// Checks the parameters; the message says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(format!("{name} is not a finite number"))
            }
        };
        match *self {
            DistributionSpec::Normal { mean, sigma } => {
                finite("mean", mean)?;
                finite("sigma", sigma)?;
                if sigma < 0.0 {
                    return Err(format!("sigma must not be negative, got {sigma}"));
                }
            }
            DistributionSpec::Uniform { low, high } => {
                finite("low", low)?;
                finite("high", high)?;
                if low > high {
                    return Err(format!("low ({low}) must not exceed high ({high})"));
                }
            }
            DistributionSpec::Constant { value } => finite("value", value)?,
        }
        Ok(())
    }

    /// Mean \[mm\].
    pub fn mean(&self) -> f64 {
        match *self {
            DistributionSpec::Normal { mean, .. } => mean,
            DistributionSpec::Uniform { low, high } => 0.5 * (low + high),
            DistributionSpec::Constant { value } => value,
        }
    }

    /// Standard deviation \[mm\].
    pub fn std_dev(&self) -> f64 {
        match *self {
            DistributionSpec::Normal { sigma, .. } => sigma,
            DistributionSpec::Uniform { low, high } => (high - low) / 12f64.sqrt(),
            DistributionSpec::Constant { .. } => 0.0,
        }
    }

    /// The least value a draw can take \[mm\]: −∞ for a normal with σ > 0.
    pub fn lowest(&self) -> f64 {
        match *self {
            DistributionSpec::Normal { sigma, .. } if sigma > 0.0 => f64::NEG_INFINITY,
            DistributionSpec::Normal { mean, .. } => mean,
            DistributionSpec::Uniform { low, .. } => low,
            DistributionSpec::Constant { value } => value,
        }
    }

    /// The greatest value a draw can take \[mm\]: +∞ for a normal with σ > 0.
    pub fn highest(&self) -> f64 {
        match *self {
            DistributionSpec::Normal { sigma, .. } if sigma > 0.0 => f64::INFINITY,
            DistributionSpec::Normal { mean, .. } => mean,
            DistributionSpec::Uniform { high, .. } => high,
            DistributionSpec::Constant { value } => value,
        }
    }

    /// The largest magnitude a draw reaches \[mm\]: `max(|low|, |high|)` for a uniform, the
    /// value's for a constant, `|mean| +` [`NORMAL_REACH`]`·σ` for a normal.
    pub fn reach(&self) -> f64 {
        match *self {
            DistributionSpec::Normal { mean, sigma } => mean.abs() + NORMAL_REACH * sigma,
            DistributionSpec::Uniform { low, high } => low.abs().max(high.abs()),
            DistributionSpec::Constant { value } => value.abs(),
        }
    }

    /// The value the two words `w1`, `w2` give (see the module doc).
    #[inline]
    pub fn from_words(&self, w1: u64, w2: u64) -> f64 {
        const SCALE: f64 = 1.0 / (1u64 << 53) as f64;
        match *self {
            DistributionSpec::Normal { mean, sigma } => {
                let u1 = ((w1 >> 11) as f64 + 0.5) * SCALE;
                let u2 = (w2 >> 11) as f64 * SCALE;
                let radius = (-2.0 * libm::log(u1)).sqrt();
                mean + sigma * radius * libm::cos(2.0 * std::f64::consts::PI * u2)
            }
            DistributionSpec::Uniform { low, high } => {
                let _ = w1;
                low + (high - low) * ((w2 >> 11) as f64 * SCALE)
            }
            DistributionSpec::Constant { value } => value,
        }
    }
}

impl Distribution<f64> for DistributionSpec {
    /// Draws one value, taking exactly two words from `rng`.
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let w1 = rng.next_u64();
        let w2 = rng.next_u64();
        self.from_words(w1, w2)
    }
}
