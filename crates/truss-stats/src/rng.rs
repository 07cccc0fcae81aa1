//! Counter-based random numbers: a random value is a pure function of (seed, stream,
//! replicate, counter), never of the order in which anything was read.
//!
//! ## Definition
//!
//! The mixing function is the SplitMix64 finaliser (Steele, Lea & Flood, "Fast splittable
//! pseudorandom number generators", OOPSLA 2014; constants of Vigna's `splitmix64.c`):
//!
//! ```text
//! mix64(z) = z ⊕ (z ≫ 31)  after  z ← (z ⊕ (z ≫ 30))·0xbf58476d1ce4e5b9,  z ← (z ⊕ (z ≫ 27))·0x94d049bb133111eb
//! ```
//!
//! with wrapping 64-bit arithmetic. The key of replicate `r` of stream `s` is
//! `k = mix64(mix64(seed ⊕ s) + (r + 1)·γ)` with `γ = 0x9e3779b97f4a7c15`, and the value for
//! counter `i` (for the bootstrap: the global sample index) is
//!
//! ```text
//! u(seed, s, r, i) = mix64(k + (i + 1)·γ)
//! ```
//!
//! that is, the `(i + 1)`-th output of a SplitMix64 generator started at state `k`.
//! Distinct streams ([`Stream`]) keep the bootstrap weights and the goodness-of-fit null
//! simulation independent.

/// The golden-ratio increment of SplitMix64.
pub const GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// The SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The independent random streams this crate draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u64)]
pub enum Stream {
    /// Poisson bootstrap weights, counter = global sample index.
    Bootstrap = 0x626f_6f74,
    /// Goodness-of-fit null samples, counter = position in the simulated sample.
    GofNull = 0x676f_6621,
    /// Goodness-of-fit null samples of the normal law, counter = twice the position in the
    /// simulated sample (and one more, the two uniforms of a Box–Muller draw).
    GofNormalNull = 0x676f_664e,
    /// Synthetic data for tests and benchmarks.
    Synthetic = 0x7379_6e74,
}

/// The key of replicate `replicate` of `stream` under `seed`.
#[inline]
pub fn replicate_key(seed: u64, stream: Stream, replicate: u64) -> u64 {
    mix64(mix64(seed ^ stream as u64).wrapping_add(replicate.wrapping_add(1).wrapping_mul(GAMMA)))
}

/// The 64 random bits for counter `i` under replicate key `key`.
#[inline(always)]
pub fn bits(key: u64, i: u64) -> u64 {
    bits_at(key, counter_offset(i))
}

/// `(i + 1)·γ`, the part of [`bits`] that does not depend on the replicate (hoisted out of the
/// bootstrap's loop over replicates).
#[inline(always)]
pub fn counter_offset(i: u64) -> u64 {
    i.wrapping_add(1).wrapping_mul(GAMMA)
}

/// [`bits`] from a precomputed [`counter_offset`].
#[inline(always)]
pub fn bits_at(key: u64, offset: u64) -> u64 {
    mix64(key.wrapping_add(offset))
}

/// A uniform number in the open interval (0, 1) from 64 random bits: `(⌊u/2¹²⌋ + ½)/2⁵²`,
/// exactly representable, between 2⁻⁵³ and 1 − 2⁻⁵³.
#[inline(always)]
pub fn open01(u: u64) -> f64 {
    ((u >> 12) as f64 + 0.5) * (1.0 / (1u64 << 52) as f64)
}

/// A standard exponential variate, `−ln U`, from 64 random bits.
#[inline(always)]
pub fn exp1(u: u64) -> f64 {
    -open01(u).ln()
}

/// A standard normal variate from two uniforms in (0, 1) by Box–Muller (cosine branch):
/// `√(−2 ln u₁)·cos(2π u₂)`.
#[inline]
pub fn box_muller(u1: f64, u2: f64) -> f64 {
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// A sequential stream of the counter-based generator: output `i` is [`bits`]`(seed, i)`, so
/// it is SplitMix64 started at state `seed`. Test data and benchmark samples are drawn from
/// it (uniforms by [`open01`], normals by [`box_muller`] of two uniforms).
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    key: u64,
    counter: u64,
}

impl SplitMix64 {
    /// The stream whose first output is `mix64(seed + γ)`.
    pub fn new(seed: u64) -> Self {
        Self {
            key: seed,
            counter: 0,
        }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let u = bits(self.key, self.counter);
        self.counter += 1;
        u
    }

    /// A uniform number in (0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        open01(self.next_u64())
    }

    /// A standard normal number (two uniforms).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        box_muller(a, b)
    }
}

/// The inverse-CDF table of the Poisson(1) distribution on 64-bit integers.
///
/// `thresholds[k] = ⌊F(k)·2⁶⁴⌋` with `F(k) = e⁻¹ Σ_{j ≤ k} 1/j!`; a weight is the number of
/// thresholds that `u` reaches, so `P(w = k) = F(k) − F(k−1)` to within 2⁻⁵³ (the precision of
/// `F` in double precision). Weights never exceed [`PoissonTable::MAX`].
#[derive(Debug, Clone)]
pub struct PoissonTable {
    thresholds: [u64; PoissonTable::MAX as usize],
}

impl Default for PoissonTable {
    fn default() -> Self {
        Self::new()
    }
}

impl PoissonTable {
    /// The largest weight the table can produce (P(W > 19) < 10⁻¹⁸ for W ~ Poisson(1)).
    pub const MAX: u8 = 19;

    /// Builds the table.
    pub fn new() -> Self {
        let mut thresholds = [u64::MAX; Self::MAX as usize];
        let mut term = (-1.0f64).exp();
        let mut cdf = 0.0f64;
        for (k, t) in thresholds.iter_mut().enumerate() {
            if k > 0 {
                term /= k as f64;
            }
            cdf += term;
            // `as` saturates at u64::MAX once the CDF rounds to 1.
            *t = (cdf * 18_446_744_073_709_551_616.0) as u64;
        }
        Self { thresholds }
    }

    /// The thresholds `⌊F(k)·2⁶⁴⌋`, k = 0, 1, ….
    pub fn thresholds(&self) -> &[u64] {
        &self.thresholds
    }

    /// The Poisson(1) weight for 64 random bits `u`.
    #[inline(always)]
    pub fn weight(&self, u: u64) -> u8 {
        let t = &self.thresholds;
        // Branch-free for the common weights 0..=3 (98.1 % of draws): the branch below is
        // almost always predicted.
        let w =
            u8::from(u >= t[0]) + u8::from(u >= t[1]) + u8::from(u >= t[2]) + u8::from(u >= t[3]);
        if u < t[3] {
            return w;
        }
        let mut w = 4;
        while (w as usize) < t.len() && u >= t[w as usize] {
            w += 1;
        }
        w
    }
}

/// The Poisson bootstrap weight of global sample `index` in replicate `replicate` under `seed`:
/// a pure function of the three, so it never depends on how the job was split or read.
pub fn poisson_weight(table: &PoissonTable, seed: u64, replicate: u64, index: u64) -> u8 {
    table.weight(bits(
        replicate_key(seed, Stream::Bootstrap, replicate),
        index,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mix must match the reference SplitMix64 (Vigna, splitmix64.c): the first outputs
    /// of a generator seeded with 0 are 0xe220a8397b1dcdaf, 0x6e789e6aa1b965f4, 0x06c45d188009454f.
    #[test]
    fn splitmix64_reference_outputs() {
        let key = 0u64;
        assert_eq!(bits(key, 0), 0xe220_a839_7b1d_cdaf);
        assert_eq!(bits(key, 1), 0x6e78_9e6a_a1b9_65f4);
        assert_eq!(bits(key, 2), 0x06c4_5d18_8009_454f);
    }

    /// Poisson(1) frequencies over 10⁶ draws against the pmf e⁻¹/k! (5-sigma binomial bands).
    #[test]
    fn poisson_weights_have_poisson_one_frequencies() {
        let table = PoissonTable::new();
        let n = 1_000_000u64;
        let mut counts = [0u64; 20];
        let key = replicate_key(7, Stream::Bootstrap, 3);
        let mut sum = 0u64;
        for i in 0..n {
            let w = table.weight(bits(key, i));
            counts[w as usize] += 1;
            sum += u64::from(w);
        }
        let mut pmf = (-1.0f64).exp();
        for (k, &c) in counts.iter().enumerate().take(8) {
            if k > 0 {
                pmf /= k as f64;
            }
            let expected = pmf * n as f64;
            let sd = (n as f64 * pmf * (1.0 - pmf)).sqrt();
            assert!(
                (c as f64 - expected).abs() < 5.0 * sd + 1.0,
                "k = {k}: {c} draws, expected {expected:.0} ± {sd:.0}"
            );
        }
        // Mean 1, variance 1: the sum of n weights is n ± 5·sqrt(n).
        assert!((sum as f64 - n as f64).abs() < 5.0 * (n as f64).sqrt());
    }

    #[test]
    fn table_is_monotone_and_saturates() {
        let t = PoissonTable::new();
        assert!(t.thresholds.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(t.weight(0), 0);
        assert_eq!(t.weight(u64::MAX), PoissonTable::MAX);
        // F(0) = e^-1 = 0.3679: just below and above the first threshold.
        let t0 = t.thresholds[0];
        assert_eq!(t.weight(t0 - 1), 0);
        assert_eq!(t.weight(t0), 1);
        assert!(((t0 as f64) / 2f64.powi(64) - (-1.0f64).exp()).abs() < 1e-15);
    }

    #[test]
    fn weights_depend_only_on_seed_replicate_index() {
        let table = PoissonTable::new();
        let a: Vec<u8> = (0..100).map(|i| poisson_weight(&table, 1, 5, i)).collect();
        let b: Vec<u8> = (0..100)
            .rev()
            .map(|i| poisson_weight(&table, 1, 5, i))
            .collect();
        assert!(a.iter().eq(b.iter().rev()));
        let c: Vec<u8> = (0..100).map(|i| poisson_weight(&table, 1, 6, i)).collect();
        assert_ne!(a, c);
    }

    #[test]
    fn open01_is_strictly_inside() {
        assert!(open01(0) > 0.0);
        assert!(open01(u64::MAX) < 1.0);
        assert!(exp1(u64::MAX) > 0.0);
    }

    /// The sequential stream is SplitMix64: from state 1234567 its first outputs are the
    /// reference values of Vigna's `splitmix64.c` (as printed by its test driver), and its
    /// normals have mean 0 and variance 1.
    #[test]
    fn sequential_stream_is_splitmix64() {
        let mut s = SplitMix64::new(1234567);
        assert_eq!(s.next_u64(), 6457827717110365317);
        assert_eq!(s.next_u64(), 3203168211198807973);
        let mut s = SplitMix64::new(7);
        let n = 20_000;
        let v: Vec<f64> = (0..n).map(|_| s.normal()).collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 4.0 / (n as f64).sqrt(), "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
    }
}
