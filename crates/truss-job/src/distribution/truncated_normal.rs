//! The truncated normal: a normal length error whose parts beyond the tolerance `mean ± t`
//! are scrapped at inspection, so the parts built in lie within it. With the default mean 0
//! that is the drawing's tolerance ±t.
//!
//! ## Draw
//!
//! With `a = t/σ` the limit in standard deviations, `A = ½·erf(a/√2)` the normal's mass
//! between 0 and `a`, and `T = ½·erfc(a/√2)` its mass beyond `a`, the words `w₁, w₂` give
//!
//! ```text
//! m = w₁ >> 11                         (53 bits)
//! h = (m + ½)·2⁻⁵³ · A                 the mass between 0 and the draw's |z|
//! τ = T + ((2⁵³ − m) − ½)·2⁻⁵³ · A     the mass beyond it, ½ − h without cancellation
//! x = Φ⁻¹(½ + h)                       (Wichura's AS 241: from h in its central region, from τ in the tails)
//! value = mean + min(σ·x, t)  if w₂ < 2⁶³,   mean − min(σ·x, t)  otherwise
//! ```
//!
//! so `|z| = x` is uniform in probability over [0, a] (the inverse of its distribution
//! function, exact to the last few bits, where rejection sampling would take a variable
//! number of words), and the sign is the top bit of `w₂`. Every step is IEEE-754 arithmetic
//! in a fixed order, `√`, and the pure-Rust `libm`'s `ln`, `erf` and `erfc`, so a draw has
//! the same bits on every machine. A draw is `mean ± σ·x(a, w₁)`: scaling σ and t together
//! scales every draw about the mean, which is how a tolerance study scales it.
//!
//! ## Moments
//!
//! Symmetric about its mean, so the mean is `mean`; the variance is
//!
//! ```text
//! Var = σ²·(1 − 2a·φ(a)/erf(a/√2)),   φ(a) = e^(−a²/2)/√(2π)
//! ```
//!
//! (`E[Z² | |Z| < a]` by parts), computed for `a < 1`, where the difference cancels, from
//! the series `a²·Σ c_k/(2k + 3) / Σ c_k/(2k + 1)`, `c_k = (−a²/2)^k/k!`. It tends to σ²
//! for a large limit and to the uniform's t²/3 for a small one.

use super::kind::{Kind, SCALE, finite};
use serde::{Deserialize, Serialize};

/// Normal with mean (default 0) and σ > 0, truncated to `mean ± limit` (limit > 0):
/// `{"truncated_normal": {"sigma": 0.0063, "limit": 0.0126}}`. σ is the untruncated normal's;
/// the distribution's own standard deviation is smaller ([`Kind::std_dev`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruncatedNormal {
    /// Mean \[mm\], the centre of the tolerance.
    #[serde(default)]
    pub mean: f64,
    /// Standard deviation of the normal before truncation \[mm\].
    pub sigma: f64,
    /// Half-width of the tolerance: parts beyond `mean ± limit` are scrapped \[mm\].
    pub limit: f64,
}

impl TruncatedNormal {
    /// The limit in standard deviations, `a = limit/σ`.
    pub fn limit_in_sigmas(&self) -> f64 {
        self.limit / self.sigma
    }
}

impl Kind for TruncatedNormal {
    fn check(&self) -> Result<(), String> {
        finite("mean", self.mean)?;
        finite("sigma", self.sigma)?;
        finite("limit", self.limit)?;
        if self.sigma <= 0.0 {
            return Err(format!(
                "sigma must be positive, got {} (a truncated normal with σ = 0 has no shape: \
                 give {{\"constant\": …}})",
                self.sigma
            ));
        }
        if self.limit <= 0.0 {
            return Err(format!(
                "limit must be positive, got {} (the tolerance is mean ± limit)",
                self.limit
            ));
        }
        if !self.limit_in_sigmas().is_finite() {
            return Err(format!(
                "sigma {} mm is too small beside limit {} mm: limit/sigma is beyond the \
                 largest number (give a larger sigma; beyond 40 σ the cut changes nothing)",
                truss_core::readable(self.sigma),
                truss_core::readable(self.limit)
            ));
        }
        Ok(())
    }

    /// See the module doc.
    fn draw(&self, w1: u64, w2: u64) -> f64 {
        let a = self.limit_in_sigmas();
        let z = a * std::f64::consts::FRAC_1_SQRT_2;
        let (inside, beyond) = (0.5 * libm::erf(z), 0.5 * libm::erfc(z));
        let m = w1 >> 11;
        let h = (m as f64 + 0.5) * SCALE * inside;
        let tail = beyond + (((1u64 << 53) - m) as f64 - 0.5) * SCALE * inside;
        let magnitude = (self.sigma * positive_quantile(h, tail)).min(self.limit);
        if w2 >> 63 == 0 {
            self.mean + magnitude
        } else {
            self.mean - magnitude
        }
    }

    fn mean(&self) -> f64 {
        self.mean
    }

    /// `σ·√(1 − 2a·φ(a)/erf(a/√2))` (module doc); for a limit so far inside σ that `a²`
    /// underflows (σ = 1e200 mm, limit 0.01 mm), `t·√(Σ c_k/(2k + 3) / Σ c_k/(2k + 1))`, the
    /// same series without its factor `a²` (→ t/√3, the uniform's), never 0.
    fn std_dev(&self) -> f64 {
        let a = self.limit_in_sigmas();
        let variance = truncated_variance(a);
        if variance >= f64::MIN_POSITIVE {
            self.sigma * variance.sqrt()
        } else {
            self.limit * series_ratio(a).sqrt()
        }
    }

    fn lowest(&self) -> f64 {
        self.mean - self.limit
    }

    fn highest(&self) -> f64 {
        self.mean + self.limit
    }

    /// `|mean| + limit`: no draw goes further.
    fn reach(&self) -> f64 {
        self.mean.abs() + self.limit
    }

    fn reach_in_words(&self) -> String {
        format!(
            "mean {} mm, limit {} mm: |mean| + limit = {} mm",
            truss_core::readable(self.mean),
            truss_core::readable(self.limit),
            truss_core::readable(self.reach())
        )
    }

    fn shifted(&self, shift: f64) -> Self {
        TruncatedNormal {
            mean: self.mean + shift,
            ..*self
        }
    }

    /// σ and the limit multiplied by `ratio` (the shape `a` kept).
    fn spread_scaled(&self, ratio: f64) -> Self {
        TruncatedNormal {
            mean: self.mean,
            sigma: self.sigma * ratio,
            limit: self.limit * ratio,
        }
    }

    /// σ and the limit scaled together, the limit in proportion (the shape `a` kept); at
    /// σ = 0 every part is exact: no form of this shape (`None`, no error at all).
    fn with_sigma(&self, sigma: f64) -> Result<Option<Self>, String> {
        if self.mean != 0.0 {
            return Err(format!(
                "its length error has mean {} mm: a tolerance study needs zero-mean errors",
                self.mean
            ));
        }
        if sigma == 0.0 {
            return Ok(None);
        }
        let ratio = sigma / self.std_dev();
        Ok(Some(TruncatedNormal {
            mean: 0.0,
            sigma: self.sigma * ratio,
            limit: self.limit * ratio,
        }))
    }

    /// `truncated_normal`: the limit in standard deviations `a = limit/σ`, so that cases
    /// of the same shape form one σ-series.
    fn series_marker(&self) -> Option<(&'static str, f64)> {
        Some(("truncated_normal", self.limit_in_sigmas()))
    }
}

/// `E[Z² | |Z| < a]` for a standard normal `Z`: `1 − 2a·φ(a)/erf(a/√2)`, from its series
/// below `a = 1` (module doc).
pub(crate) fn truncated_variance(a: f64) -> f64 {
    if a < 1.0 {
        a * a * series_ratio(a)
    } else if a > 40.0 {
        // a·φ(a) < 10⁻³⁴⁰: nothing of the normal is cut off.
        1.0
    } else {
        let density = libm::exp(-0.5 * a * a) / (2.0 * std::f64::consts::PI).sqrt();
        1.0 - 2.0 * a * density / libm::erf(a * std::f64::consts::FRAC_1_SQRT_2)
    }
}

/// `Σ c_k/(2k + 3) / Σ c_k/(2k + 1)`, `c_k = (−a²/2)^k/k!`, for `a < 1`: the truncated
/// variance over `a²` (module doc).
fn series_ratio(a: f64) -> f64 {
    let c = -0.5 * a * a;
    let (mut term, mut inner, mut outer) = (1.0, 0.0, 0.0);
    for k in 0..30 {
        let k = k as f64;
        inner += term / (2.0 * k + 1.0);
        outer += term / (2.0 * k + 3.0);
        term *= c / (k + 1.0);
    }
    outer / inner
}

/// `x = Φ⁻¹(½ + h) ≥ 0` given both `h` and `tail = ½ − h` (each exact in its own range):
/// Wichura's algorithm AS 241 (Applied Statistics 37, 477–484, 1988), relative error about
/// 10⁻¹⁶.
fn positive_quantile(h: f64, tail: f64) -> f64 {
    if h <= 0.425 {
        let r = 0.180625 - h * h;
        h * horner(&as241::CENTRAL_NUMERATOR, r) / horner(&as241::CENTRAL_DENOMINATOR, r)
    } else {
        let r = (-libm::log(tail)).sqrt();
        if r <= 5.0 {
            let r = r - 1.6;
            horner(&as241::NEAR_NUMERATOR, r) / horner(&as241::NEAR_DENOMINATOR, r)
        } else {
            let r = r - 5.0;
            horner(&as241::FAR_NUMERATOR, r) / horner(&as241::FAR_DENOMINATOR, r)
        }
    }
}

/// `c₀ + c₁x + … + c₇x⁷` by Horner's rule, highest power first.
fn horner(c: &[f64; 8], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

/// AS 241's coefficients as published (20 significant digits, each rounded to the nearest
/// double by the compiler), constant term first.
#[allow(clippy::excessive_precision)]
mod as241 {
    pub(super) const CENTRAL_NUMERATOR: [f64; 8] = [
        3.387_132_872_796_366_608,
        1.331_416_678_917_843_774_5e2,
        1.971_590_950_306_551_442_7e3,
        1.373_169_376_550_946_112_5e4,
        4.592_195_393_154_987_145_7e4,
        6.726_577_092_700_870_085_3e4,
        3.343_057_558_358_812_810_5e4,
        2.509_080_928_730_122_672_7e3,
    ];
    pub(super) const CENTRAL_DENOMINATOR: [f64; 8] = [
        1.0,
        4.231_333_070_160_091_125_2e1,
        6.871_870_074_920_579_083e2,
        5.394_196_021_424_751_107_7e3,
        2.121_379_430_158_659_586_7e4,
        3.930_789_580_009_271_061e4,
        2.872_908_573_572_194_267_4e4,
        5.226_495_278_852_854_561e3,
    ];
    pub(super) const NEAR_NUMERATOR: [f64; 8] = [
        1.423_437_110_749_683_577_34,
        4.630_337_846_156_545_295_9,
        5.769_497_221_460_691_405_5,
        3.647_848_324_763_204_605_04,
        1.270_458_252_452_368_382_58,
        2.417_807_251_774_506_117_7e-1,
        2.272_384_498_926_918_458_33e-2,
        7.745_450_142_783_414_076_4e-4,
    ];
    pub(super) const NEAR_DENOMINATOR: [f64; 8] = [
        1.0,
        2.053_191_626_637_758_821_87,
        1.676_384_830_183_803_849_4,
        6.897_673_349_851_000_045_5e-1,
        1.481_039_764_274_800_745_9e-1,
        1.519_866_656_361_645_719_66e-2,
        5.475_938_084_995_344_946e-4,
        1.050_750_071_644_416_843_24e-9,
    ];
    pub(super) const FAR_NUMERATOR: [f64; 8] = [
        6.657_904_643_501_103_777_2,
        5.463_784_911_164_114_369_9,
        1.784_826_539_917_291_335_8,
        2.965_605_718_285_048_912_3e-1,
        2.653_218_952_657_612_309_3e-2,
        1.242_660_947_388_078_438_6e-3,
        2.711_555_568_743_487_578_15e-5,
        2.010_334_399_292_288_132_65e-7,
    ];
    pub(super) const FAR_DENOMINATOR: [f64; 8] = [
        1.0,
        5.998_322_065_558_879_376_9e-1,
        1.369_298_809_227_358_053_1e-1,
        1.487_536_129_085_061_485_25e-2,
        7.868_691_311_456_132_591e-4,
        1.846_318_317_510_054_681_8e-5,
        1.421_511_758_316_445_888_7e-7,
        2.044_263_103_389_939_785_64e-15,
    ];
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_chacha::ChaCha20Rng;
    use rand_core::{Rng, SeedableRng};

    /// Φ(x) − ½ for x ≥ 0, from libm's erf (an independent route to the quantile's inverse).
    fn above_half(x: f64) -> f64 {
        0.5 * libm::erf(x * std::f64::consts::FRAC_1_SQRT_2)
    }

    /// The quantile inverts libm's normal distribution function to about 10⁻¹⁴ relative, in
    /// the centre and in the tails out to a mass of 10⁻³⁰⁰ (each of AS 241's three regions).
    #[test]
    fn the_quantile_inverts_the_distribution_function() {
        for h in [1e-300, 1e-12, 0.01, 0.2, 0.3, 0.42, 0.425] {
            let x = positive_quantile(h, 0.5 - h);
            assert!((above_half(x) - h).abs() <= 1e-14 * h, "{h}: {x}");
        }
        for tail in [0.07, 1e-3, 1e-8, 1e-11, 1e-20, 1e-100, 1e-300] {
            let x = positive_quantile(0.5 - tail, tail);
            let got = 0.5 * libm::erfc(x * std::f64::consts::FRAC_1_SQRT_2);
            // ln(tail) moves by x·δx: a relative error ε of x is one of x²·ε in the tail.
            let allowed = 1e-14 * (x * x).max(1.0);
            assert!(
                ((got - tail) / tail).abs() < allowed,
                "{tail}: {x} gives {got}"
            );
        }
    }

    /// The variance's series and closed form agree where they meet, and tend to the
    /// uniform's t²/3 and the normal's σ²; a midpoint quadrature of E[Z² | |Z| < a] agrees.
    #[test]
    fn the_variance_is_exact() {
        let closed = |a: f64| {
            let density = libm::exp(-0.5 * a * a) / (2.0 * std::f64::consts::PI).sqrt();
            1.0 - 2.0 * a * density / libm::erf(a * std::f64::consts::FRAC_1_SQRT_2)
        };
        let seam = 1.0 - 1e-12;
        assert!((truncated_variance(seam) - closed(seam)).abs() < 1e-14);
        for a in [1e-6, 1e-3] {
            let v = truncated_variance(a);
            assert!(
                ((v - a * a / 3.0) / (a * a / 3.0)).abs() < a * a,
                "{a}: {v}"
            );
        }
        assert_eq!(truncated_variance(50.0), 1.0);
        assert!((truncated_variance(8.0) - 1.0).abs() < 1e-13);
        for a in [0.3, 0.9, 1.5, 2.0, 3.0, 5.0] {
            let n = 200_000;
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                let z = (i as f64 + 0.5) * a / n as f64;
                let w = libm::exp(-0.5 * z * z);
                num += z * z * w;
                den += w;
            }
            let v = truncated_variance(a);
            assert!(
                ((num / den - v) / v).abs() < 1e-9,
                "{a}: {} vs {v}",
                num / den
            );
        }
    }

    /// 200,000 draws from the sample streams: all within mean ± t, mean and variance the
    /// exact ones within 4 standard errors, and the fractions below five points the
    /// truncated distribution function's.
    #[test]
    fn draws_have_the_exact_moments() {
        for (mean, sigma, limit) in [(0.0, 0.01, 0.02), (0.3, 2.0, 1.0), (-0.1, 0.5, 3.0)] {
            let d = TruncatedNormal { mean, sigma, limit };
            d.check().unwrap();
            let mut rng = ChaCha20Rng::seed_from_u64(11);
            let n = 200_000;
            let xs: Vec<f64> = (0..n)
                .map(|_| {
                    let (w1, w2) = (rng.next_u64(), rng.next_u64());
                    d.draw(w1, w2)
                })
                .collect();
            assert!(xs.iter().all(|x| (mean - limit..=mean + limit).contains(x)));
            let nf = n as f64;
            let m = xs.iter().sum::<f64>() / nf;
            let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / nf;
            let fourth = xs.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / nf;
            let exact = d.std_dev().powi(2);
            assert!(
                (m - mean).abs() < 4.0 * (exact / nf).sqrt(),
                "{d:?}: mean {m}"
            );
            let se = ((fourth - exact * exact) / nf).sqrt();
            assert!(
                (var - exact).abs() < 4.0 * se,
                "{d:?}: var {var} vs {exact}"
            );
            let a = limit / sigma;
            let mass = 2.0 * above_half(a);
            for x in [-0.9, -0.4, 0.0, 0.25, 0.8] {
                let at = mean + x * limit;
                let p = (above_half(x * a) + 0.5 * mass) / mass;
                let f = xs.iter().filter(|&&v| v < at).count() as f64 / nf;
                assert!(
                    (f - p).abs() < 4.0 * (p * (1.0 - p) / nf).sqrt(),
                    "{x}: {f} vs {p}"
                );
            }
        }
    }

    /// Scaling σ and the limit together scales every draw about the mean; `with_sigma`
    /// reaches the σ asked for and keeps the shape.
    #[test]
    fn scaling_keeps_the_draws_and_the_shape() {
        let d = TruncatedNormal {
            mean: 0.0,
            sigma: 0.01,
            limit: 0.02,
        };
        let s = d
            .with_sigma(0.003)
            .unwrap()
            .expect("a truncated normal scales to one");
        assert_eq!(d.with_sigma(0.0), Ok(None), "σ 0: no truncated normal");
        assert!((s.std_dev() - 0.003).abs() < 1e-15);
        assert!((s.limit_in_sigmas() - 2.0).abs() < 1e-14);
        let r = s.sigma / d.sigma;
        for (w1, w2) in [
            (1u64, 2u64),
            (u64::MAX, 0),
            (0x1234_5678_9abc_def0, u64::MAX),
        ] {
            let (x, y) = (d.draw(w1, w2), s.draw(w1, w2));
            assert!((y - r * x).abs() <= 1e-15 * x.abs().max(1e-300), "{x} {y}");
        }
        assert!(
            TruncatedNormal { mean: 0.1, ..d }
                .with_sigma(0.1)
                .unwrap_err()
                .contains("zero-mean")
        );
    }

    /// σ ≤ 0, a limit ≤ 0 and non-finite values are refused, naming the field.
    #[test]
    fn bad_parameters_are_refused() {
        let ok = TruncatedNormal {
            mean: 0.0,
            sigma: 0.01,
            limit: 0.02,
        };
        for (bad, field) in [
            (
                TruncatedNormal { sigma: 0.0, ..ok },
                "sigma must be positive",
            ),
            (
                TruncatedNormal { sigma: -1.0, ..ok },
                "sigma must be positive",
            ),
            (
                TruncatedNormal { limit: 0.0, ..ok },
                "limit must be positive",
            ),
            (
                TruncatedNormal {
                    limit: f64::INFINITY,
                    ..ok
                },
                "limit is not a finite",
            ),
            (
                TruncatedNormal {
                    mean: f64::NAN,
                    ..ok
                },
                "mean is not a finite",
            ),
            (
                TruncatedNormal {
                    sigma: f64::NAN,
                    ..ok
                },
                "sigma is not a finite",
            ),
            (
                TruncatedNormal {
                    sigma: 5e-324,
                    ..ok
                },
                "sigma 5e-324 mm is too small",
            ),
        ] {
            let m = bad.check().unwrap_err();
            assert!(m.starts_with(field), "{bad:?}: {m}");
        }
    }

    /// σ = 1e200 mm cut at 0.01 mm is a uniform of ±0.01 mm in all but name: its standard
    /// deviation is t/√3, not 0 (the variance formula's a² underflows); a limit that is not
    /// tiny keeps the formula's own bits.
    #[test]
    fn a_huge_sigma_keeps_its_spread() {
        let d = TruncatedNormal {
            mean: 0.0,
            sigma: 1e200,
            limit: 0.01,
        };
        d.check().unwrap();
        let uniform = 0.01 / 3f64.sqrt();
        assert!(
            (d.std_dev() / uniform - 1.0).abs() < 1e-15,
            "{}",
            d.std_dev()
        );
        let d = TruncatedNormal { sigma: 1e300, ..d };
        assert!(
            (d.std_dev() / uniform - 1.0).abs() < 1e-15,
            "{}",
            d.std_dev()
        );
        let d = TruncatedNormal { sigma: 0.02, ..d };
        assert_eq!(
            d.std_dev(),
            0.02 * truncated_variance(d.limit_in_sigmas()).sqrt()
        );
    }
}
