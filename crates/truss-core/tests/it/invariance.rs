//! Invariances and precision of the solution of the paper's prism.
//!
//! - Rigid rotation: rotating the whole model (nodes and reference normal) leaves θ_P,
//!   member forces and the slack set unchanged and rotates the displacements.
//! - Positive homogeneity: with every length error (the diagonals' 1.15 µm pre-shortening of
//!   Table 1 included) scaled by c > 0, θ_P scales by c: tension-only contact without gaps
//!   has no length scale; only the geometric nonlinearity, of relative size |u|/L ≈ 1e-5,
//!   breaks it.
//! - Resolution: θ_P agrees with a solve run to the rounding floor to better than 1e-9, at 5
//!   stages and at 60 (where some solves end on the displacements' rounding floor).
//! - Compression ratio: θ_P statistics do not move, beyond their sampling noise, for cable
//!   compression ratios from 1e-6 to 1e-3 at 5 stages, and (slow tier) from 1e-5 to 1e-2
//!   at 30 stages, 1e-3 to 1e-2 at 30 stages with σ = 66.7 µm and at 300 stages.

use crate::common::*;
use proptest::prelude::*;
use truss_core::model_file::ModelFile;
use truss_core::prism::PrismOptions;
use truss_core::{DEFAULT_COMPRESSION_RATIO, Model, SolveOptions, Solver};

const SIGMA: f64 = 0.0063;

fn prism(file: &ModelFile) -> Model {
    Model::new(file.clone()).unwrap()
}

fn theta(model: &Model, errors: &[f64], options: SolveOptions) -> f64 {
    let mut solver = Solver::new(model, options).unwrap();
    solver.solve(errors).unwrap();
    solver.distortion().unwrap().theta_p
}

fn rotation(a: f64, b: f64, c: f64) -> [[f64; 3]; 3] {
    let (sa, ca, sb, cb, sc, cc) = (a.sin(), a.cos(), b.sin(), b.cos(), c.sin(), c.cos());
    // Rz(a)·Ry(b)·Rx(c)
    [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
}

fn rotate(r: &[[f64; 3]; 3], x: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Rigid rotation of the whole model: same θ_P (to 1e-9), forces and slack set.
    #[test]
    fn rigid_rotation_changes_nothing(a in -3.1f64..3.1, b in -1.5f64..1.5, c in -3.1f64..3.1, seed in 0u64..1000) {
        let file = PrismOptions::with_stages(5).file().unwrap();
        let model = prism(&file);
        let errors = errors(&model, &["batten", "longeron"], SIGMA, &mut Normals::new(seed));
        let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
        solver.solve(&errors).unwrap();

        let r = rotation(a, b, c);
        let mut rotated = file.clone();
        for n in &mut rotated.nodes {
            n.xyz = rotate(&r, n.xyz);
        }
        let top = rotated.top_surface.as_mut().unwrap();
        top.reference_normal = rotate(&r, top.reference_normal);
        // Supports hold all three directions, so they need no rotation.
        let model_r = prism(&rotated);
        let mut solver_r = Solver::new(&model_r, SolveOptions::default()).unwrap();
        solver_r.solve(&errors).unwrap();

        let (t, tr) = (solver.distortion().unwrap().theta_p, solver_r.distortion().unwrap().theta_p);
        prop_assert!((t - tr).abs() <= 1e-9 * t, "theta {t} vs rotated {tr}");
        // Forces to 1e-7 of the largest: the solve converges relative to the largest force,
        // so a member carrying a thousandth of it is resolved to that absolute precision.
        let largest = (0..model.members().len())
            .map(|m| solver.member_force(m).abs())
            .fold(1e-3, f64::max);
        for m in 0..model.members().len() {
            prop_assert_eq!(solver.is_slack(m), solver_r.is_slack(m));
            let (f, fr) = (solver.member_force(m), solver_r.member_force(m));
            prop_assert!((f - fr).abs() <= 1e-7 * largest, "member {m}: {f} vs {fr} (largest {largest})");
        }
        // Displacements to 1e-8 of the largest, for the same reason: a component near zero
        // is resolved to the precision of the whole field, not to its own size.
        let scale = (0..model.nodes().len())
            .flat_map(|i| solver.displacement(i))
            .fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..model.nodes().len() {
            let (u, ur) = (rotate(&r, solver.displacement(i)), solver_r.displacement(i));
            for k in 0..3 {
                prop_assert!(
                    (u[k] - ur[k]).abs() <= 1e-12 + 1e-8 * scale,
                    "node {i}, axis {k}: {} vs {} (largest {scale})", u[k], ur[k]
                );
            }
        }
    }
}

/// Worst `|θ(c·e)/(c·θ(e)) − 1|` over 20 samples of amplitude `sigma` and c ∈ {0.1, 0.5, 2,
/// 3}, with the diagonals' Table 1 pre-shortening (1.15 µm at σ = 6.3 µm) scaled alike.
fn homogeneity_deviation(sigma: f64) -> f64 {
    let model = PrismOptions {
        diagonal_length: None,
        ..PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let shortening = (537.4 - 380.0 * 2f64.sqrt()) * sigma / SIGMA;
    let mut worst: f64 = 0.0;
    for seed in 0..20 {
        let mut e = errors(
            &model,
            &["batten", "longeron"],
            sigma,
            &mut Normals::new(seed),
        );
        for (x, m) in e.iter_mut().zip(model.members()) {
            if m.group == "diagonal" {
                *x = shortening;
            }
        }
        let base = theta(&model, &e, SolveOptions::default());
        for c in [0.1, 0.5, 2.0, 3.0] {
            let scaled: Vec<f64> = e.iter().map(|x| c * x).collect();
            let t = theta(&model, &scaled, SolveOptions::default());
            worst = worst.max((t / (c * base) - 1.0).abs());
        }
    }
    worst
}

/// θ_P(c·e) = c·θ_P(e) to 1e-6 relative where the geometric nonlinearity (relative size
/// |u|/L) is below that: amplitude σ = 1e-5 mm, displacements ≈ 3e-5 mm on 380 mm.
#[test]
fn theta_is_positively_homogeneous_in_the_length_errors() {
    let worst = homogeneity_deviation(1e-5);
    println!("σ = 1e-5 mm: worst relative deviation from homogeneity {worst:.2e}");
    assert!(worst <= 1e-6, "worst relative deviation {worst:.2e}");
}

/// At larger amplitudes the departure from homogeneity is the geometric nonlinearity of
/// the large-displacement formulation: it grows about in proportion to the amplitude (a
/// tenfold amplitude gave a 17- to 24-fold departure; the test allows 5 to 40) and stays of
/// the order of |u|/L: at
/// the paper's σ = 6.3 µm about 1e-4 (measured 1.4e-4 for c = 3), never 1e-3. The
/// compression ratio of the cables plays no part in it (the same with r = 1e-8).
#[test]
fn departure_from_homogeneity_is_the_geometric_nonlinearity() {
    let small = homogeneity_deviation(1e-4);
    let large = homogeneity_deviation(1e-3);
    let paper = homogeneity_deviation(SIGMA);
    println!("deviation at σ = 1e-4, 1e-3, 6.3e-3 mm: {small:.2e} {large:.2e} {paper:.2e}");
    assert!(
        (5.0..40.0).contains(&(large / small)),
        "{small:.2e} → {large:.2e}"
    );
    assert!(paper < 1e-3, "{paper:.2e}");
}

/// θ_P of a solve that keeps iterating (without factorisation reuse, up to
/// `max_iterations`) until the step is at the rounding floor: the reference of the
/// resolution tests. It may end there without meeting its 1e-16 tolerances: that is the
/// reference we want, so its last iterate is taken either way.
fn rounding_floor_theta(model: &Model, errors: &[f64], max_iterations: u32) -> f64 {
    let tight = SolveOptions {
        step_tolerance: 1e-16,
        residual_floor: 1e-16,
        reuse_factorisation: false,
        max_iterations,
        ..SolveOptions::default()
    };
    let mut solver = Solver::new(model, tight).unwrap();
    let _ = solver.solve(errors);
    solver.distortion().unwrap().theta_p
}

/// The default tolerances resolve θ_P to better than 1e-9: compared with a solve that
/// keeps iterating until the step is at the rounding floor.
#[test]
fn theta_is_resolved_to_better_than_1e9() {
    let model = PrismOptions::with_stages(5).model().unwrap();
    let mut worst: f64 = 0.0;
    for seed in 100..160 {
        let e = errors(
            &model,
            &["batten", "longeron"],
            SIGMA,
            &mut Normals::new(seed),
        );
        let t = theta(&model, &e, SolveOptions::default());
        worst = worst.max((t / rounding_floor_theta(&model, &e, 200) - 1.0).abs());
    }
    println!("worst relative difference from the rounding-floor solve: {worst:.2e}");
    assert!(worst <= 1e-9, "{worst:.2e}");
}

/// The same at 60 stages, where the top moves millimetres and the out-of-balance force's
/// rounding noise (`ε·k·‖u‖∞` per member) is above the force floor, so that some solves end
/// on the rounding floor of the displacements: θ_P is still resolved to 1e-9, and the
/// force those solves end on is within that floor.
#[test]
fn theta_of_a_tall_tower_is_resolved_to_better_than_1e9() {
    let model = PrismOptions::with_stages(60).model().unwrap();
    let stiffest = model
        .members()
        .iter()
        .map(|m| m.area * m.youngs_modulus / m.natural_length)
        .fold(0.0, f64::max);
    let (mut worst, mut on_rounding_floor) = (0.0f64, 0);
    for seed in 200..206 {
        let e = errors(
            &model,
            &["batten", "longeron"],
            SIGMA,
            &mut Normals::new(seed),
        );
        let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
        let report = solver.solve(&e).unwrap();
        let eq = solver.equilibrium().unwrap();
        let force = eq.forces.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        let u_max = eq
            .displacements
            .iter()
            .flatten()
            .fold(0.0f64, |a, u| a.max(u.abs()));
        let rounding = 4.0 * f64::EPSILON * stiffest * u_max;
        assert!(report.residual <= rounding.max(1e-13 * force) * 1.0001);
        if report.residual > 1e-13 * force {
            on_rounding_floor += 1;
        }
        let t = eq.distortion.unwrap().theta_p;
        worst = worst.max((t / rounding_floor_theta(&model, &e, 40) - 1.0).abs());
    }
    println!(
        "60 stages: worst relative difference {worst:.2e}; {on_rounding_floor} of 6 ended on the rounding floor"
    );
    assert!(worst <= 1e-9, "{worst:.2e}");
    assert!(
        on_rounding_floor > 0,
        "no solve exercised the rounding floor"
    );
}

/// The 50th and 95th percentiles and the RMS of θ_P over `n` samples of the `stages`-stage
/// prism with the cables' compression ratio `ratio` and length errors of σ = `sigma` \[mm\]
/// on battens and longerons, with common random numbers (the same draws for every ratio).
fn theta_statistics(stages: usize, sigma: f64, n: usize, ratio: f64) -> [f64; 3] {
    let model = PrismOptions {
        compression_ratio: ratio,
        ..PrismOptions::with_stages(stages)
    }
    .model()
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let mut rng = Normals::new(2024);
    let mut t: Vec<f64> = (0..n)
        .map(|_| {
            let e = errors(&model, &["batten", "longeron"], sigma, &mut rng);
            solver.solve(&e).unwrap();
            solver.distortion().unwrap().theta_p
        })
        .collect();
    t.sort_by(f64::total_cmp);
    let rms = (t.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt();
    [t[n / 2], t[(0.95 * n as f64) as usize], rms]
}

/// Asserts that θ_P's statistics at each of `ratios` move from the default ratio's
/// by less than a tenth of the 95th percentile's standard error: about
/// `√(p(1−p)/n)/(f(q)·q)` for a Rayleigh sample, 1.6 % at n = 1500, i.e. not beyond their
/// own noise. Returns the largest relative move.
fn assert_ratio_does_not_matter(stages: usize, sigma: f64, n: usize, ratios: &[f64]) -> f64 {
    let base = theta_statistics(stages, sigma, n, DEFAULT_COMPRESSION_RATIO);
    let bound = 0.1 * 0.016 * (1500.0 / n as f64).sqrt();
    let mut worst: f64 = 0.0;
    for &ratio in ratios {
        let s = theta_statistics(stages, sigma, n, ratio);
        for (k, name) in ["p50", "p95", "rms"].iter().enumerate() {
            let rel = (s[k] / base[k] - 1.0).abs();
            worst = worst.max(rel);
            assert!(
                rel < bound,
                "{stages} stages, σ = {sigma} mm, ratio {ratio:e}: {name} moved by {rel:.2e} (bound {bound:.1e})"
            );
        }
    }
    worst
}

/// θ_P statistics for compression ratios 1e-6 … 1e-3 (the default is 1e-4) do not move
/// beyond their own noise (see [`assert_ratio_does_not_matter`]), for the paper's 5 stages.
#[test]
fn theta_statistics_do_not_depend_on_the_compression_ratio() {
    assert_ratio_does_not_matter(5, SIGMA, 1500, &[1e-6, 1e-5, 1e-3]);
}

/// The same for long trusses and large errors, where the ratio sets the solver's cost (a
/// slack panel's regularising stiffness decides how nonlinear it is): at 30 stages for
/// ratios 1e-5 … 1e-2, and for 1e-3 and 1e-2 at σ = 66.7 µm (the paper's largest) and at
/// 300 stages (smaller ratios take hundreds of factorisations per solve there).
#[test]
#[ignore = "slow: 300-stage solves, run optimised by scripts/test.sh"]
fn theta_statistics_of_long_trusses_do_not_depend_on_the_compression_ratio() {
    let w30 = assert_ratio_does_not_matter(30, SIGMA, 1000, &[1e-5, 1e-3, 1e-2]);
    let w30_large = assert_ratio_does_not_matter(30, 0.0667, 500, &[1e-3, 1e-2]);
    let w300 = assert_ratio_does_not_matter(300, SIGMA, 100, &[1e-3, 1e-2]);
    println!(
        "largest relative move: {w30:.2e} at 30 stages, {w30_large:.2e} there at σ = 66.7 µm, {w300:.2e} at 300"
    );
}
