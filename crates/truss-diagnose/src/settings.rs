//! How to diagnose: the settings of a diagnosis (simulation size, the instrument's noise,
//! the false-positive rate, the candidates asked for) and its progress notes on stderr.

use std::time::Instant;

/// Seed of the simulated instrument noise.
pub const NOISE_SEED: u64 = 0x006e_6f69_7365;

/// How to diagnose.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Simulated samples per evaluation; `None`: max(2000, 20·n), at most 10 000.
    pub samples: Option<usize>,
    /// The instrument's standard deviation σ_m \[mm\].
    pub measurement_sigma: f64,
    /// The false-positive rate of the whole verdict on data that miss nothing. Half of it,
    /// [`Settings::candidate_level`], goes to the candidates' likelihood-ratio tests
    /// (Bonferroni over the candidates within a step, ForwardStop over the steps); the other
    /// half is the comparison's ([`crate::comparison::statistics::LEVEL`], fixed at 0.025).
    pub alpha: f64,
    /// No progress on stderr.
    pub quiet: bool,
    /// Only these candidates (by name); `None`: every applicable one.
    pub candidates: Option<Vec<String>>,
    /// With member measurements, condition each specimen's node term on its own measured
    /// members ([`crate::likelihood::conditional`]); `false`: the member measurements only enter as
    /// draws from the case's distributions (the older, distribution-only use, kept for
    /// comparison).
    pub condition_on_members: bool,
    /// Worker threads of the simulations and bootstraps (`--threads`); `None`: every core
    /// this process may use ([`truss_threads::available`]). The results do not depend on it.
    pub threads: Option<usize>,
}

impl Settings {
    /// The candidates' family-wise level: α/2 (see [`Settings::alpha`]).
    pub fn candidate_level(&self) -> f64 {
        self.alpha / 2.0
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            samples: None,
            measurement_sigma: 0.0,
            alpha: 0.05,
            quiet: false,
            candidates: None,
            condition_on_members: true,
            threads: None,
        }
    }
}

impl Settings {
    /// N for `n` specimens.
    pub fn samples_for(&self, n: usize) -> usize {
        self.samples.unwrap_or_else(|| (20 * n).clamp(2000, 10_000))
    }

    /// The worker threads to use: [`Settings::threads`], or every core.
    pub fn thread_count(&self) -> usize {
        truss_threads::or_available(self.threads)
    }
}

/// Progress lines on stderr with the elapsed time.
pub struct Progress {
    quiet: bool,
    start: Instant,
}

impl Progress {
    /// Starts the clock.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            start: Instant::now(),
        }
    }
    /// Prints a line.
    pub fn note(&self, message: &str) {
        if !self.quiet {
            eprintln!("[{:6.1} s] {message}", self.start.elapsed().as_secs_f64());
        }
    }
    /// Seconds since the start.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}
