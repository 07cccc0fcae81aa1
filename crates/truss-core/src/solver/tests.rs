//! Unit tests of the assembled system against finite differences: the out-of-balance force
//! is the gradient of the total potential energy, and the tangent is its Jacobian.

use super::evaluate::evaluate;
use super::*;
use crate::prism::{BacklashOptions, PrismOptions};

/// A solver for the 3-stage prism (exact diagonals, so some cables go slack and some stay
/// taut under the errors below) with its state set at a displacement `u` of a few µm; with
/// backlash joints if given (clearances of 2 µm at each longeron end against displacements
/// of ±2.5 µm and length errors of ±5 µm put some longerons on their holes' edges and leave
/// some in their free play).
fn solver_with(seed: u64, backlash: Option<BacklashOptions>) -> (Solver, Vec<f64>) {
    let model = PrismOptions {
        diagonal_length: None,
        backlash,
        ..PrismOptions::with_stages(3)
    }
    .model()
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let mut x = seed;
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    };
    let errors: Vec<f64> = (0..model.members().len()).map(|_| 0.01 * next()).collect();
    solver
        .set_sample(Perturbation {
            length_errors: &errors,
            ..Perturbation::default()
        })
        .unwrap();
    let n = solver.structure.free;
    let mut u = vec![0.0; n + 1];
    for (i, v) in u[..n].iter_mut().enumerate() {
        // Only free directions move (the fixed ones of a partly fixed node have no rows).
        if !is_fixed(&solver, i) {
            *v = 0.005 * next();
        }
    }
    (solver, u)
}

/// Whether unknown `i` is a fixed direction of a partly fixed node (an identity row).
fn is_fixed(solver: &Solver, i: usize) -> bool {
    let (node, axis) = solver.structure.dof_owner[i];
    solver.structure.node_dofs[node][axis as usize] == crate::structure::FIXED
}

fn residual_and_energy(solver: &mut Solver, u: &[f64]) -> (Vec<f64>, f64) {
    let mut r = vec![0.0; u.len()];
    evaluate(
        &solver.structure,
        &solver.sample.members,
        &solver.sample.loads,
        u,
        &mut r,
        &mut solver.work.states,
    );
    solver.work.u.copy_from_slice(u);
    (r, solver.potential_energy())
}

/// Backlash joints with a clearance that some joints' offsets exceed and some do not.
fn joints() -> Option<BacklashOptions> {
    Some(BacklashOptions {
        clearance: 0.002,
        ..BacklashOptions::default()
    })
}

/// The seeds of the finite-difference checks: three without joints, two with.
fn cases() -> [(u64, Option<BacklashOptions>); 5] {
    [
        (1, None),
        (2, None),
        (3, None),
        (4, joints()),
        (5, joints()),
    ]
}

#[test]
fn residual_is_the_energy_gradient() {
    for (seed, backlash) in cases() {
        let (mut solver, u) = solver_with(seed, backlash);
        let (r, _) = residual_and_energy(&mut solver, &u);
        if backlash.is_some() {
            let loose = solver.loose_joint_count() as usize;
            let joints = solver.structure.joints.len();
            assert!(
                loose > 0 && loose < joints,
                "seed {seed}: want joints both bearing and loose, {loose} of {joints} loose"
            );
        }
        let h = 1e-6;
        for i in 0..solver.structure.free {
            let (mut up, mut um) = (u.clone(), u.clone());
            up[i] += h;
            um[i] -= h;
            let (_, ep) = residual_and_energy(&mut solver, &up);
            let (_, em) = residual_and_energy(&mut solver, &um);
            let fd = (ep - em) / (2.0 * h);
            assert!(
                (fd - r[i]).abs() <= 1e-5 * r[i].abs().max(1e-2),
                "seed {seed} row {i}: {fd} vs {}",
                r[i]
            );
        }
    }
}

#[test]
fn tangent_is_the_residual_jacobian() {
    for (seed, backlash) in cases() {
        let (mut solver, u) = solver_with(seed, backlash);
        let (_, _) = residual_and_energy(&mut solver, &u);
        solver.update_slack();
        solver
            .factor
            .factor_slack
            .copy_from_slice(&solver.work.slack);
        solver.assemble_model();
        let n = solver.structure.free;
        let h = 1e-7;
        for j in 0..n {
            let (mut up, mut um) = (u.clone(), u.clone());
            up[j] += h;
            um[j] -= h;
            let (rp, _) = residual_and_energy(&mut solver, &up);
            let (rm, _) = residual_and_energy(&mut solver, &um);
            for i in 0..n {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                let k = if is_fixed(&solver, i) {
                    0.0 // identity rows of fixed directions are not part of the Jacobian
                } else {
                    solver.factor.k.get(i, j)
                };
                let scale = solver.factor.k.get(i, i).abs().max(1.0);
                assert!(
                    (fd - k).abs() <= 1e-6 * scale,
                    "seed {seed} K[{i}][{j}]: fd {fd} vs {k}"
                );
            }
        }
    }
}
