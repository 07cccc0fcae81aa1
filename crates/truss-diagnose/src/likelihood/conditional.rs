//! Each specimen's own measured members in its likelihood (`--measured-members`).
//!
//! ## The likelihood
//!
//! A specimen `i` whose members `P` were measured as `êᵢ = eᵢ + gauge noise` (mm) has node
//! displacements `yᵢ` (mm) that depend mostly on those very length errors. Its term of ℓ is
//! the joint density of both, factorised as
//!
//! ```text
//! ln p(yᵢ, êᵢ) = ln p(yᵢ | êᵢ) + Σ_{m ∈ P} ln p(ê_{i,m})
//! ```
//!
//! The second part is the member term of [`crate::likelihood::gaussian`] (each measured member's
//! length error against the case's distribution of it). The first is the Gaussian
//! conditional of the case's joint distribution of (x, ê), estimated from the same `N`
//! simulated samples as the marginal one: every sample's length errors of the members in `P`
//! are those its solve drew (common random numbers: [`Simulation::errors`], the same words
//! as every other case's), the gauge noise `σ_m·z` added (`z` from the counter-based
//! generator under [`GAUGE_SEED`], key (sample, member), drawn once per diagnosis:
//! [`GaugeNoise`]), and the displacements `x` regressed on them by least squares:
//!
//! ```text
//! x = x̄ + Bᵀ(ê − ē) + r,     p(yᵢ | êᵢ) ≈ N(yᵢ; x̄ + Bᵀ(êᵢ − ē), S_r + (σ_m² + τ²)·I)
//! ```
//!
//! with `S_r = Σ r rᵀ/(N − q − 1)` the residual covariance (q the members regressed on, those
//! whose simulated ê has a spread), scaled for specimen i by the regression's prediction
//! factor `1 + 1/N + hᵢ`, `hᵢ = (êᵢ − ē)ᵀ(EᵀE)⁻¹(êᵢ − ē)` (E the centred simulated ê): the
//! estimated coefficients' own error, about q/N, which the simulation inflation c = 1 + n/N
//! does not cover. This is exact when (x, ê) are jointly normal, and the
//! best linear predictor otherwise: the node positions are nearly linear in small length
//! errors, while what is not linear in them (free play, slack cables, the candidates' own
//! effects) stays in `x̄` and `S_r`. Members a specimen did not measure are drawn from the job
//! as before and so are part of `S_r`. Specimens are grouped by the set of members they
//! measured, one regression per set; a specimen with no member measured keeps the marginal
//! term `N(yᵢ; x̄, S_x + (σ_m² + τ²)·I)`.
//!
//! Conditioning removes the scatter the measured member errors cause, so an effect that the
//! member errors would hide (a joint clearance of a few micrometres) stands out, and a
//! length effect shows in the member term, where it belongs, rather than in the node term.

use crate::comparison::measured::Measured;
use crate::comparison::simulate::{Simulation, noise_normal};
use crate::errors::DiagnoseError;
use crate::likelihood::gaussian::{Gaussian, RESOLUTION};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use truss_core::Model;
use truss_job::Job;

/// Seed of the simulated gauge noise on member measurements.
pub const GAUGE_SEED: u64 = 0x6761_7567_6500;

/// The standard normals `z` of the simulated gauge noise (module doc) of samples
/// `0..samples` at the members the node specimens measured: a function of (sample, member)
/// alone, so drawn at the first simulation and read by every later one.
#[derive(Debug)]
pub struct GaugeNoise {
    samples: usize,
    /// The members the node specimens measured (baseline indices, ascending).
    members: Vec<usize>,
    /// `z` of sample `k`, member `members[c]` at `k·members.len() + c`, once drawn.
    z: std::cell::OnceCell<Vec<f64>>,
}

impl GaugeNoise {
    /// The gauge noise of samples `0..samples` at the members `measured`'s node specimens
    /// measured (none without member measurements), drawn when first read.
    pub fn new(samples: usize, measured: &Measured) -> Self {
        let mut members: Vec<usize> = measured.members.as_ref().map_or(Vec::new(), |data| {
            data.observations
                .iter()
                .zip(&data.truss)
                .filter(|&(_, &t)| t < measured.n())
                .map(|(&(m, _), _)| m)
                .collect()
        });
        members.sort_unstable();
        members.dedup();
        Self {
            samples,
            members,
            z: std::cell::OnceCell::new(),
        }
    }

    /// `z` (see the field), drawn on the first call.
    fn z(&self) -> &[f64] {
        self.z.get_or_init(|| {
            (0..self.samples as u64)
                .flat_map(|k| {
                    self.members
                        .iter()
                        .map(move |&m| noise_normal(GAUGE_SEED, k, m as u64))
                })
                .collect()
        })
    }
}

/// Each specimen's term `ln p(yᵢ | êᵢ)` (module doc), or its marginal term where it has no
/// measured member. `baseline` is the model the measured member indices refer to; `gauge`
/// the gauge noise of `measured`, of at least the simulation's samples.
pub fn log_densities(
    job: &Job,
    baseline: &Model,
    sim: &Simulation,
    measured: &Measured,
    sigma_m: f64,
    gauge: &GaugeNoise,
) -> Result<Vec<f64>, DiagnoseError> {
    let n = measured.n();
    let d = sim.d;
    let marginal = Gaussian::from_simulation(sim, sigma_m)?;
    let mut out = marginal.log_densities(&measured.y);
    let Some(data) = &measured.members else {
        return Ok(out);
    };
    // Each node specimen's measured members, (baseline index, value), sorted.
    let mut own: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for (&(m, e), &t) in data.observations.iter().zip(&data.truss) {
        if t < n {
            own[t].push((m, e));
        }
    }
    let mut groups: BTreeMap<Vec<usize>, Vec<usize>> = BTreeMap::new();
    for (i, o) in own.iter_mut().enumerate() {
        o.sort_by_key(|&(m, _)| m);
        if !o.is_empty() {
            groups
                .entry(o.iter().map(|&(m, _)| m).collect())
                .or_default()
                .push(i);
        }
    }
    if groups.is_empty() {
        return Ok(out);
    }
    let draws = Draws::new(job, baseline, sim, sigma_m, gauge)?;
    for (members, specimens) in groups {
        let regression = Regression::fit(sim, &draws, &members, sigma_m)?;
        for i in specimens {
            let e: Vec<f64> = own[i].iter().map(|&(_, e)| e).collect();
            out[i] = regression.log_density(&measured.y[i * d..(i + 1) * d], &e);
        }
    }
    Ok(out)
}

/// The simulated samples' measured length errors ê (each sample's drawn errors, gauge
/// noise added), at the measured members.
struct Draws {
    /// `N × width` row-major: sample row r, measured member c at `r·width + c`.
    e: Vec<f64>,
    width: usize,
    /// Each baseline member's column in `e`, if measured.
    column: Vec<Option<usize>>,
}

impl Draws {
    fn new(
        job: &Job,
        baseline: &Model,
        sim: &Simulation,
        sigma_m: f64,
        gauge: &GaugeNoise,
    ) -> Result<Self, DiagnoseError> {
        let case = &job.cases[0];
        let (members, z) = (&gauge.members, gauge.z());
        let width = members.len();
        if sim.errors.len() != sim.n * sim.members || sim.members != case.model.members().len() {
            return Err(DiagnoseError::Simulation {
                what: case.name.clone(),
                message: format!(
                    "the simulation kept {} length errors for {} samples of {} members",
                    sim.errors.len(),
                    sim.n,
                    case.model.members().len()
                ),
            });
        }
        // A derived case's model may number members differently (backlash): found by id.
        let index: Vec<Option<usize>> = members
            .iter()
            .map(|&m| {
                let id = &baseline.members()[m].id;
                match case.model.members().get(m) {
                    Some(x) if &x.id == id => Some(m),
                    _ => case.model.member_index(id),
                }
            })
            .collect();
        let mut column = vec![None; baseline.members().len()];
        for (c, &m) in members.iter().enumerate() {
            column[m] = Some(c);
        }
        if sim
            .indices
            .iter()
            .any(|&k| (k as usize + 1) * width > z.len())
        {
            return Err(DiagnoseError::Simulation {
                what: case.name.clone(),
                message: "a sample beyond the diagnosis's samples has no gauge noise".into(),
            });
        }
        let mut e = Vec::with_capacity(sim.n * width);
        for (drawn, &k) in sim
            .errors
            .chunks_exact(sim.members.max(1))
            .zip(&sim.indices)
        {
            let z = &z[k as usize * width..(k as usize + 1) * width];
            e.extend(
                index
                    .iter()
                    .zip(z)
                    .map(|(i, z)| i.map_or(0.0, |i| drawn[i]) + sigma_m * z),
            );
        }
        Ok(Self { e, width, column })
    }
}

/// The least-squares regression of the displacements on some members' ê.
struct Regression {
    /// Regressed members (positions in the group's member list).
    kept: Vec<usize>,
    /// ē of the kept members.
    e_mean: DVector<f64>,
    /// x̄.
    x_mean: DVector<f64>,
    /// `q × d` coefficients.
    b: DMatrix<f64>,
    /// The centred regressors' Gram matrix EᵀE, factorised (for the leverage).
    gram: Option<nalgebra::Cholesky<f64, nalgebra::Dyn>>,
    /// Simulated samples N.
    samples: usize,
    /// The predictive covariance, factorised.
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    log_det: f64,
}

impl Regression {
    fn fit(
        sim: &Simulation,
        draws: &Draws,
        members: &[usize],
        sigma_m: f64,
    ) -> Result<Self, DiagnoseError> {
        let (n, d) = (sim.n, sim.d);
        let column = |j: usize| -> Vec<f64> {
            let c = draws.column[members[j]].expect("a group's members are measured");
            (0..n).map(|r| draws.e[r * draws.width + c]).collect()
        };
        let mut kept = Vec::new();
        let mut cols = Vec::new();
        for j in 0..members.len() {
            let c = column(j);
            let mean = c.iter().sum::<f64>() / n as f64;
            let var = c.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
            // A member without spread (and no gauge noise) carries nothing to regress on.
            if var > 1e-24 {
                kept.push(j);
                cols.push((mean, c));
            }
        }
        let q = kept.len();
        let failed = |message: String| DiagnoseError::Simulation {
            what: "the regression on the measured members".into(),
            message,
        };
        if n < q + d + 10 {
            return Err(failed(format!(
                "{n} converged samples are too few to regress {d} coordinates on {q} measured members (use more --samples)"
            )));
        }
        let e_mean = DVector::from_iterator(q, cols.iter().map(|(m, _)| *m));
        let x_mean = DVector::from_iterator(
            d,
            (0..d).map(|j| (0..n).map(|r| sim.x[r * d + j]).sum::<f64>() / n as f64),
        );
        let ec = DMatrix::from_fn(n, q, |r, j| cols[j].1[r] - e_mean[j]);
        let xc = DMatrix::from_fn(n, d, |r, j| sim.x[r * d + j] - x_mean[j]);
        let (b, gram) = if q == 0 {
            (DMatrix::zeros(0, d), None)
        } else {
            let gram = ec.transpose() * &ec;
            let chol = nalgebra::Cholesky::new(gram)
                .ok_or_else(|| failed("the members' simulated errors are collinear".into()))?;
            (chol.solve(&(ec.transpose() * &xc)), Some(chol))
        };
        let r = &xc - &ec * &b;
        let mut cov = r.transpose() * &r / (n - q - 1) as f64;
        let extra = sigma_m * sigma_m + RESOLUTION * RESOLUTION;
        for j in 0..d {
            cov[(j, j)] += extra;
        }
        let chol = nalgebra::Cholesky::new(cov.clone())
            .ok_or_else(|| failed("the residual covariance is not positive definite".into()))?;
        let log_det = crate::likelihood::gaussian::log_det(&chol);
        Ok(Self {
            kept,
            e_mean,
            x_mean,
            b,
            gram,
            samples: n,
            chol,
            log_det,
        })
    }

    /// `ln N(y; x̄ + Bᵀ(ê − ē), Σ_r)` for a specimen's displacements `y` and its measured
    /// errors `e` (the group's members, in order).
    fn log_density(&self, y: &[f64], e: &[f64]) -> f64 {
        let d = y.len();
        let de = DVector::from_iterator(
            self.kept.len(),
            self.kept
                .iter()
                .zip(self.e_mean.iter())
                .map(|(&j, m)| e[j] - m),
        );
        // The prediction's own uncertainty: Σ_r·(1 + 1/N + h), h = (ê − ē)ᵀ(EᵀE)⁻¹(ê − ē)
        // the leverage of the specimen's measured errors (a regression's prediction
        // variance), so that N barely above q does not make the fit overconfident.
        let h = self.gram.as_ref().map_or(0.0, |g| de.dot(&g.solve(&de)));
        let scale = 1.0 + 1.0 / self.samples as f64 + h;
        let mu = &self.x_mean + self.b.transpose() * de;
        let diff = DVector::from_iterator(d, y.iter().zip(mu.iter()).map(|(a, b)| a - b));
        let z = self
            .chol
            .l_dirty()
            .solve_lower_triangular(&diff)
            .expect("L is regular");
        -0.5 * (d as f64 * (2.0 * std::f64::consts::PI).ln()
            + self.log_det
            + d as f64 * scale.ln()
            + z.norm_squared() / scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comparison::measured::{Coordinate, MemberData};
    use crate::comparison::simulate::simulate;

    /// A 5-stage prism job of `samples` samples, with pin joints in free play where
    /// `backlash` (hole nodes and joints added to the rigid baseline's model) and a thermal
    /// field (length changes the members' measurements do not see).
    fn job(backlash: bool, samples: u64) -> Job {
        let (model, clearance) = if backlash {
            (
                r#"{"prism": {"stages": 5, "backlash": true}}"#,
                r#""backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}},"#,
            )
        } else {
            (r#"{"prism": {"stages": 5}}"#, "")
        };
        let text = format!(
            r#"{{"model": {model}, "seed": 5,
                "cases": [{{"name": "c", "samples": {samples}, {clearance}
                            "effects": {{"thermal_gradient": {{"gradient": [0, 0, 0.002], "offset": 0.5, "alpha": 23e-6}}}},
                            "length_errors": {{"batten": {{"normal": {{"sigma": 0.0067}}}},
                                               "longeron": {{"normal": {{"sigma": 0.0067}}}},
                                               "diagonal": {{"uniform": {{"low": -0.0201, "high": 0}}}}}}}}]}}"#
        );
        Job::from_json(&text, std::path::Path::new(".")).unwrap()
    }

    /// The measured members' simulated errors, read from the simulation and the gauge noise
    /// drawn once, are exactly those drawn again from every sample's stream as the errors
    /// were before (`draw_length_errors` plus `σ_m·z`, found by the baseline member's id in
    /// the derived model), bit for bit; members no node specimen measured get no column.
    #[test]
    fn simulated_member_errors_are_those_drawn_again_from_each_stream() {
        let samples = 24;
        let baseline = job(false, samples).cases[0].model.clone();
        let derived = job(true, samples);
        let case = &derived.cases[0];
        let top = baseline.top_surface().unwrap().nodes;
        let sim = simulate(
            &derived,
            &Coordinate::of_nodes(&baseline, &top),
            samples as usize,
            None,
            2,
        )
        .unwrap();
        assert_eq!(sim.n, samples as usize);
        // Specimen 0 measured members 3 and 1, specimen 1 member 1 again; member 0 only on
        // a truss without node positions (index 2 of 2 node specimens).
        let measured = Measured {
            members: Some(MemberData {
                observations: vec![(3, 0.001), (1, -0.002), (1, 0.0), (0, 0.003)],
                truss: vec![0, 0, 1, 2],
            }),
            specimens: vec!["a".into(), "b".into()],
            coords: Vec::new(),
            y: Vec::new(),
            tan_x: Vec::new(),
            tan_y: Vec::new(),
            theta_p: Vec::new(),
            lines: Vec::new(),
            report: Default::default(),
        };
        let gauge = GaugeNoise::new(samples as usize, &measured);
        let sigma_m = 0.001;
        let draws = Draws::new(&derived, &baseline, &sim, sigma_m, &gauge).unwrap();
        assert_eq!(draws.width, 2);
        assert_eq!(draws.column[..4], [None, Some(0), None, Some(1)]);
        let key = truss_job::sampler::stream_key(derived.seed, &case.name);
        let mut drawn = Vec::new();
        for (r, &k) in sim.indices.iter().enumerate() {
            truss_job::sampler::draw_length_errors(&key, case, k, &mut drawn);
            for (c, m) in [(0, 1), (1, 3)] {
                let i = case.model.member_index(&baseline.members()[m].id).unwrap();
                let want = drawn[i] + sigma_m * noise_normal(GAUGE_SEED, k, m as u64);
                assert_eq!(
                    draws.e[r * 2 + c].to_bits(),
                    want.to_bits(),
                    "sample {k}, member {m}"
                );
            }
        }
    }

    /// One coordinate that is exactly twice one member's error plus independent scatter of
    /// SD 0.5: the regression recovers slope 2 and the residual variance 0.25, and the
    /// conditional density of y = 2e + 0.3 is that of N(0.3; 0, 0.25 + τ²).
    #[test]
    fn regression_recovers_a_linear_dependence_and_its_residual() {
        let n = 4000;
        let (mut x, mut e) = (Vec::new(), Vec::new());
        for k in 0..n as u64 {
            let ek = noise_normal(7, k, 0);
            let rk = 0.5 * noise_normal(7, k, 1);
            e.push(ek);
            x.push(2.0 * ek + rk);
        }
        let sim = Simulation {
            n,
            d: 1,
            x,
            ..Simulation::default()
        };
        let draws = Draws {
            e,
            width: 1,
            column: vec![Some(0)],
        };
        let r = Regression::fit(&sim, &draws, &[0], 0.0).unwrap();
        assert!((r.b[(0, 0)] - 2.0).abs() < 0.03, "{}", r.b);
        let at = 1.0;
        // The prediction factor 1 + 1/N + (1 − ē)²/Σ(e − ē)² ≈ 1 + 2/N.
        let var = (0.25 + RESOLUTION * RESOLUTION) * (1.0 + 2.0 / n as f64);
        let want = -0.5 * ((2.0 * std::f64::consts::PI * var).ln() + 0.09 / var);
        let got = r.log_density(&[2.0 * (at - r.e_mean[0]) + r.x_mean[0] + 0.3], &[at]);
        assert!((got - want).abs() < 0.05, "{got} vs {want}");
    }
}
