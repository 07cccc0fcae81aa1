//! The Gaussian synthetic likelihood of the measured specimens under a simulated case.
//!
//! ## Definition
//!
//! With the specimens' displacement vectors `y₁ … yₙ ∈ ℝᵈ` (the compared coordinates, mm) and
//! a case's `N` simulated vectors `x₁ … x_N` (noise-free, common random numbers), the case's
//! predictive distribution of one specimen is approximated by the normal
//!
//! ```text
//! N(μ, Σ),   μ = x̄,   Σ = S_x + (σ_m² + τ²)·I,   S_x = Σⱼ (xⱼ − x̄)(xⱼ − x̄)ᵀ / (N − 1)
//! ```
//!
//! (σ_m the instrument's standard deviation, τ = [`RESOLUTION`] a floor that keeps Σ
//! regular where the model predicts no scatter at all), and
//!
//! ```text
//! ℓ = Σᵢ ln N(yᵢ; μ, Σ) = −n/2 · [d ln 2π + ln det Σ + tr(Σ⁻¹ S_y) + (ȳ − μ)ᵀ Σ⁻¹ (ȳ − μ)]
//! ```
//!
//! with `ȳ` and `S_y` (divisor n) the specimens' mean and covariance: the synthetic
//! likelihood (Wood 2010) of the specimens' first two moments. Σ is factorised by Cholesky.
//!
//! ## Measured members
//!
//! When member length errors were measured one by one, each observation `e` of member `m`
//! adds `ln N(e; E[ε_m], Var[ε_m] + σ_m² + τ²)` with the case's distribution of that member's
//! length error (its mean and variance): a deterministic effect (gravity, temperature) leaves
//! it unchanged, a length effect does not. The term treats the member measurements as
//! independent of the node measurements, which is exact only when they come from different
//! specimens; with the same specimens it overstates their weight slightly.

use crate::comparison::measured::MemberData;
use crate::comparison::simulate::Simulation;
use crate::errors::DiagnoseError;
use nalgebra::{DMatrix, DVector};

/// The floor τ of the predicted standard deviation (defined with the simulation it floors,
/// which the comparison's statistics read too).
pub use crate::comparison::simulate::RESOLUTION;

/// The specimens' mean and covariance.
#[derive(Debug, Clone)]
pub struct DataSummary {
    /// Specimens n.
    pub n: usize,
    /// Mean ȳ \[mm\].
    pub mean: DVector<f64>,
    /// Covariance S_y, divisor n \[mm²\].
    pub cov: DMatrix<f64>,
}

/// Mean and covariance (divisor `n − ddof`) of `n × d` row-major data.
pub fn moments(x: &[f64], n: usize, d: usize, ddof: usize) -> (DVector<f64>, DMatrix<f64>) {
    let mut mean = DVector::zeros(d);
    for row in x.chunks_exact(d) {
        for j in 0..d {
            mean[j] += row[j];
        }
    }
    mean /= n as f64;
    let mut cov = DMatrix::zeros(d, d);
    let mut c = vec![0.0; d];
    for row in x.chunks_exact(d) {
        for j in 0..d {
            c[j] = row[j] - mean[j];
        }
        for a in 0..d {
            for b in 0..=a {
                cov[(a, b)] += c[a] * c[b];
            }
        }
    }
    let div = (n - ddof).max(1) as f64;
    for a in 0..d {
        for b in 0..=a {
            let v = cov[(a, b)] / div;
            cov[(a, b)] = v;
            cov[(b, a)] = v;
        }
    }
    (mean, cov)
}

impl DataSummary {
    /// The summary of `n × d` displacements.
    pub fn new(y: &[f64], n: usize, d: usize) -> Self {
        let (mean, cov) = moments(y, n, d, 0);
        Self { n, mean, cov }
    }
}

/// ln det Σ from Σ's Cholesky factor L: 2·Σⱼ ln Lⱼⱼ.
pub(crate) fn log_det(chol: &nalgebra::Cholesky<f64, nalgebra::Dyn>) -> f64 {
    2.0 * chol
        .l_dirty()
        .diagonal()
        .iter()
        .map(|v| v.ln())
        .sum::<f64>()
}

/// A case's Gaussian predictive distribution of one specimen.
#[derive(Debug, Clone)]
pub struct Gaussian {
    /// μ \[mm\].
    pub mean: DVector<f64>,
    /// Σ \[mm²\].
    pub cov: DMatrix<f64>,
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    log_det: f64,
}

impl Gaussian {
    /// From a simulation; `sigma_m` the instrument's standard deviation \[mm\].
    pub fn from_simulation(sim: &Simulation, sigma_m: f64) -> Result<Self, DiagnoseError> {
        let (mean, mut cov) = moments(&sim.x, sim.n, sim.d, 1);
        let extra = sigma_m * sigma_m + RESOLUTION * RESOLUTION;
        for j in 0..sim.d {
            cov[(j, j)] += extra;
        }
        let chol =
            nalgebra::Cholesky::new(cov.clone()).ok_or_else(|| DiagnoseError::Simulation {
                what: "the predictive covariance".into(),
                message: "not positive definite".into(),
            })?;
        let log_det = log_det(&chol);
        Ok(Self {
            mean,
            cov,
            chol,
            log_det,
        })
    }

    /// Each specimen's term `ln N(yᵢ; μ, Σ)` of ℓ, for `n × d` displacements.
    pub fn log_densities(&self, y: &[f64]) -> Vec<f64> {
        let d = self.mean.len();
        let c = -0.5 * (d as f64 * (2.0 * std::f64::consts::PI).ln() + self.log_det);
        y.chunks_exact(d)
            .map(|row| {
                let diff =
                    DVector::from_iterator(d, row.iter().zip(self.mean.iter()).map(|(a, b)| a - b));
                let z = self
                    .chol
                    .l_dirty()
                    .solve_lower_triangular(&diff)
                    .expect("L is regular");
                c - 0.5 * z.norm_squared()
            })
            .collect()
    }

    /// ℓ of the specimens (module doc).
    pub fn log_likelihood(&self, data: &DataSummary) -> f64 {
        let d = self.mean.len() as f64;
        let diff = &data.mean - &self.mean;
        let maha = diff.dot(&self.chol.solve(&diff));
        let trace = self.chol.solve(&data.cov).trace();
        -0.5 * data.n as f64 * (d * (2.0 * std::f64::consts::PI).ln() + self.log_det + trace + maha)
    }
}

/// The member terms of ℓ (module doc), one per observation, for the case's per-member
/// distributions. The observations name members of the `measured` model (the baseline's);
/// a derived case's model may number them differently (backlash adds joints and nodes), so
/// they are found by id.
pub fn member_log_likelihood(
    case: &truss_job::job::Case,
    measured: &truss_core::Model,
    data: &MemberData,
    sigma_m: f64,
) -> Vec<f64> {
    let floor = sigma_m * sigma_m + RESOLUTION * RESOLUTION;
    let index = |m: usize| {
        let id = &measured.members()[m].id;
        match case.model.members().get(m) {
            Some(member) if &member.id == id => Some(m),
            _ => case.model.member_index(id),
        }
    };
    data.observations
        .iter()
        .map(|&(m, e)| {
            let (mean, var) = index(m)
                .and_then(|i| case.member_errors[i])
                .map_or((0.0, 0.0), |d| (d.mean(), d.std_dev().powi(2)));
            let v = var + floor;
            -0.5 * ((2.0 * std::f64::consts::PI * v).ln() + (e - mean).powi(2) / v)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For d = 1 the formula is the sum of normal log densities.
    #[test]
    fn one_dimension_is_the_normal_log_density() {
        let sim = Simulation {
            n: 4,
            d: 1,
            x: vec![1.0, 2.0, 3.0, 4.0],
            ..Simulation::default()
        };
        let g = Gaussian::from_simulation(&sim, 0.5).unwrap();
        let var = 5.0 / 3.0 + 0.25 + RESOLUTION * RESOLUTION;
        let y = [2.0, 4.5, 0.0];
        let data = DataSummary::new(&y, 3, 1);
        let direct: f64 = y
            .iter()
            .map(|v| -0.5 * ((2.0 * std::f64::consts::PI * var).ln() + (v - 2.5).powi(2) / var))
            .sum();
        assert!((g.log_likelihood(&data) - direct).abs() < 1e-12);
        let sum: f64 = g.log_densities(&y).iter().sum();
        assert!((sum - direct).abs() < 1e-12);
    }
}
