//! A solve started from a nearby sample's anchor (`Solver::set_start`, the diagnosis's
//! finite differences) against the same solve from rest: the same equilibrium within the
//! solver's tolerance, for fewer factorisations; a start serves one solve; a start of the
//! wrong size is refused. Independent of how the start is used inside: each check compares
//! two full solves of the same problem.

use crate::common::*;
use truss_core::prism::{BacklashOptions, PrismOptions};
use truss_core::solver::Perturbation;
use truss_core::{Model, SolveError, SolveOptions, Solver};

/// The paper's prism with pin joints (§4.2.3, solved at the limit of its one-sided
/// members), and without (its tilt framed by bars, solved by Newton alone).
fn models() -> [(&'static str, Model); 2] {
    let pinned = PrismOptions {
        backlash: Some(BacklashOptions::default()),
        ..PrismOptions::with_stages(5)
    };
    [
        ("pin joints", pinned.model().unwrap()),
        ("rigid", PrismOptions::with_stages(5).model().unwrap()),
    ]
}

/// On 40 draws of the Fig. 16 case at σ = 0.033 mm (the three-effect diagnosis's truss:
/// most diagonals slack, most joints bearing), each sample is solved from rest, then its
/// length errors and clearances are scaled by 1.001 (a finite-difference step of the
/// diagnosis) and the new problem is solved twice: from rest, and from the first solve's
/// anchor. The two agree on every node's displacement within 1e-6 of the largest (measured:
/// 3e-8 of θ_P at worst on 300 such draws), and the solves from the anchor take fewer
/// factorisations in all.
#[test]
fn a_start_from_a_nearby_sample_reaches_the_same_equilibrium_for_less_work() {
    for (name, model) in models() {
        let mut rng = Normals::new(23);
        let options = SolveOptions {
            holding: false,
            ..SolveOptions::default()
        };
        let mut first = Solver::new(&model, options.clone()).unwrap();
        let mut cold = Solver::new(&model, options.clone()).unwrap();
        let mut warm = Solver::new(&model, options).unwrap();
        let (mut from_rest, mut from_anchor) = (0, 0);
        for sample in 0..40 {
            let (errors, clearances) = fig16_draw(&model, 0.033, &mut rng);
            first
                .solve_perturbed(Perturbation {
                    length_errors: &errors,
                    clearances: &clearances,
                    ..Perturbation::default()
                })
                .unwrap();
            let errors: Vec<f64> = errors.iter().map(|e| 1.001 * e).collect();
            let clearances: Vec<f64> = clearances.iter().map(|c| 1.001 * c).collect();
            let p = Perturbation {
                length_errors: &errors,
                clearances: &clearances,
                ..Perturbation::default()
            };
            from_rest += cold.solve_perturbed(p).unwrap().factorisations;
            warm.set_start(first.anchor()).unwrap();
            from_anchor += warm.solve_perturbed(p).unwrap().factorisations;
            let nodes = 0..model.nodes().len();
            let largest = nodes
                .clone()
                .flat_map(|n| cold.displacement(n))
                .fold(0.0, |m: f64, x| m.max(x.abs()));
            for n in nodes {
                let (a, b) = (cold.displacement(n), warm.displacement(n));
                for k in 0..3 {
                    assert!(
                        (a[k] - b[k]).abs() <= 1e-6 * largest,
                        "{name}, sample {sample}, node {n}: {a:?} from rest, {b:?} from the anchor"
                    );
                }
            }
        }
        assert!(
            from_anchor < from_rest,
            "{name}: {from_anchor} factorisations from the anchors, {from_rest} from rest"
        );
    }
}

/// A start serves the next solve only: the solve after it, without one, gives the same
/// bits as a solver that never had a start.
#[test]
fn a_start_serves_one_solve() {
    for (name, model) in models() {
        let mut rng = Normals::new(5);
        let (a, b) = (
            fig16_draw(&model, 0.0067, &mut rng),
            fig16_draw(&model, 0.0067, &mut rng),
        );
        let solve = |solver: &mut Solver, d: &(Vec<f64>, Vec<f64>)| {
            solver
                .solve_perturbed(Perturbation {
                    length_errors: &d.0,
                    clearances: &d.1,
                    ..Perturbation::default()
                })
                .unwrap()
        };
        let mut fresh = Solver::new(&model, SolveOptions::default()).unwrap();
        let mut started = Solver::new(&model, SolveOptions::default()).unwrap();
        solve(&mut fresh, &a);
        let anchor = fresh.anchor().to_vec();
        started.set_start(&anchor).unwrap();
        solve(&mut started, &a);
        let expected = solve(&mut fresh, &b);
        let got = solve(&mut started, &b);
        assert_eq!(
            (expected.iterations, expected.factorisations),
            (got.iterations, got.factorisations),
            "{name}"
        );
        for n in 0..model.nodes().len() {
            assert_eq!(
                fresh.displacement(n).map(f64::to_bits),
                started.displacement(n).map(f64::to_bits),
                "{name}, node {n}"
            );
        }
    }
}

/// A start must have one finite displacement per free degree of freedom.
#[test]
fn a_start_of_the_wrong_size_or_not_finite_is_refused() {
    let (_, model) = &models()[0];
    let mut solver = Solver::new(model, SolveOptions::default()).unwrap();
    let n = solver.structure().free_dofs();
    assert_eq!(solver.anchor().len(), n);
    for bad in [vec![0.0; n - 1], vec![0.0; n + 1], {
        let mut v = vec![0.0; n];
        v[3] = f64::NAN;
        v
    }] {
        match solver.set_start(&bad) {
            Err(SolveError::Input(message)) => assert!(message.contains(&n.to_string())),
            other => panic!("{other:?} for a start of {} entries", bad.len()),
        }
    }
    solver.set_start(&vec![0.0; n]).unwrap();
}
