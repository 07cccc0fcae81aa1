//! What every distribution says about itself ([`Kind`]), and the two ways a random word
//! becomes a number in the unit interval that the draws share. A leaf below the registry
//! (`mod.rs`) and the distributions' own files, which all read it.

/// Everything a distribution says about itself (lengths in mm).
pub trait Kind {
    /// Checks the parameters as read; the message names the faulty field.
    fn check(&self) -> Result<(), String>;
    /// The value the two words `w1`, `w2` give (see the module doc).
    fn draw(&self, w1: u64, w2: u64) -> f64;
    /// Mean \[mm\].
    fn mean(&self) -> f64;
    /// Standard deviation \[mm\].
    fn std_dev(&self) -> f64;
    /// The least value a draw can take \[mm\] (−∞ if unbounded).
    fn lowest(&self) -> f64;
    /// The greatest value a draw can take \[mm\] (+∞ if unbounded).
    fn highest(&self) -> f64;
    /// The largest magnitude a draw is taken to reach \[mm\], checked against a member's
    /// elastic range ([`truss_core::MAX_LENGTH_ERROR_FRACTION`]).
    fn reach(&self) -> f64;
    /// How [`Kind::reach`] comes about, in words for a refusal
    /// (`mean 0 mm, σ 1 mm: |mean| + 6σ = 6 mm`).
    fn reach_in_words(&self) -> String;
    /// The distribution of the values plus `shift` \[mm\].
    fn shifted(&self, shift: f64) -> Self
    where
        Self: Sized;
    /// The spread about the mean multiplied by `ratio` > 0, the mean kept (so the standard
    /// deviation is multiplied by `ratio`); a distribution without spread stays as it is.
    fn spread_scaled(&self, ratio: f64) -> Self
    where
        Self: Sized;
    /// The same shape, zero-mean, with standard deviation `sigma` ≥ 0 \[mm\], for a
    /// tolerance study, which scales each group's errors `e = σ·z` with `z` fixed by the
    /// sample's stream; `None` where the shape has no form without spread (the registry
    /// then writes no error at all: a normal of mean 0 and σ 0); or why it cannot be scaled
    /// so (not zero-mean, no spread).
    fn with_sigma(&self, sigma: f64) -> Result<Option<Self>, String>
    where
        Self: Sized;
    /// A key and value this distribution puts into its case's parameters (so that cases
    /// differing in it form their own series in the merge's sweeps), if any. Of several
    /// groups with the same key, the case keeps the largest value.
    fn series_marker(&self) -> Option<(&'static str, f64)>;
}

/// `2⁻⁵³`: a word's top 53 bits times this is a uniform number in [0, 1).
pub(super) const SCALE: f64 = 1.0 / (1u64 << 53) as f64;

/// `u₁ = ((w >> 11) + ½)·2⁻⁵³ ∈ (0, 1)`.
#[inline]
pub(super) fn open_unit(w: u64) -> f64 {
    ((w >> 11) as f64 + 0.5) * SCALE
}

/// `u₂ = (w >> 11)·2⁻⁵³ ∈ [0, 1)`.
#[inline]
pub(super) fn half_open_unit(w: u64) -> f64 {
    (w >> 11) as f64 * SCALE
}

/// `Err` naming `name` unless `v` is finite.
pub(super) fn finite(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} is not a finite number"))
    }
}
