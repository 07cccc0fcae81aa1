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
//! are drawn again from its stream (common random numbers), the gauge noise `σ_m·z` added
//! (`z` from the counter-based generator under [`GAUGE_SEED`], key (sample, member)), and the
//! displacements `x` regressed on them by least squares:
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

/// Each specimen's term `ln p(yᵢ | êᵢ)` (module doc), or its marginal term where it has no
/// measured member. `baseline` is the model the measured member indices refer to.
pub fn log_densities(
    job: &Job,
    baseline: &Model,
    sim: &Simulation,
    measured: &Measured,
    sigma_m: f64,
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
    let draws = Draws::new(job, baseline, sim, sigma_m);
    for (members, specimens) in groups {
        let regression = Regression::fit(sim, &draws, &members, sigma_m)?;
        for i in specimens {
            let e: Vec<f64> = own[i].iter().map(|&(_, e)| e).collect();
            out[i] = regression.log_density(&measured.y[i * d..(i + 1) * d], &e);
        }
    }
    Ok(out)
}

/// The simulated samples' measured length errors ê (drawn again from each sample's stream,
/// gauge noise added), by baseline member index.
struct Draws {
    /// `N × M` row-major, M the baseline's members.
    e: Vec<f64>,
    members: usize,
}

impl Draws {
    fn new(job: &Job, baseline: &Model, sim: &Simulation, sigma_m: f64) -> Self {
        let case = &job.cases[0];
        let key = truss_job::sampler::stream_key(job.seed, &case.name);
        // A derived case's model may number members differently (backlash): found by id.
        let index: Vec<Option<usize>> = baseline
            .members()
            .iter()
            .enumerate()
            .map(|(m, member)| match case.model.members().get(m) {
                Some(x) if x.id == member.id => Some(m),
                _ => case.model.member_index(&member.id),
            })
            .collect();
        let members = index.len();
        let mut e = Vec::with_capacity(sim.n * members);
        let mut drawn = Vec::new();
        for &k in &sim.indices {
            truss_job::sampler::draw_length_errors(&key, case, k, &mut drawn);
            e.extend(index.iter().enumerate().map(|(m, i)| {
                i.map_or(0.0, |i| drawn[i]) + sigma_m * noise_normal(GAUGE_SEED, k, m as u64)
            }));
        }
        Self { e, members }
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
            (0..n)
                .map(|r| draws.e[r * draws.members + members[j]])
                .collect()
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
        let draws = Draws { e, members: 1 };
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
