//! Verification against hand-derived solutions.
//!
//! Every case is one-dimensional along x (all members collinear), where the geometrically
//! nonlinear solution is exact in closed form: a member from x_a to x_b has current length
//! `L = x_b − x_a`, force `N = E·A·(L − L₀)/L₀` (tension positive) and the free node's
//! equilibrium is a balance of the two member forces. Units N, mm, MPa.
//!
//! ```text
//!   A ●━━━━━━━ bar 1 ━━━━━━━● B ━━━━━━━ bar 2 (or cable) ━━━━━━━● C
//!   x = 0                    x = L + u                          x = 2L
//!   fixed                    free in x only                     fixed
//! ```

use crate::common::*;
use truss_core::{Model, SolveOptions, Solver};

const L: f64 = 380.0;
const E: f64 = 70_000.0;

fn series(a1: f64, a2: f64, n1: f64, n2: f64, cable2: Option<f64>) -> Model {
    Model::new(file(
        vec![
            node("A", [0.0, 0.0, 0.0]),
            node("B", [L, 0.0, 0.0]),
            node("C", [2.0 * L, 0.0, 0.0]),
        ],
        vec![
            member("1", "A", "B", a1, Some(n1), None),
            member("2", "B", "C", a2, Some(n2), cable2),
        ],
        vec![support("A", "xyz"), support("C", "xyz"), support("B", "yz")],
    ))
    .unwrap()
}

/// A single bar between two fixed supports, made δ too long: no node can move, so it is
/// compressed by N = −E·A·δ/(L + δ) exactly.
#[test]
fn bar_between_two_supports_with_a_length_error() {
    let delta = 0.0123;
    let model = Model::new(file(
        vec![node("A", [0.0, 0.0, 0.0]), node("B", [L, 0.0, 0.0])],
        vec![member("1", "A", "B", 14.9, None, None)],
        vec![support("A", "xyz"), support("B", "xyz")],
    ))
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    solver.solve(&[delta]).unwrap();
    let expected = -E * 14.9 * delta / (L + delta);
    assert!((solver.member_force(0) - expected).abs() <= 1e-12 * expected.abs());
}

/// Two bars in series, errors δ₁ and δ₂: with k_i = E·A_i/(L + δ_i),
/// k₁(u − δ₁) = k₂(−u − δ₂), so u = (k₁δ₁ − k₂δ₂)/(k₁ + k₂) and N = k₁(u − δ₁).
#[test]
fn two_bars_in_series() {
    let (a1, a2, d1, d2) = (14.9, 3.1, 0.01, -0.004);
    let model = series(a1, a2, L + d1, L + d2, None);
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let report = solver.solve(&[0.0, 0.0]).unwrap();
    let (k1, k2) = (E * a1 / (L + d1), E * a2 / (L + d2));
    let u = (k1 * d1 - k2 * d2) / (k1 + k2);
    let n = k1 * (u - d1);
    let got = solver.displacement(1)[0];
    assert!(
        (got - u).abs() <= 1e-12 * u.abs(),
        "u = {got}, expected {u}"
    );
    assert!((solver.member_force(0) - n).abs() <= 1e-10 * n.abs());
    assert!((solver.member_force(1) - n).abs() <= 1e-10 * n.abs());
    assert!(report.residual <= 1e-9, "{report:?}");
}

/// A cable shortened by s pulls the node against a bar: the cable stays taut and, as for
/// two bars, u = −k₂s/(k₁ + k₂) with k₂ = E·A₂/(L − s); tension N = k₂(s − u) − … > 0.
#[test]
fn pre_shortened_cable_is_taut_and_in_tension() {
    let s = 0.02;
    let model = series(14.9, 3.1, L, L - s, Some(1e-5));
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let report = solver.solve(&[0.0, 0.0]).unwrap();
    let (k1, k2) = (E * 14.9 / L, E * 3.1 / (L - s));
    let u = (k1 * 0.0 - k2 * (-s)) / (k1 + k2);
    let tension = k2 * (-u + s);
    assert!((solver.displacement(1)[0] - u).abs() <= 1e-12 * u.abs());
    assert!(solver.member_force(1) > 0.0 && !solver.is_slack(1));
    assert!((solver.member_force(1) - tension).abs() <= 1e-10 * tension);
    assert_eq!(report.slack_cables, 0);
}

/// A cable made too long beside a bar that holds the node: the cable is slack and, with a
/// compression ratio of zero (the paper's), carries nothing. This model's tilt is not
/// framed (it has no top surface), so the solver answers at the limit `r → 0` itself: the
/// cable's force and the node's displacement are zero (to rounding). At a small explicit
/// ratio the series formula of the next test holds: the cable carries `r·k·e`, the bar the
/// opposite, the node moves by that over the bar's stiffness, and at a ratio 1,000 times
/// smaller all three are 1,000 times smaller: they vanish in the limit.
#[test]
fn slack_cable_carries_nothing() {
    // (Relative tolerance: the solve resolves the node to about 1e-11 of the misfit.)
    let solve = |ratio: f64, tolerance: f64| {
        let model = Model::new(file(
            vec![node("A", [0.0, 0.0, 0.0]), node("B", [L, 0.0, 0.0])],
            vec![
                member("bar", "A", "B", 14.9, None, None),
                member("cable", "A", "B", 3.1, Some(L + 0.05), Some(ratio)),
            ],
            vec![support("A", "xyz"), support("B", "yz")],
        ))
        .unwrap();
        let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
        let report = solver.solve(&[0.0, 0.0]).unwrap();
        assert!(solver.is_slack(1));
        assert_eq!(report.slack_cables, 1);
        let (k1, k2) = (E * 14.9 / L, ratio * E * 3.1 / (L + 0.05));
        // Equilibrium of node B: k₁·u + k₂·(u + s) = 0, the cable's stretch s = −0.05 mm.
        let u = k2 * 0.05 / (k1 + k2);
        let cable = k2 * (u - 0.05);
        for (got, want) in [
            (solver.displacement(1)[0], u),
            (solver.member_force(1), cable),
            (solver.member_force(0), -cable),
        ] {
            assert!(
                (got - want).abs() <= tolerance * want.abs().max(1e-12),
                "{got} vs {want}"
            );
        }
        (solver.member_force(1), solver.displacement(1)[0])
    };
    // At the limit: nothing, to 1e-12 N and 1e-12 mm.
    let (force, moved) = solve(0.0, 1.0);
    assert!(
        force.abs() <= 1e-12 && moved.abs() <= 1e-12,
        "{force} N, {moved} mm"
    );
    let (small, moved) = solve(1e-5, 1e-5);
    assert!(small < 0.0 && small.abs() <= 1e-4 * 28.6, "{small} N");
    let (smaller, less) = solve(1e-8, 1e-5);
    assert!((smaller / small - 1e-3).abs() <= 1e-7 && (less / moved - 1e-3).abs() <= 1e-7);
}

/// With a small compression ratio r the slack cable carries r·k·e, pushing the node by the
/// series formula with k₂ = r·E·A/L₀.
#[test]
fn slack_cable_with_a_compression_ratio_carries_r_times_its_stiffness() {
    let (r, s) = (1e-3, 0.05);
    let model = series(14.9, 3.1, L, L + s, Some(r));
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    solver.solve(&[0.0, 0.0]).unwrap();
    let (k1, k2) = (E * 14.9 / L, r * E * 3.1 / (L + s));
    let u = -k2 * s / (k1 + k2);
    assert!((solver.displacement(1)[0] - u).abs() <= 1e-12 * u.abs());
    assert!(solver.is_slack(1) && solver.member_force(1) < 0.0);
}

/// No imperfection, no load: the solution is exactly zero, with no iteration at all.
#[test]
fn zero_imperfections_give_exactly_zero_displacement() {
    let model = truss_core::prism::PrismOptions {
        diagonal_length: None,
        ..truss_core::prism::PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let errors = vec![0.0; model.members().len()];
    let report = solver.solve(&errors).unwrap();
    for i in 0..model.nodes().len() {
        assert_eq!(solver.displacement(i), [0.0; 3]);
    }
    assert_eq!(solver.distortion().unwrap().theta_p, 0.0);
    assert_eq!(report.residual, 0.0);
}
