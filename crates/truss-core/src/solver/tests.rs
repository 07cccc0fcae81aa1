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
    let mut next = uniform(seed);
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

/// Numbers in [−0.5, 0.5) from a linear congruential generator seeded by `seed`.
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed;
    move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }
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

/// SplitMix64 + Box–Muller, as in the benchmark (`benches/solve.rs`): its samples (also
/// the batched path's tests' stream).
pub(super) struct Normals(pub(super) u64);

impl Normals {
    pub(super) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub(super) fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
}

/// Sample `index` of the benchmark's path probe (`-- --paths`): the §3.4 prism of `stages`
/// stages, σ = 0.0667 mm on battens and longerons.
fn probe_sample(stages: usize, index: usize) -> (crate::Model, Vec<f64>) {
    let model = PrismOptions::with_stages(stages).model().unwrap();
    let errors = nth_sample(&model, 34 + stages as u64, 0.0666666666666667, index);
    (model, errors)
}

/// The length errors of sample `index` of the stream `seed` for `model`: σ·N(0, 1) on
/// battens and longerons, none on diagonals, drawn in member order sample after sample (as
/// the benchmark draws them).
fn nth_sample(model: &crate::Model, seed: u64, sigma: f64, index: usize) -> Vec<f64> {
    let mut rng = Normals(seed);
    let mut errors = vec![];
    for _ in 0..=index {
        errors = model
            .members()
            .iter()
            .map(|m| {
                if m.group == "diagonal" {
                    0.0
                } else {
                    sigma * rng.normal()
                }
            })
            .collect();
    }
    errors
}

/// The equilibrium is not always unique: sample 293 of the 10-stage path probe has two
/// stable equilibria with the same number of slack cables, about 1e-5 of the model apart,
/// separated by a ridge of the energy. The default solver reaches the higher one, the
/// solver without factorisation reuse (another path, the same convergence test) the lower
/// one. Both are converged to the floor; no tolerance decides between them. A faster path
/// may land in either: the results of such samples depend on the path (θ_P by 5e-4
/// relative here). If both solvers come to agree, reach the other state another way
/// before changing this test: the point is the energy along the segment between them.
/// Starting from the linearised solution does not decide between them either (see
/// [`descents_from_the_linearised_solution_end_in_different_equilibria`]).
#[test]
fn a_sample_with_two_stable_equilibria() {
    let (model, errors) = probe_sample(10, 293);
    let mut a = Solver::new(&model, SolveOptions::default()).unwrap();
    let other = SolveOptions {
        reuse_factorisation: false,
        ..SolveOptions::default()
    };
    let mut b = Solver::new(&model, other).unwrap();
    let (ra, rb) = (a.solve(&errors).unwrap(), b.solve(&errors).unwrap());
    let (ta, tb) = (
        a.distortion().unwrap().theta_p,
        b.distortion().unwrap().theta_p,
    );
    assert!(
        (ta - tb).abs() > 1e-4 * ta,
        "the two paths now agree (θ_P {ta} and {tb}): see this test's doc"
    );
    assert_eq!(ra.slack_cables, rb.slack_cables);
    let (ua, ub) = (a.work.u.clone(), b.work.u.clone());
    let n = a.structure.free;
    // Π along u(t) = u_a + t·(u_b − u_a): both ends are equilibria (r ≈ 0), and
    // dΠ/dt = r·(u_b − u_a) rises from 0 at t = 0 (a minimum along the line), changes sign
    // once (the ridge), and returns to 0 at t = 1.
    let mut energies = vec![];
    let mut slopes = vec![];
    let steps = 20;
    for t in 0..=steps {
        let t = t as f64 / steps as f64;
        let u: Vec<f64> = ua.iter().zip(&ub).map(|(x, y)| x + t * (y - x)).collect();
        let (r, pi) = residual_and_energy(&mut a, &u);
        let slope: f64 = (0..n).map(|i| r[i] * (ub[i] - ua[i])).sum();
        energies.push(pi);
        slopes.push(slope);
    }
    let (pa, pb) = (energies[0], energies[steps]);
    let ridge = energies.iter().copied().fold(f64::MIN, f64::max);
    // The energies' rounding noise is about 1e-11 of Π (≈ 36 N·mm): 4e-10 N·mm.
    let noise = 1e-11 * pa.abs();
    assert!(
        ridge > pa.max(pb) + 1e4 * noise,
        "a ridge between them: Π {pa} and {pb} at the ends, at most {ridge} between"
    );
    assert!(
        (pa - pb).abs() > 1e4 * noise,
        "distinct energies: {pa} and {pb}"
    );
    let peak = 1 + slopes[1..].iter().position(|&d| d < 0.0).unwrap();
    assert!(
        slopes[1..peak].iter().all(|&d| d > 0.0) && slopes[peak..steps].iter().all(|&d| d < 0.0),
        "one ridge: {slopes:?}"
    );
    let scale = slopes.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    assert!(slopes[0].abs() < 1e-6 * scale && slopes[steps].abs() < 1e-6 * scale);
}

/// Sets the sample of `errors` and returns the exact linearised solution `u_L` (step 1).
fn linearised_start(solver: &mut Solver, errors: &[f64]) -> Vec<f64> {
    solver
        .set_sample(Perturbation {
            length_errors: errors,
            ..Perturbation::default()
        })
        .unwrap();
    let _ = lanes::finish(solver.start(lanes::Kernels::OneSample));
    solver.work.u.clone()
}

/// A slow descent from `u`: explicit Euler steps `u += α·d`, each at most `rho` (relative
/// to max |u|) long, along `d = −P(u)⁻¹·r(u)` until `‖r‖∞ ≤ 1e-12·F`. With
/// `newton_metric`, `P = K(u) + μ·diag K(u)` (the true tangent with the smallest Levenberg
/// shift μ of 0, 1e-9, 1e-8, … that is positive definite: a damped Newton flow); otherwise
/// `P = K₀`, the all-taut nominal stiffness (a preconditioned gradient flow). Each step
/// lowers Π to first order, so the path is a continuous descent from `u`. `None` if it does
/// not settle within the step budget.
fn slow_descent(
    solver: &mut Solver,
    mut u: Vec<f64>,
    rho: f64,
    newton_metric: bool,
) -> Option<Vec<f64>> {
    let n = solver.structure.free;
    let rho = rho * evaluate::max_abs(&u[..n]);
    let (mut r, mut d) = (vec![0.0; n + 1], vec![0.0; n + 1]);
    for _ in 0..2_000_000u32 {
        let eval = evaluate(
            &solver.structure,
            &solver.sample.members,
            &solver.sample.loads,
            &u,
            &mut r,
            &mut solver.work.states,
        );
        if eval.residual <= 1e-12 * eval.force_scale.max(solver.sample.force_ref) {
            return Some(u);
        }
        for i in 0..n {
            d[i] = -r[i];
        }
        let cap: f64 = if newton_metric {
            solver.work.u.copy_from_slice(&u);
            solver.update_slack();
            solver
                .factor
                .factor_slack
                .copy_from_slice(&solver.work.slack);
            solver.step.pinned.fill(false);
            let mut shift = 0.0;
            loop {
                solver.assemble_model();
                solver.factor.k.scale_diagonal(1.0 + shift);
                if solver.factor.k.factor().is_ok() {
                    break;
                }
                shift = if shift == 0.0 { 1e-9 } else { 10.0 * shift };
            }
            solver.factor.k.solve_in_place(&mut d[..n]);
            1.0
        } else {
            solver.structure.nominal.solve_in_place(&mut d[..n]);
            0.5 // explicit Euler is stable for steps below 2/λ_max(K₀⁻¹K) ≈ 2
        };
        let alpha = cap.min(rho / evaluate::max_abs(&d[..n]));
        for i in 0..n {
            u[i] += alpha * d[i];
        }
    }
    None
}

/// "The equilibrium reached by energy descent from the linearised solution `u_L`" does not
/// single out one state for such a sample: `u_L` lies far above the ridge between the two
/// equilibria of [`a_sample_with_two_stable_equilibria`] (Π(u_L) exceeds both by about 40
/// times the ridge's height), so the sublevel set `{Π ≤ Π(u_L)}` holds both in one
/// connected piece, and two slow continuous descents from `u_L` — a damped Newton flow and
/// a `K₀`-preconditioned gradient flow, steps of at most 1e-3 of the displacements — end in
/// different ones. Slow (a quarter of a million gradient steps): run with `--ignored`.
#[test]
#[ignore]
fn descents_from_the_linearised_solution_end_in_different_equilibria() {
    let (model, errors) = probe_sample(10, 293);
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let n = solver.structure.free;
    let u_l = linearised_start(&mut solver, &errors);
    let newton = slow_descent(&mut solver, u_l.clone(), 1e-3, true).expect("Newton flow settles");
    let gradient =
        slow_descent(&mut solver, u_l.clone(), 1e-3, false).expect("gradient flow settles");
    let apart = (0..n)
        .map(|i| (newton[i] - gradient[i]).abs())
        .fold(0.0, f64::max);
    let scale = evaluate::max_abs(&newton[..n]);
    assert!(
        apart > 1e-2 * scale,
        "the two descents agree: {apart} mm apart"
    );
    let (pl, pn, pg) = (
        energy_at(&mut solver, &u_l),
        energy_at(&mut solver, &newton),
        energy_at(&mut solver, &gradient),
    );
    let mut ridge = f64::MIN;
    for t in 0..=40 {
        let t = t as f64 / 40.0;
        let u: Vec<f64> = newton
            .iter()
            .zip(&gradient)
            .map(|(x, y)| x + t * (y - x))
            .collect();
        ridge = ridge.max(energy_at(&mut solver, &u));
    }
    let height = ridge - pn.max(pg);
    assert!(
        height > 1e4 * 1e-11 * pn.abs(),
        "a ridge between them: {height} N·mm"
    );
    assert!(
        pl - ridge > 10.0 * height,
        "u_L above the ridge: Π(u_L) {pl}, ridge {ridge}, ends {pn} and {pg} N·mm"
    );
}

fn energy_at(solver: &mut Solver, u: &[f64]) -> f64 {
    residual_and_energy(solver, u).1
}

/// The length errors of sample `index` of the benchmark's stream (`benches/solve.rs`:
/// seed 2024, σ = 0.0063 mm on battens and longerons) for `model`.
fn bench_sample(model: &crate::Model, index: usize) -> Vec<f64> {
    nth_sample(model, 2024, 0.0063, index)
}

/// Step 1 with a slack set too large for the capacitance matrix (pin joints in free play,
/// 40 or more slack halves) is the banded active-set iteration; it must find the linearised
/// solution the Woodbury iteration finds, on samples near a mechanism where a cable at its
/// kink used to flip at every piece (the iteration then failed, and Newton from zero met a
/// mechanism).
#[test]
fn the_banded_linearised_start_finds_the_woodbury_solution() {
    // At a ratio of 1e-4: at the limit's 1e-7 the linearised problem near a mechanism is a
    // thousand times worse conditioned, and the two solutions agree to its rounding only.
    let model = PrismOptions {
        backlash: Some(BacklashOptions::default()),
        compression_ratio: 1e-4,
        ..PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let structure = Arc::clone(&solver.structure);
    let n = structure.free;
    let mut woodbury = structure.basis.clone().unwrap();
    woodbury.max_slack = usize::MAX;
    for index in [3462, 6250] {
        let errors = bench_sample(&model, index);
        solver
            .set_sample(Perturbation {
                length_errors: &errors,
                ..Perturbation::default()
            })
            .unwrap();
        for (st, m) in solver.work.stretch.iter_mut().zip(&solver.sample.members) {
            *st = m.initial_stretch;
        }
        let mut active = crate::linearised::ActiveSet::new(woodbury.cables.len());
        let mut u = vec![0.0; n + 1];
        active
            .solve_linearised(
                &structure,
                &woodbury,
                &solver.work.stretch,
                &solver.sample.loads,
                &mut u,
            )
            .unwrap();
        assert!(active.slack.len() > structure.basis.as_ref().unwrap().max_slack);
        solver.linearised_banded(&structure, &mut 0).unwrap();
        let scale = evaluate::max_abs(&u[..n]);
        let apart = (0..n)
            .map(|i| (u[i] - solver.work.u[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            apart <= 1e-7 * scale,
            "sample {index}: {apart} mm apart of {scale} mm"
        );
        solver.solve(&errors).unwrap();
    }
}

/// The displacements' rounding floor of the force test never decides a solve of the
/// paper's 5-stage prism: at the converged point of 200 samples at σ = 6.3 µm and 200 at
/// 66.7 µm it is below a fifth of the force floor `residual_floor·F`, so the paper's results
/// do not depend on it (it is there for tall towers; see the integration test
/// `theta_of_a_tall_tower_is_resolved_to_better_than_1e9`).
#[test]
fn the_rounding_floor_is_below_the_force_floor_for_the_paper_prism() {
    let model = PrismOptions::with_stages(5).model().unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let mut worst: f64 = 0.0;
    for (seed, sigma) in [(7, 0.0063), (8, 0.0666666666666667)] {
        for index in 0..200 {
            solver
                .solve(&nth_sample(&model, seed, sigma, index))
                .unwrap();
            let force = solver
                .work
                .states
                .iter()
                .fold(0.0f64, |a, s| a.max(s.force.abs()));
            let floor = solver.options.residual_floor * force.max(solver.sample.force_ref);
            let u_max = evaluate::max_abs(&solver.work.u[..solver.structure.free]);
            worst = worst.max(solver.rounding_floor(u_max) / floor);
        }
    }
    println!("largest rounding floor / force floor: {worst:.3}");
    assert!(worst < 0.2, "{worst}");
}

/// The chord steps' secant first trial ([`SolveOptions::chord_secant`]) saves iterations
/// on the paper's prism: over 300 samples of the benchmark's stream, at least 0.2 fewer on
/// average (of about 5.4), and the same answers (θ_P within 1e-9).
#[test]
fn the_chord_secant_saves_iterations() {
    let model = PrismOptions::with_stages(5).model().unwrap();
    let plain = SolveOptions {
        chord_secant: false,
        ..SolveOptions::default()
    };
    let mut with = Solver::new(&model, SolveOptions::default()).unwrap();
    let mut without = Solver::new(&model, plain).unwrap();
    let (mut saved, mut worst) = (0i64, 0.0f64);
    let n = 300;
    for index in 0..n {
        let errors = bench_sample(&model, index);
        let a = with.solve(&errors).unwrap().iterations;
        let b = without.solve(&errors).unwrap().iterations;
        saved += i64::from(b) - i64::from(a);
        let (ta, tb) = (
            with.distortion().unwrap().theta_p,
            without.distortion().unwrap().theta_p,
        );
        worst = worst.max((ta / tb - 1.0).abs());
    }
    let mean = saved as f64 / n as f64;
    println!("iterations saved per solve: {mean:.3}; θ_P apart by at most {worst:.1e}");
    assert!(mean >= 0.2, "{mean}");
    assert!(worst <= 1e-9, "{worst:.2e}");
}

/// A model step's later pieces assemble again only the slots of the cables that switched
/// (`Solver::reassemble_model`): checked against a whole assembly of the same slack set,
/// bit for bit, over rounds of random switches (several at once, and back again), on the
/// prism with and without backlash joints and on one with a partly fixed node (whose links
/// are masked and whose fixed direction is an identity row), with some cables pinned.
#[test]
fn reassembling_the_switched_cables_gives_the_whole_assembly_bit_for_bit() {
    let partly_fixed = {
        let mut file = PrismOptions::with_stages(3).file().unwrap();
        file.supports.push(crate::model_file::SupportSpec {
            node: "n1.0".into(),
            fixed: "x".into(),
        });
        crate::Model::new(file).unwrap()
    };
    let mut solvers: Vec<(Solver, Vec<f64>)> = cases()
        .into_iter()
        .map(|(seed, backlash)| solver_with(seed, backlash))
        .collect();
    let partly = Solver::new(&partly_fixed, SolveOptions::default()).unwrap();
    let n = partly.structure.free;
    let u: Vec<f64> = (0..=n)
        .map(|i| {
            if i < n {
                1e-3 * ((i * 7 % 11) as f64 - 5.0)
            } else {
                0.0
            }
        })
        .collect();
    assert!(partly.structure.members.iter().any(|c| c.link.masked));
    assert!(!partly.structure.identity_rows.is_empty());
    solvers.push((partly, u));
    let mut x = 12345u64;
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 33) as usize
    };
    for (solver, u) in &mut solvers {
        residual_and_energy(solver, u);
        solver.update_slack();
        let cables: Vec<usize> = (0..solver.structure.members.len())
            .filter(|&m| solver.structure.members[m].is_cable)
            .collect();
        let slots = solver.factor.kept.storage.len();
        let bandwidth = solver.structure.bandwidth();
        for &m in cables.iter().step_by(5) {
            solver.step.pinned[m] = true;
        }
        solver
            .factor
            .factor_slack
            .copy_from_slice(&solver.work.slack);
        solver.assemble_model_keeping(true);
        let mut switched = 0;
        for round in 0..12 {
            for _ in 0..1 + round % 4 {
                let m = cables[next() % cables.len()];
                solver.factor.factor_slack[m] = !solver.factor.factor_slack[m];
                switched += 1;
            }
            solver.reassemble_model(false);
            let again = solver.factor.k.storage_mut().to_vec();
            solver.assemble_model();
            let whole = solver.factor.k.storage_mut().to_vec();
            assert_eq!(again.len(), slots);
            for (slot, (a, w)) in again.iter().zip(&whole).enumerate() {
                // A diagonal block's upper triangle is never written nor read.
                let diagonal = slot % (bandwidth + 1) == bandwidth;
                for r in 0..3 {
                    for c in 0..if diagonal { r + 1 } else { 3 } {
                        assert_eq!(
                            a[r][c].to_bits(),
                            w[r][c].to_bits(),
                            "slot {slot} ({r}, {c}), round {round}"
                        );
                    }
                }
            }
        }
        assert!(switched > 12);
    }
}

/// The engagement search of the model steps and of the steps at `ρ = 0`
/// ([`Solver::first_to_engage`]) looks only at the one-sided members that reach a row up
/// to the failed pivot's (its direction is zero above it): checked against the search over
/// every member in model order, as it was written before, for directions random up to a
/// row and zero above it, every one-sided member slack, on the prism with and without
/// backlash joints, for every row and both an unbounded and a finite curvature.
#[test]
fn engagement_looks_only_at_the_members_a_failed_pivot_moves_and_finds_the_same_one() {
    fn every_member(solver: &Solver, curvature: f64) -> Option<usize> {
        let n = solver.structure.free;
        let v = &solver.work.scratch;
        let descent = if super::evaluate::dot_n(&solver.work.r[..n], &v[..n]) > 0.0 {
            -1.0
        } else {
            1.0
        };
        for sign in [descent, -descent] {
            let mut first: Option<(f64, usize)> = None;
            for (m, c) in solver.structure.members.iter().enumerate() {
                if !(c.is_cable && solver.factor.factor_slack[m]) {
                    continue;
                }
                let st = &solver.work.states[m];
                let rate = sign * c.sense * solver.elongation_rate(m, v);
                let k =
                    solver.sample.tension[m] * (1.0 - solver.sample.members[m].compression_ratio);
                if rate > 0.0 && k * rate * rate > -curvature {
                    let at = (-c.sense * st.elongation).max(0.0) / rate;
                    if first.is_none_or(|(best, _)| at < best) {
                        first = Some((at, m));
                    }
                }
            }
            if first.is_some() {
                return first.map(|(_, m)| m);
            }
        }
        None
    }
    let mut next = uniform(777);
    let mut found = 0;
    for (seed, backlash) in cases() {
        let (mut solver, u) = solver_with(seed, backlash);
        let (r, _) = residual_and_energy(&mut solver, &u);
        solver.work.r.copy_from_slice(&r);
        let n = solver.structure.free;
        for (m, c) in solver.structure.members.iter().enumerate() {
            solver.factor.factor_slack[m] = c.is_cable;
        }
        let prefix = &solver.structure.one_sided_by_row;
        assert!(prefix.windows(2).all(|w| w[0] < w[1]));
        for row in 0..n {
            for i in 0..=n {
                solver.work.scratch[i] = if i <= row && !is_fixed(&solver, i) {
                    next()
                } else {
                    0.0
                };
            }
            for curvature in [f64::INFINITY, -1e-3] {
                let want = every_member(&solver, curvature);
                assert_eq!(
                    solver.first_to_engage(curvature, row),
                    want,
                    "seed {seed}, row {row}, curvature {curvature}"
                );
                found += usize::from(want.is_some());
            }
        }
    }
    // Most directions engage some cable (else the comparison says little).
    assert!(found > 100, "{found}");
}
