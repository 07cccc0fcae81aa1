//! The distributions a job gives to member length errors and joint clearances, and exactly
//! how each turns random words into a number.
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
//! truncated_normal(mean, σ, t) = mean ± min(σ·x, t)          (see [`TruncatedNormal`])
//! ```
//!
//! `ln`, `cos` and `erf` are the pure-Rust `libm` crate's, not the platform's C library
//! (whose results may differ in the last bit between machines and versions), and `√` is
//! exact in IEEE-754: so a draw has the same bits on every machine. That is also why the
//! normal is not `rand_distr::Normal`, whose ziggurat calls the platform's `exp` and `ln` in
//! its tails; our types implement `rand_distr`'s [`Distribution`] trait all the same.
//!
//! ## One home per distribution
//!
//! Each distribution is one type in its own file ([`Normal`], [`Uniform`], [`Constant`],
//! [`TruncatedNormal`]) whose [`Kind`] methods say everything about it: its checks, its
//! draw, its moments and reach, how it is shifted and scaled, whether a tolerance study can
//! scale it to a σ, and its mark in a case's parameters. The list in this file registers
//! each once: the job format's names, [`DistributionSpec`]'s variants and the dispatch all
//! come from it. A new distribution is one more file and one more line here.

mod constant;
mod kind;
mod normal;
mod truncated_normal;
mod uniform;

pub use constant::Constant;
pub use kind::Kind;
pub use normal::{NORMAL_REACH, Normal};
pub use truncated_normal::TruncatedNormal;
pub use uniform::Uniform;

use rand_core::Rng;
use rand_distr::Distribution;
use serde::{Deserialize, Serialize};

/// Registers the distributions: each line a variant of [`DistributionSpec`], its type, and
/// its name in the job format.
macro_rules! distributions {
    ($($(#[$doc:meta])* $variant:ident($ty:ident) = $name:literal,)*) => {
        /// A distribution as a job file writes it: `{"normal": {"sigma": 0.0063}}`,
        /// `{"normal": {"mean": 0.001, "sigma": 0.0063}}`,
        /// `{"uniform": {"low": -0.2, "high": 0.2}}`, `{"constant": {"value": -0.01}}` or
        /// `{"truncated_normal": {"sigma": 0.0063, "limit": 0.0126}}`. Values in mm. Exactly
        /// one kind: an object naming two (`{"normal": {…}, "uniform": {…}}`) is refused,
        /// naming both.
        #[derive(Debug, Clone, Copy, PartialEq, Serialize)]
        pub enum DistributionSpec {
            $($(#[$doc])* #[serde(rename = $name)] $variant($ty),)*
        }

        /// [`DistributionSpec`] as read, before its one kind is checked.
        #[derive(Deserialize)]
        enum Written {
            $(#[serde(rename = $name)] $variant($ty),)*
        }

        impl DistributionSpec {
            /// The names of the kinds in the job format, in the order registered.
            pub const KINDS: &[&str] = &[$($name),*];

            /// What this distribution says about itself.
            pub fn kind(&self) -> &dyn Kind {
                match self {
                    $(DistributionSpec::$variant(d) => d,)*
                }
            }

            /// The distribution of the values plus `shift` \[mm\].
            pub fn shifted(&self, shift: f64) -> DistributionSpec {
                match self {
                    $(DistributionSpec::$variant(d) => d.shifted(shift).into(),)*
                }
            }

            /// The spread about the mean multiplied by `ratio` (see [`Kind::spread_scaled`]).
            pub fn spread_scaled(&self, ratio: f64) -> DistributionSpec {
                match self {
                    $(DistributionSpec::$variant(d) => d.spread_scaled(ratio).into(),)*
                }
            }

            /// The same shape, zero-mean, with standard deviation `sigma` \[mm\] (no error
            /// at all, a normal of σ 0, where the shape has no form without spread), or why
            /// it cannot be scaled (see [`Kind::with_sigma`]).
            pub fn with_sigma(&self, sigma: f64) -> Result<DistributionSpec, String> {
                let none = DistributionSpec::Normal(Normal { mean: 0.0, sigma: 0.0 });
                match self {
                    $(DistributionSpec::$variant(d) => {
                        Ok(d.with_sigma(sigma)?.map_or(none, Into::into))
                    })*
                }
            }

            fn from_written(w: Written) -> Self {
                match w {
                    $(Written::$variant(d) => DistributionSpec::$variant(d),)*
                }
            }
        }

        $(impl From<$ty> for DistributionSpec {
            fn from(d: $ty) -> Self {
                DistributionSpec::$variant(d)
            }
        })*
    };
}

distributions! {
    /// Normal with mean (default 0) and standard deviation σ ≥ 0.
    Normal(Normal) = "normal",
    /// Uniform on [low, high], low ≤ high.
    Uniform(Uniform) = "uniform",
    /// Always the same value.
    Constant(Constant) = "constant",
    /// Normal with mean (default 0) and σ > 0, parts beyond mean ± limit scrapped.
    TruncatedNormal(TruncatedNormal) = "truncated_normal",
}

impl<'de> Deserialize<'de> for DistributionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let value = serde_json::Value::deserialize(d)?;
        if let serde_json::Value::Object(map) = &value
            && map.len() > 1
        {
            let kinds: Vec<&str> = map.keys().map(String::as_str).collect();
            let known: Vec<String> = Self::KINDS
                .iter()
                .map(|k| format!("{{\"{k}\": …}}"))
                .collect();
            return Err(D::Error::custom(format!(
                "one distribution at a time, got {} ({}): give one of {}",
                kinds.len(),
                kinds.join(", "),
                known.join(", ")
            )));
        }
        let written = Written::deserialize(value).map_err(|e| D::Error::custom(e.to_string()))?;
        Ok(Self::from_written(written))
    }
}

impl DistributionSpec {
    /// Checks the parameters; the message says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        self.kind().check()
    }

    /// Mean \[mm\].
    pub fn mean(&self) -> f64 {
        self.kind().mean()
    }

    /// Standard deviation \[mm\].
    pub fn std_dev(&self) -> f64 {
        self.kind().std_dev()
    }

    /// The least value a draw can take \[mm\]: −∞ for a normal with σ > 0.
    pub fn lowest(&self) -> f64 {
        self.kind().lowest()
    }

    /// The greatest value a draw can take \[mm\]: +∞ for a normal with σ > 0.
    pub fn highest(&self) -> f64 {
        self.kind().highest()
    }

    /// The largest magnitude a draw is taken to reach \[mm\] (see [`Kind::reach`]):
    /// `max(|low|, |high|)` for a uniform, the value's for a constant, `|mean| +`
    /// [`NORMAL_REACH`]`·σ` for a normal, `|mean| + limit` for a truncated normal.
    pub fn reach(&self) -> f64 {
        self.kind().reach()
    }

    /// [`DistributionSpec::reach`] in words, for a refusal.
    pub fn reach_in_words(&self) -> String {
        self.kind().reach_in_words()
    }

    /// Its mark in its case's parameters, if any (see [`Kind::series_marker`]).
    pub fn series_marker(&self) -> Option<(&'static str, f64)> {
        self.kind().series_marker()
    }

    /// The value the two words `w1`, `w2` give (see the module doc).
    #[inline]
    pub fn from_words(&self, w1: u64, w2: u64) -> f64 {
        self.kind().draw(w1, w2)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Scaled to σ 0, a shape without a form of no spread (the truncated normal) becomes no
    /// error at all, a normal of σ 0; the others keep their shape.
    #[test]
    fn scaled_to_no_spread() {
        let zero = DistributionSpec::from(Normal {
            mean: 0.0,
            sigma: 0.0,
        });
        let truncated = TruncatedNormal {
            mean: 0.0,
            sigma: 0.01,
            limit: 0.02,
        };
        assert_eq!(DistributionSpec::from(truncated).with_sigma(0.0), Ok(zero));
        let normal = DistributionSpec::from(Normal {
            mean: 0.0,
            sigma: 0.5,
        });
        assert_eq!(normal.with_sigma(0.0), Ok(zero));
        let uniform = DistributionSpec::from(Uniform {
            low: -1.0,
            high: 1.0,
        });
        assert!(matches!(
            uniform.with_sigma(0.0),
            Ok(DistributionSpec::Uniform(_))
        ));
    }
}
