//! What the data could not have seen: for every candidate not in the final model, the
//! smallest effect its test against the final model would have detected with 80 % power
//! ([`crate::likelihood::power`]), at that test's level, c and λ̄: the test of the step
//! after the last kept one (whose null is the final model), or step 1's when nothing was
//! kept.

use crate::candidates::candidate::Candidate;
use crate::candidates::parameter::two_digit_decimals;
use crate::likelihood::power::Unseen;
use crate::selection::decide::DELTA_BIC;
use crate::selection::step::Step;

/// The candidates of `steps[index]` (the step after the last kept one) not named in the
/// final model `named`, with their limits and naming limits (the step names only at
/// ΔBIC ≤ −[`DELTA_BIC`]); none when no step tested against the final model (no
/// candidate was left). `library` holds every candidate.
pub fn unseen(
    steps: &[Step],
    index: usize,
    named: &[&str],
    n: usize,
    library: &[Box<dyn Candidate>],
) -> Vec<Unseen> {
    let Some(step) = steps.get(index) else {
        return Vec::new();
    };
    step.candidates
        .iter()
        .filter(|c| !named.contains(&c.name.as_str()))
        .map(|c| Unseen {
            name: c.name.clone(),
            step: step.number,
            significant: c.significant,
            p_value: c.p_value,
            specimens: n,
            limit: c.detection_limit.clone().map(|mut l| {
                if let Some(k) = library.iter().find(|k| k.name() == c.name) {
                    l.with_naming(k.parameters(), n, DELTA_BIC);
                }
                l
            }),
        })
        .collect()
}

/// A size with its unit, µm for mm, to two significant digits.
/// A value in the hardware's unit: a length in mm as µm, others as they are.
pub(crate) fn in_hardware_units(v: f64, unit: &'static str) -> (f64, &'static str) {
    if unit == "mm" {
        (v * truss_units::MICROMETRE_PER_MM, "µm")
    } else {
        (v, unit)
    }
}

fn size_text(v: f64, unit: &'static str) -> String {
    let (v, unit) = in_hardware_units(v, unit);
    let digits = two_digit_decimals(v).unwrap_or(0);
    format!("{v:.digits$} {unit}")
}

/// A naming limit is said where it exceeds the detection limit by more than this factor.
pub const NAMING_SAYS: f64 = 1.05;

impl Unseen {
    /// The limit of the candidate's most visible parameter in words: `` `length_bias`
    /// bias.longeron below 1.8 µm `` (a scale as its factor), then its naming limit where
    /// that is more than [`NAMING_SAYS`] times larger and reads differently
    /// (` (named only from 2.3 µm)`), or that it
    /// is not detectable at any size within the plausible range; `c` is the candidate.
    pub fn words(&self, c: &dyn Candidate) -> String {
        let Some(limit) = &self.limit else {
            return format!("`{}`: no limit (its fit failed)", self.name);
        };
        let Some(j) = limit.most_visible else {
            return format!(
                "`{}`: not detectable at any size within its plausible range",
                self.name
            );
        };
        let p = &limit.parameters[j];
        let q = &c.parameters()[j];
        let (size, value) = (p.size.unwrap_or(0.0), p.value.unwrap_or(q.null));
        let amount = if q.log {
            format!(
                "off by a factor below {:.2} (stated {})",
                value / q.null,
                size_text(q.null, q.unit)
            )
        } else {
            format!("below {}", size_text(size, q.unit))
        };
        // The naming limit, where naming asks clearly more than significance (its BIC).
        let naming = match (p.naming_value, p.naming_size) {
            (Some(Some(v)), Some(Some(d)))
                if d > NAMING_SAYS * size && size_text(d, q.unit) != size_text(size, q.unit) =>
            {
                if q.log {
                    format!(" (named only from a factor {:.2})", v / q.null)
                } else {
                    format!(" (named only from {})", size_text(d, q.unit))
                }
            }
            (Some(None), _) => " (not named at any size within its plausible range)".into(),
            _ => String::new(),
        };
        format!(
            "`{}` {} {amount}{naming}{}",
            self.name,
            p.name,
            if self.significant {
                " (but its test was significant)"
            } else {
                ""
            }
        )
    }
}

/// The stated limits checked by simulation: data made by [`crate::synth`] with a
/// `length_bias` along its most visible parameter at 1.5 and 0.5 times the limit stated on
/// data without it; the candidate's test (alone in its step, so α_K = 0.025) must be
/// significant in at least 70 % of the trials at 1.5 times and in at most 30 % at 0.5
/// times. The limit is of power 0.8 at 1.0 times; the asymptotic power at 1.5 times
/// (λ = 2.25·λ₈₀) is above 0.99 and at 0.5 times (λ = λ₈₀/4) 0.2 (both printed). 30 specimens,
/// N = 300 samples, [`TRIALS`] = 20 seeds each: a true rate of 0.2 passes the 30 % bound
/// (at most 6 of 20) with probability 0.91, one of 0.5 with 0.06; 0.99 passes the 70 %
/// bound (at least 14) with probability 1 − 1e-8, 0.6 with 0.25.
#[cfg(test)]
mod tests {
    use super::size_text;
    use crate::candidates::library_for;
    use crate::comparison::baseline::Baseline;
    use crate::comparison::measured::read;
    use crate::likelihood::score::{Evaluator, Test, fit_candidate};
    use crate::synth::{SynthOptions, synth};
    use std::path::{Path, PathBuf};

    /// Sizes read in µm for mm, to two significant digits.
    #[test]
    fn sizes_read_to_two_digits() {
        assert_eq!(size_text(0.00183, "mm"), "1.8 µm");
        assert_eq!(size_text(0.0183, "mm"), "18 µm");
        assert_eq!(size_text(0.297, "K"), "0.30 K");
        assert_eq!(size_text(0.000123, "K/mm"), "0.00012 K/mm");
    }

    /// Trials per size.
    const TRIALS: usize = 20;
    const SPECIMENS: usize = 30;
    const SAMPLES: usize = 300;
    const LEVEL: f64 = 0.025;

    fn job() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/diagnose-baseline.json")
    }

    /// The candidate's test on data made under `seed` with `effect`: significant?, and the
    /// limit it states.
    fn test_on(
        dir: &Path,
        effect: &str,
        seed: u64,
    ) -> (bool, Option<crate::likelihood::power::DetectionLimit>) {
        let mut csv = Vec::new();
        synth(
            &SynthOptions {
                job: job(),
                case: "as-built".into(),
                specimens: SPECIMENS,
                seed,
                effect: effect.into(),
                measurement_sigma: 0.001,
                all_nodes: false,
                members_out: None,
            },
            &mut csv,
        )
        .unwrap();
        let path = dir.join(format!("{seed}.csv"));
        std::fs::write(&path, csv).unwrap();
        let baseline = Baseline::read(&job(), "as-built").unwrap();
        let measured = read(baseline.model(), &path, None, 5).unwrap();
        let (library, _) = library_for(&baseline, false);
        let c = library
            .iter()
            .find(|c| c.name() == "length_bias")
            .unwrap()
            .as_ref();
        let ev = Evaluator {
            baseline: &baseline,
            start: baseline.derived_case(),
            measured: &measured,
            samples: SAMPLES,
            sigma_m: 0.001,
            condition: false,
            threads: 1,
            simulations: Default::default(),
            memo: None,
            gauge: &crate::likelihood::conditional::GaugeNoise::new(SAMPLES, &measured),
        };
        let null: Vec<f64> = c.parameters().iter().map(|p| p.null).collect();
        let l0: f64 = ev.terms_at(c, &null).unwrap().iter().sum();
        let test = Test {
            l0,
            n: measured.n(),
            inflation: 1.0 + measured.n() as f64 / SAMPLES as f64,
            level: LEVEL,
        };
        let s = fit_candidate(&ev, c, &test).score;
        (s.significant, s.detection_limit)
    }

    #[test]
    #[ignore = "slow statistical check: run in release"]
    fn stated_limits_hold_in_simulation() {
        let dir = tempfile::tempdir().unwrap();
        let clock = std::time::Instant::now();
        let (_, limit) = test_on(dir.path(), "none", 7_000);
        let limit = limit.expect("a limit on data without the effect");
        let j = limit.most_visible.expect("a length bias is visible");
        let p = &limit.parameters[j];
        let size = p.size.unwrap();
        let asymptotic = |f: f64| {
            crate::likelihood::power::power(
                limit.critical_value,
                limit.parameters.len(),
                f * f * limit.noncentrality,
            )
        };
        eprintln!(
            "limit: {} {:.3} µm; asymptotic power at 1.5×: {:.3}, at 0.5×: {:.3} ({limit:?})",
            p.name,
            size * 1e3,
            asymptotic(1.5),
            asymptotic(0.5)
        );
        let found = |factor: f64| {
            (0..TRIALS as u64)
                .filter(|&i| {
                    let effect = format!("length_bias:{}={}", p.name, factor * size);
                    test_on(dir.path(), &effect, 7_100 + i).0
                })
                .count()
        };
        let (large, small) = (found(1.5), found(0.5));
        eprintln!(
            "found at 1.5×: {large}/{TRIALS}, at 0.5×: {small}/{TRIALS}; {:.1} s",
            clock.elapsed().as_secs_f64()
        );
        assert!(large as f64 >= 0.7 * TRIALS as f64, "{large}/{TRIALS}");
        assert!(small as f64 <= 0.3 * TRIALS as f64, "{small}/{TRIALS}");
    }
}
