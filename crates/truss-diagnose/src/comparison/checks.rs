//! The data checked against the stated instrument noise σ_m (`--measurement-sigma`) before
//! anything is simulated or fitted.
//!
//! Every measured coordinate is the truss's displacement plus the instrument's noise, and
//! the simulation adds σ_m to every simulated coordinate; so the specimen-to-specimen
//! scatter of a coordinate cannot be below σ_m, nor can two independent specimens lie
//! closer together than two draws of the noise. Data that do are either not independent
//! specimens (copies, a specimen entered twice with rounding) or measured with less noise
//! than stated; fitted as they are, their missing scatter reads as an effect. The checks
//! (none with σ_m = 0: nothing is stated):
//!
//! - **A coordinate with no scatter at all** (the same value in every specimen): refused
//!   ([`DiagnoseError::Measured`], naming the coordinates): with σ_m > 0 it cannot happen
//!   (a pasted column, or values rounded coarser than the noise).
//! - **Scatter below the noise** (warning `scatter_below_noise`): for coordinate j with
//!   sample variance s_j² over n specimens, (n − 1)·s_j²/σ_m² is stochastically at least
//!   χ²_{n−1} (the displacement's own scatter only adds: Anderson's theorem on the centred
//!   Gaussian noise), so p_j = F_{χ²_{n−1}}((n − 1)·s_j²/σ_m²) is a valid lower-tail
//!   p-value; a coordinate is flagged where p_j < [`CHECK_LEVEL`]/d (Bonferroni over the d
//!   coordinates). The warning names the flagged coordinates with their scatter and the
//!   largest σ_m the least-scattered allows at that level,
//!   σ_max = √((n − 1)·s_j²/χ²_{n−1}(CHECK_LEVEL/d)).
//! - **Specimens closer than the noise allows** (warning `specimens_closer_than_noise`): for
//!   specimens u ≠ v, D = Σ_j (y_uj − y_vj)² is stochastically at least 2σ_m²·χ²_d (the
//!   difference of two independent noises, N(0, 2σ_m²) per coordinate, plus the
//!   displacements' difference, which only adds), so p = F_{χ²_d}(D/(2σ_m²)); a pair is
//!   flagged where p < [`CHECK_LEVEL`]/(n(n − 1)/2) (Bonferroni over the pairs). Exact copies
//!   are refused before ([`crate::comparison::measured`]); these are near-copies.
//!
//! The two warnings go to stderr and into `diagnosis.json` (`data.checks[]`) and
//! `diagnosis.md` (the Data section); the diagnosis still runs, since the stated noise may
//! simply be too large, but its verdict then rests on a noise the data contradict.

use crate::comparison::measured::{DataCheck, Measured};
use crate::errors::DiagnoseError;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The family-wise level of each check (over the coordinates, or over the pairs): a
/// warning on data that agree with the stated noise at most once in a thousand diagnoses.
pub const CHECK_LEVEL: f64 = 1e-3;

/// Most coordinates or pairs named in a warning.
pub const NAMED: usize = 5;

/// A length in µm for the sentences (the data are in mm).
fn um(mm: f64) -> String {
    let v = mm * 1000.0;
    if v >= 10.0 {
        format!("{v:.1} µm")
    } else {
        format!("{v:.2} µm")
    }
}

/// The checks of the module doc on `data` against `sigma_m` \[mm\]: the warnings, or the
/// refusal of a coordinate with no scatter.
pub fn check(data: &Measured, sigma_m: f64) -> Result<Vec<DataCheck>, DiagnoseError> {
    let (n, d) = (data.n(), data.d());
    if sigma_m <= 0.0 || n < 2 || d == 0 {
        return Ok(Vec::new());
    }
    let path = std::path::PathBuf::from(&data.report.file);
    let mut out = Vec::new();
    // Per coordinate: the sample variance (two passes).
    let var: Vec<f64> = (0..d)
        .map(|j| {
            let mean = (0..n).map(|u| data.y[u * d + j]).sum::<f64>() / n as f64;
            (0..n)
                .map(|u| (data.y[u * d + j] - mean).powi(2))
                .sum::<f64>()
                / (n - 1) as f64
        })
        .collect();
    let flat: Vec<String> = (0..d)
        .filter(|&j| (1..n).all(|u| data.y[u * d + j] == data.y[j]))
        .map(|j| data.coords[j].label())
        .collect();
    if !flat.is_empty() {
        return Err(DiagnoseError::Measured {
            path,
            message: format!(
                "{}{} {} the same value in all {n} specimens, which measurements with the stated instrument noise σ_m = {} never have: a pasted column, or values rounded coarser than the noise? Give the measurements to more digits, or state the noise the instrument has",
                flat.iter()
                    .take(NAMED)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
                if flat.len() > NAMED {
                    format!(" and {} more coordinates", flat.len() - NAMED)
                } else {
                    String::new()
                },
                if flat.len() == 1 { "has" } else { "have" },
                um(sigma_m)
            ),
        });
    }
    let chi = |k: usize| ChiSquared::new(k as f64).expect("k ≥ 1");
    let scatter = chi(n - 1);
    let level = CHECK_LEVEL / d as f64;
    let mut low: Vec<(usize, f64)> = (0..d)
        .map(|j| {
            (
                j,
                scatter.cdf((n - 1) as f64 * var[j] / (sigma_m * sigma_m)),
            )
        })
        .filter(|&(_, p)| p < level)
        .collect();
    if !low.is_empty() {
        low.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (least, p) = low[0];
        let sigma_max = ((n - 1) as f64 * var[least] / scatter.inverse_cdf(level)).sqrt();
        out.push(DataCheck {
            check: "scatter_below_noise",
            flagged: low.len(),
            p_value: p,
            words: format!(
                "the data contradict the stated instrument noise σ_m = {}: the specimen-to-specimen scatter of {} of the {d} coordinates ({}{}) is below it, which the noise every measurement carries does not allow (χ² lower tail over {n} specimens, p = {p:.1e} for {}, below {CHECK_LEVEL} over the {d} coordinates); these data allow at most σ_m = {}: state the instrument's noise, or check that the rows are independent specimens",
                um(sigma_m),
                low.len(),
                low.iter()
                    .take(NAMED)
                    .map(|&(j, _)| format!("{} SD {}", data.coords[j].label(), um(var[j].sqrt())))
                    .collect::<Vec<_>>()
                    .join(", "),
                if low.len() > NAMED { ", …" } else { "" },
                data.coords[least].label(),
                um(sigma_max)
            ),
        });
    }
    // Pairs of specimens: flagged below the Bonferroni threshold of D/(2σ_m²).
    let pairs = n * (n - 1) / 2;
    let spread = chi(d);
    let threshold = spread.inverse_cdf(CHECK_LEVEL / pairs as f64) * 2.0 * sigma_m * sigma_m;
    let mut close: Vec<(usize, usize, f64)> = Vec::new();
    for u in 0..n {
        let a = &data.y[u * d..(u + 1) * d];
        for v in u + 1..n {
            let b = &data.y[v * d..(v + 1) * d];
            let dist: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
            if dist < threshold {
                close.push((u, v, dist));
            }
        }
    }
    if !close.is_empty() {
        close.sort_by(|a, b| a.2.total_cmp(&b.2));
        let p = spread.cdf(close[0].2 / (2.0 * sigma_m * sigma_m));
        let name = |u: usize| format!("{:?} (line {})", data.specimens[u], data.lines[u]);
        out.push(DataCheck {
            check: "specimens_closer_than_noise",
            flagged: close.len(),
            p_value: p,
            words: format!(
                "{} pair(s) of specimens lie closer together in all {d} coordinates than two independent measurements with the stated noise σ_m = {} can (χ²_{d} lower tail, p = {p:.1e} for the closest, below {CHECK_LEVEL} over the {pairs} pairs): {}{}; near-copies of one specimen (a copy with rounding, one truss entered twice) are not independent specimens and narrow every interval",
                close.len(),
                um(sigma_m),
                close
                    .iter()
                    .take(NAMED)
                    .map(|&(u, v, dist)| format!(
                        "{} and {} ({} RMS apart, where the noise alone puts two specimens √2·σ_m = {} apart on average)",
                        name(v),
                        name(u),
                        um((dist / d as f64).sqrt()),
                        um(std::f64::consts::SQRT_2 * sigma_m)
                    ))
                    .collect::<Vec<_>>()
                    .join(", "),
                if close.len() > NAMED { ", …" } else { "" }
            ),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comparison::measured::{Coordinate, DataReport};

    /// Standard normals from splitmix64 and Box–Muller (a generator of the test's own).
    struct Normals(u64);
    impl Normals {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 + 0.5 / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (a, b) = (self.uniform(), self.uniform());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        }
    }

    /// Data of `n` specimens with `d` coordinates, rows `y`.
    fn data(n: usize, d: usize, y: Vec<f64>) -> Measured {
        Measured {
            specimens: (0..n).map(|u| format!("s{u}")).collect(),
            coords: (0..d)
                .map(|j| Coordinate {
                    node: j / 3,
                    node_id: format!("n{}", j / 3),
                    axis: j % 3,
                })
                .collect(),
            y,
            tan_x: vec![0.0; n],
            tan_y: vec![0.0; n],
            theta_p: vec![0.0; n],
            lines: (0..n).map(|u| 2 + 3 * u as u64).collect(),
            members: None,
            report: DataReport {
                file: "m.csv".into(),
                ..DataReport::default()
            },
        }
    }

    /// n specimens of d coordinates, each a N(0, sd²) draw (the noise; no displacement).
    fn gaussian(n: usize, d: usize, sd: f64, seed: u64) -> Vec<f64> {
        let mut g = Normals(seed);
        (0..n * d).map(|_| sd * g.normal()).collect()
    }

    /// By hand, with n = 3 and one coordinate, where χ²₂'s CDF is 1 − e^(−x/2): values 0,
    /// a, 2a have s² = a², so p = 1 − exp(−a²/σ_m²); at a = σ_m/100, p = 1 − e^(−10⁻⁴),
    /// below 10⁻³, flagged; the σ_m these data allow is √(2a²/q), q = −2 ln(1 − 10⁻³) the
    /// χ²₂ quantile. At a = σ_m/10 (p = 0.00995) nothing is flagged.
    #[test]
    fn scatter_below_noise_by_hand() {
        let sigma = 0.002;
        let a = sigma / 100.0;
        let w = check(&data(3, 1, vec![0.0, a, 2.0 * a]), sigma).unwrap();
        let s = w.iter().find(|c| c.check == "scatter_below_noise").unwrap();
        let p = 1.0 - (-1e-4f64).exp();
        assert!((s.p_value - p).abs() < 1e-6 * p, "{s:?}");
        let q = -2.0 * (1.0 - CHECK_LEVEL).ln();
        let allowed = (2.0 * a * a / q).sqrt();
        assert!(
            s.words.contains(&format!("at most σ_m = {}", um(allowed))),
            "{s:?}"
        );
        assert!(s.words.contains("n0 x SD 0.02 µm") && s.words.contains("σ_m = 2.00 µm"));
        let a = sigma / 10.0;
        let w = check(&data(3, 1, vec![0.0, a, 2.0 * a]), sigma).unwrap();
        assert!(w.iter().all(|c| c.check != "scatter_below_noise"), "{w:?}");
    }

    /// Data with exactly the stated noise raise no warning (over 200 data sets of 30
    /// specimens × 9 coordinates, at most 2, where each check's rate is at most 10⁻³), and
    /// none with σ_m = 0; at half the stated noise, 100 specimens flag all nine coordinates.
    #[test]
    fn the_stated_noise_passes_and_half_of_it_is_flagged() {
        let sigma = 0.001;
        let warned = (0..200)
            .filter(|&seed| {
                !check(&data(30, 9, gaussian(30, 9, sigma, seed)), sigma)
                    .unwrap()
                    .is_empty()
            })
            .count();
        assert!(warned <= 2, "{warned} of 200");
        let half = data(100, 9, gaussian(100, 9, 0.5 * sigma, 7));
        assert!(check(&half, 0.0).unwrap().is_empty());
        let w = check(&half, sigma).unwrap();
        let s = w.iter().find(|c| c.check == "scatter_below_noise").unwrap();
        assert_eq!(s.flagged, 9, "{s:?}");
        assert!(s.words.contains("9 of the 9 coordinates"), "{}", s.words);
    }

    /// A near-copy (specimen 40 = specimen 3 plus a twentieth of the noise) among 40
    /// specimens with the stated noise: the one pair is flagged, naming both with lines;
    /// the coordinates' scatter is not.
    #[test]
    fn a_near_copy_is_flagged_naming_the_pair() {
        let sigma = 0.001;
        let mut y = gaussian(40, 9, sigma, 11);
        let copy: Vec<f64> = y[27..36].to_vec();
        let mut g = Normals(99);
        y.extend(copy.iter().map(|v| v + 0.05 * sigma * g.normal()));
        let w = check(&data(41, 9, y), sigma).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(
            (w[0].check, w[0].flagged),
            ("specimens_closer_than_noise", 1)
        );
        assert!(
            w[0].words
                .contains("\"s40\" (line 122) and \"s3\" (line 11)"),
            "{}",
            w[0].words
        );
    }

    /// The pair threshold's χ² quantile far in the lower tail (10⁻³ over the 19 900 pairs of
    /// 200 specimens): for 2 degrees of freedom it is −2 ln(1 − p) by hand; for 27 the CDF
    /// at the quantile gives p back.
    #[test]
    fn lower_tail_quantiles_hold_far_out() {
        let p = CHECK_LEVEL / 19_900.0;
        let two = ChiSquared::new(2.0).unwrap().inverse_cdf(p);
        let by_hand = -2.0 * (-p).ln_1p();
        assert!((two - by_hand).abs() < 1e-6 * by_hand, "{two} {by_hand}");
        let c = ChiSquared::new(27.0).unwrap();
        let q = c.inverse_cdf(p);
        assert!((c.cdf(q) - p).abs() < 1e-3 * p, "{q} {}", c.cdf(q));
    }

    /// A coordinate with the same value in every specimen is refused naming it and the file.
    #[test]
    fn a_coordinate_without_scatter_is_refused() {
        let mut y = gaussian(10, 6, 0.001, 3);
        for u in 0..10 {
            y[u * 6 + 4] = 0.0125;
        }
        let e = check(&data(10, 6, y), 0.001).unwrap_err().to_string();
        assert!(
            e.starts_with("m.csv: n1 y has the same value in all 10 specimens"),
            "{e}"
        );
    }
}
