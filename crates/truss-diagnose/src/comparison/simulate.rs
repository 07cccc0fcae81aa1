//! Running a derived case: `N` samples solved by the job crate's sample engine
//! ([`truss_job::engine`]: the same draws and solver as a shard run, results in index
//! order), each sample's displacements at the measured coordinates collected, and, when
//! asked, the instrument's noise added and the top surface's angles computed from the noisy
//! positions, exactly as they are from a measured specimen.
//!
//! ## Measurement noise
//!
//! The value added to coordinate `j` of sample `k` is `σ_m·z` with `z` a standard normal
//! from the Box–Muller transform of two counter-based uniforms
//! (`truss_stats::rng`, stream `Synthetic`, key `(noise seed, k)`, counters `2j`, `2j + 1`):
//! a pure function of (seed, k, j), so every derived case sees the same noise (common random
//! numbers here too) and the result does not depend on the thread count.

use crate::comparison::measured::Coordinate;
use crate::errors::DiagnoseError;
use truss_core::SolveOptions;
use truss_core::measure::distortion;
use truss_job::Engine;
use truss_job::Job;
use truss_job::solve::Outcome;
use truss_stats::rng::{Stream, bits, box_muller, open01, replicate_key};

/// The floor τ of the predicted standard deviation of every coordinate \[mm\]: 0.1 µm, below
/// any instrument's resolution for trusses of this size, and large against the solver's
/// error (1e-12 relative).
pub const RESOLUTION: f64 = 1e-4;

/// The simulated samples of one case.
#[derive(Debug, Clone, Default)]
pub struct Simulation {
    /// Converged samples `N`.
    pub n: usize,
    /// Coordinates per sample `d`.
    pub d: usize,
    /// `N × d` displacements at the coordinates, noise-free \[mm\].
    pub x: Vec<f64>,
    /// `N × d` with the instrument's noise (empty unless asked) \[mm\].
    pub x_noisy: Vec<f64>,
    /// tan θ_x of the noisy positions (empty unless asked).
    pub tan_x: Vec<f64>,
    /// tan θ_y of the noisy positions.
    pub tan_y: Vec<f64>,
    /// θ_P of the noisy positions \[rad\].
    pub theta_p: Vec<f64>,
    /// The sample index of each converged row (rows of `x`): the key of its simulated
    /// gauge noise in [`crate::likelihood::conditional`].
    pub indices: Vec<u64>,
    /// Members per sample in `errors`: the case model's.
    pub members: usize,
    /// `N × members` length errors each converged sample drew \[mm\] (rows as `x`, the case
    /// model's member order, thermal length changes not added): the member measurements'
    /// simulated counterparts in [`crate::likelihood::conditional`], kept from the solve
    /// rather than drawn again.
    pub errors: Vec<f64>,
    /// Samples whose solve failed (left out).
    pub failed: usize,
    /// The first failure's reason.
    pub first_failure: Option<String>,
}

/// What to simulate besides the noise-free displacements.
#[derive(Debug, Clone, Copy)]
pub struct Noise {
    /// Instrument standard deviation σ_m \[mm\].
    pub sigma: f64,
    /// Seed of the noise.
    pub seed: u64,
}

/// A standard normal from (seed, k, j); see the module doc.
pub fn noise_normal(seed: u64, k: u64, j: u64) -> f64 {
    let key = replicate_key(seed, Stream::Synthetic, k);
    let u1 = open01(bits(key, 2 * j));
    let u2 = open01(bits(key, 2 * j + 1));
    box_muller(u1, u2)
}

/// Index of each top-surface node's x, y, z in `coords`, if they are all there.
pub fn top_indices(coords: &[Coordinate], top: [usize; 3]) -> Option<[[usize; 3]; 3]> {
    let find =
        |node: usize, axis: usize| coords.iter().position(|c| c.node == node && c.axis == axis);
    let mut out = [[0; 3]; 3];
    for (row, &node) in out.iter_mut().zip(top.iter()) {
        for (axis, slot) in row.iter_mut().enumerate() {
            *slot = find(node, axis)?;
        }
    }
    Some(out)
}

struct Row {
    x: Vec<f64>,
    errors: Vec<f64>,
    failure: Option<String>,
}

/// Simulates samples `0..samples` of the job's only case at `coords` on `threads` threads
/// (the result does not depend on them); with `noise`, also the noisy coordinates and the
/// top surface's angles (`top` gives each top node's x, y, z index in `coords`).
pub fn simulate(
    job: &Job,
    coords: &[Coordinate],
    samples: usize,
    noise: Option<(Noise, [[usize; 3]; 3])>,
    threads: usize,
) -> Result<Simulation, DiagnoseError> {
    let d = coords.len();
    // The coordinates name nodes of the baseline's model; a derived case's model may number
    // them differently (backlash adds hole nodes), so they are found by id.
    let model = &job.cases[0].model;
    let nodes: Vec<(usize, usize)> = coords
        .iter()
        .map(|c| match model.nodes().get(c.node) {
            Some(n) if n.id == c.node_id => Ok((c.node, c.axis)),
            _ => model
                .node_index(&c.node_id)
                .map(|i| (i, c.axis))
                .ok_or_else(|| DiagnoseError::Simulation {
                    what: job.cases[0].name.clone(),
                    message: format!("the derived model has no node {:?}", c.node_id),
                }),
        })
        .collect::<Result<_, _>>()?;
    // The comparison reads displacements only: the holding force, a quarter of a sample
    // whose diagonals are taut, is not computed (the displacements are the same bits).
    let engine = Engine::new(job, threads).with_options(SolveOptions {
        holding: false,
        ..SolveOptions::default()
    });
    let rows = engine.map(0..samples as u64, |solver, result| {
        if let Outcome::Failed(reason) = result.outcome {
            return Row {
                x: Vec::new(),
                errors: Vec::new(),
                failure: Some(reason),
            };
        }
        let errors = solver.last_drawn_errors().to_vec();
        let solver = solver.solver(0).expect("the case was solved");
        Row {
            x: nodes
                .iter()
                .map(|&(node, axis)| solver.displacement(node)[axis])
                .collect(),
            errors,
            failure: None,
        }
    });
    let case = &job.cases[0];
    let mut sim = Simulation {
        d,
        members: model.members().len(),
        ..Simulation::default()
    };
    for (k, row) in rows.into_iter().enumerate() {
        if let Some(reason) = row.failure {
            sim.failed += 1;
            sim.first_failure.get_or_insert(reason);
            continue;
        }
        if let Some((noise, top)) = &noise {
            let noisy: Vec<f64> = row
                .x
                .iter()
                .enumerate()
                .map(|(j, v)| v + noise.sigma * noise_normal(noise.seed, k as u64, j as u64))
                .collect();
            let t = model.top_surface().expect("checked when reading the data");
            let nominal = t.nodes.map(|i| model.nodes()[i].xyz);
            let u = top.map(|ix| ix.map(|j| noisy[j]));
            let dist = distortion(nominal, u, t.reference_normal);
            sim.tan_x.push(dist.tan_theta_x);
            sim.tan_y.push(dist.tan_theta_y);
            sim.theta_p.push(dist.theta_p);
            sim.x_noisy.extend(noisy);
        }
        sim.x.extend(row.x);
        sim.errors.extend(row.errors);
        sim.indices.push(k as u64);
        sim.n += 1;
    }
    if sim.n == 0 || sim.failed * 20 > samples {
        return Err(DiagnoseError::Simulation {
            what: case.name.clone(),
            message: format!(
                "{} of {samples} samples failed (first: {})",
                sim.failed,
                sim.first_failure.as_deref().unwrap_or("-")
            ),
        });
    }
    Ok(sim)
}
