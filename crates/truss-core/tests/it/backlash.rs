//! Backlash at pin joints (paper section 4): the paper's two demonstrations (Figs. 12–15),
//! the limit of vanishing clearance, and rigid rotation with joints.
//!
//! The demonstrations use a clearance of 30 mm, "extremely large to illustrate the
//! validity" (section 4.1), with the diagonals shortened until they pull every joint into
//! contact. The expected equilibrium follows by hand: a pin joint transmits force only
//! where the shaft bears on the hole's edge, so at each corner the shaft sits `g` from the
//! hole's centre in the direction of the force through the joint, which (the hole node
//! being held by its longeron alone) is the longeron's axis, less its part along the shaft
//! (backlash acts across the shaft only). Compressed longerons push
//! their holes away from the shafts: the bottom hole centre lies `g` below its (fixed)
//! shaft and the top hole centre `g` above the top shaft, so the top battens sit at
//! `L_longeron − 2g` above the bottom ones (Fig. 13: "the total height of the truss is
//! shortened").

use crate::common::*;
use truss_core::model_file::{JointSpec, ModelFile};
use truss_core::prism::{BacklashOptions, PrismOptions};
use truss_core::solver::Perturbation;
use truss_core::{Model, SolveOptions, Solver};

const G: f64 = 30.0;

fn joint(id: &str, shaft: &str, hole: &str, axis: [f64; 3]) -> JointSpec {
    JointSpec {
        id: id.into(),
        shaft: shaft.into(),
        hole: hole.into(),
        axis: Some(axis),
        clearance: G,
        tension_stiffness: None,
        compression_ratio: None,
        axial_stiffness: None,
    }
}

fn position(model: &Model, solver: &Solver, id: &str) -> [f64; 3] {
    let i = model.node_index(id).unwrap();
    let (x, u) = (model.nodes()[i].xyz, solver.displacement(i));
    [x[0] + u[0], x[1] + u[1], x[2] + u[2]]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Fig. 12/13: the square panel, four 380 mm members (A = 14.9 mm²) and two diagonals
/// (A = 3.1 mm²) shortened from 537.4 to 445.1 mm, 30 mm clearance at the four corners,
/// shafts' axes normal to the panel, the two lower batten nodes fixed.
#[test]
fn fig_13_panel_height_shortens_and_shafts_rest_along_the_longerons() {
    let corners = [
        ("bl", 0.0, 0.0),
        ("br", 380.0, 0.0),
        ("tl", 0.0, 380.0),
        ("tr", 380.0, 380.0),
    ];
    let mut nodes = Vec::new();
    for (c, x, z) in corners {
        nodes.push(node(c, [x, 0.0, z]));
        nodes.push(node(&format!("{c}.h"), [x, 0.0, z]));
    }
    let mut file: ModelFile = file(
        nodes,
        vec![
            member("batten.bottom", "bl", "br", 14.9, None, None),
            member("batten.top", "tl", "tr", 14.9, None, None),
            member("longeron.left", "bl.h", "tl.h", 14.9, None, None),
            member("longeron.right", "br.h", "tr.h", 14.9, None, None),
            member("diagonal.a", "bl", "tr", 3.1, Some(445.1), Some(1e-5)),
            member("diagonal.b", "br", "tl", 3.1, Some(445.1), Some(1e-5)),
        ],
        vec![
            support("bl", "xyz"),
            support("br", "xyz"),
            support("tl", "y"),
            support("tr", "y"),
        ],
    );
    file.joints = corners
        .iter()
        .map(|(c, _, _)| joint(&format!("joint.{c}"), c, &format!("{c}.h"), [0.0, 1.0, 0.0]))
        .collect();
    let model = Model::new(file).unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let report = solver.solve(&[]).unwrap();
    assert_eq!(report.loose_joints, 0, "every joint is taken up");

    let p = |id: &str| position(&model, &solver, id);
    for (lower, upper) in [("bl", "tl"), ("br", "tr")] {
        // Bottom hole g below its shaft, top hole g above its shaft, both along the
        // longeron's axis â: top shaft − bottom shaft = (L − 2g)·â, L the longeron's length.
        let axis = sub(p(&format!("{upper}.h")), p(&format!("{lower}.h")));
        let length = norm(axis);
        let shafts = sub(p(upper), p(lower));
        for k in 0..3 {
            let expected = (length - 2.0 * G) * axis[k] / length;
            assert!(
                (shafts[k] - expected).abs() < 1e-3,
                "{lower}–{upper}: shafts {shafts:?}, longeron {axis:?}"
            );
        }
        assert!(
            shafts[2] < 380.0 - 2.0 * G,
            "the panel's height shortens: {}",
            shafts[2]
        );
    }
    // Each shaft rests on its hole's edge (offset g, up to the contact's penetration) in
    // the direction of its longeron's axis.
    for (c, lower, upper) in [
        ("bl", "bl.h", "tl.h"),
        ("br", "br.h", "tr.h"),
        ("tl", "bl.h", "tl.h"),
        ("tr", "br.h", "tr.h"),
    ] {
        let j = model
            .joints()
            .iter()
            .position(|j| j.id == format!("joint.{c}"))
            .unwrap();
        let state = solver.joint_state(j);
        assert!(state.engaged, "{c} in contact");
        assert!(
            (state.distance - G).abs() < 1e-4 * G,
            "{c}: offset {}",
            state.distance
        );
        let axis = sub(p(upper), p(lower));
        let cross = [
            state.offset[1] * axis[2] - state.offset[2] * axis[1],
            state.offset[2] * axis[0] - state.offset[0] * axis[2],
            state.offset[0] * axis[1] - state.offset[1] * axis[0],
        ];
        let sine = norm(cross) / (norm(state.offset) * norm(axis));
        assert!(
            sine < 1e-6,
            "{c}: offset {:?} off the longeron by {sine}",
            state.offset
        );
    }
}

/// Fig. 14/15: the 1-stage prism, 30 mm clearance at the six corners, the three lower
/// batten nodes fixed: "the longeron is not tilted" (no twist), and the shafts rest on the
/// hole edges along the longerons.
///
/// The paper shortens the diagonals to 428.1 mm. With Table 1's sections that is 14 % less
/// than the 496.8 mm they span once the backlash is taken up (height 380 − 2g): some 30 kN
/// of pretension, beyond what the pin-jointed prism carries without twisting. It then
/// collapses into a twisted shape with or without backlash (measured: the top nodes drop
/// to z ≈ 144 mm without backlash), so the paper's model must have had other stiffnesses.
/// Here the diagonals are 490 mm: short enough to take up every joint, not so short that
/// the prism buckles.
#[test]
fn fig_15_one_stage_longerons_do_not_tilt() {
    let model = PrismOptions {
        diagonal_length: Some(490.0),
        backlash: Some(BacklashOptions {
            clearance: G,
            ..BacklashOptions::default()
        }),
        ..PrismOptions::with_stages(1)
    }
    .model()
    .unwrap();
    assert_eq!(model.joints().len(), 6);
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let report = solver.solve(&[]).unwrap();
    assert_eq!(report.loose_joints, 0);
    let p = |id: &str| position(&model, &solver, id);
    let centre = [190.0, 380.0 / (2.0 * 3f64.sqrt()), 0.0];
    for j in 0..3 {
        let axis = sub(p(&format!("n1.{j}.below")), p(&format!("n0.{j}.above")));
        let length = norm(axis);
        // No twist: the longeron leans, if at all, only towards the prism's axis (the top
        // battens' elastic shortening), never sideways.
        let radial = sub(centre, p(&format!("n0.{j}")));
        let sideways = (radial[0] * axis[1] - radial[1] * axis[0]) / (norm(radial) * length);
        assert!(
            sideways.abs() < 1e-9,
            "longeron {j} twists by {sideways} rad"
        );
        let lean = axis[0].hypot(axis[1]) / length;
        assert!(lean < 2e-3, "longeron {j} leans by {lean} rad");
        // Each shaft rests on its hole's edge along the longeron, so top shaft − bottom
        // shaft = (L − 2g)·â. (Backlash acts across the shaft only, whose axis is horizontal
        // and radial; the condensed joint takes the member as perpendicular to it, which
        // neglects 2g times the longeron's radial lean, at most 2·30·2e-3 = 0.12 mm here and
        // 2·0.017·1e-4 ≈ 3e-6 mm at the paper's clearances: see `crate::joint`.)
        let shafts = sub(p(&format!("n1.{j}")), p(&format!("n0.{j}")));
        for k in 0..3 {
            let expected = (length - 2.0 * G) * axis[k] / length;
            assert!(
                // Up to the two contacts' penetration N/k_t (N ≈ 1 kN here).
                (shafts[k] - expected).abs() < 1e-4,
                "node {j}: {shafts:?} vs {axis:?}"
            );
        }
        let shaft_axis = model.joints()[j].axis.unwrap();
        let along = axis[0] * shaft_axis[0] + axis[1] * shaft_axis[1] + axis[2] * shaft_axis[2];
        assert!(2.0 * G * along.abs() / length < 0.12, "radial lean {along}");
    }
}

/// The 5-stage prism with the paper's section 4.2.3 errors, solved with backlash whose
/// every clearance is `g`, and without backlash.
fn theta_with_clearance(g: Option<f64>, seed: u64) -> f64 {
    let backlash = g.map(|_| BacklashOptions::default());
    let model = PrismOptions {
        backlash,
        ..PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let sigma = 0.0067;
    let mut rng = Normals::new(seed);
    let errors: Vec<f64> = model
        .members()
        .iter()
        .map(|m| match m.group.as_str() {
            "diagonal" => -3.0 * sigma * rng.uniform(),
            _ => sigma * rng.normal(),
        })
        .collect();
    let clearances = vec![g.unwrap_or(0.0); model.joints().len()];
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    solver
        .solve_perturbed(Perturbation {
            length_errors: &errors,
            clearances: if g.is_some() { &clearances } else { &[] },
            ..Perturbation::default()
        })
        .unwrap();
    solver.distortion().unwrap().theta_p
}

/// As the clearance → 0 the model with backlash tends to the one without: the difference
/// in θ_P shrinks in proportion to `g` (until the contact's own compliance, 1e-5 of the
/// members', is all that is left).
#[test]
fn vanishing_clearance_recovers_the_model_without_backlash() {
    for seed in [11, 12, 13] {
        let rigid = theta_with_clearance(None, seed);
        let gap = |g: f64| (theta_with_clearance(Some(g), seed) - rigid).abs();
        let (d3, d4, d5, d0) = (gap(1e-3), gap(1e-4), gap(1e-5), gap(0.0));
        assert!(
            d0 < 1e-4 * rigid,
            "seed {seed}: g = 0 differs by {d0} of {rigid}"
        );
        assert!(
            d5 < 1e-2 * rigid,
            "seed {seed}: g = 1e-5 differs by {d5} of {rigid}"
        );
        assert!(d5 < d4 && d4 < d3, "seed {seed}: {d3} {d4} {d5}");
        let ratio = d3 / d4;
        assert!(
            (3.0..30.0).contains(&ratio),
            "seed {seed}: {d3}/{d4} = {ratio}, not ∝ g"
        );
    }
}

/// Rotating the whole model with backlash (nodes, joint axes, reference normal) changes
/// neither θ_P nor which joints are in contact: at a diagonal compression ratio of 1e-4,
/// where the sample has joints of both kinds, and at the default (the limit), where its
/// floating stages rise until their longerons touch their holes' edges and every joint
/// reads as bearing, with θ_P to 1e-6.
#[test]
fn rigid_rotation_with_joints_changes_nothing() {
    rigid_rotation_with_joints(1e-4, 1e-8, true);
    rigid_rotation_with_joints(truss_core::DEFAULT_COMPRESSION_RATIO, 1e-6, false);
}

fn rigid_rotation_with_joints(compression_ratio: f64, tolerance: f64, both_kinds: bool) {
    let file = PrismOptions {
        backlash: Some(BacklashOptions::default()),
        compression_ratio,
        ..PrismOptions::with_stages(3)
    }
    .file()
    .unwrap();
    let model = Model::new(file.clone()).unwrap();
    let mut rng = Normals::new(5);
    let errors: Vec<f64> = model
        .members()
        .iter()
        .map(|m| match m.group.as_str() {
            "diagonal" => -0.005 * rng.uniform(),
            _ => 0.0167 * rng.normal(),
        })
        .collect();
    let clearances: Vec<f64> = (0..model.joints().len())
        .map(|_| 0.004 + 0.013 * rng.uniform())
        .collect();
    let solve = |model: &Model| {
        let mut solver = Solver::new(model, SolveOptions::default()).unwrap();
        solver
            .solve_perturbed(Perturbation {
                length_errors: &errors,
                clearances: &clearances,
                ..Perturbation::default()
            })
            .unwrap();
        let engaged: Vec<bool> = (0..model.joints().len())
            .map(|j| solver.joint_state(j).engaged)
            .collect();
        (solver.distortion().unwrap().theta_p, engaged)
    };
    let (theta, engaged) = solve(&model);
    let (a, b) = (0.7f64, -0.4f64);
    let r = [
        [a.cos() * b.cos(), -a.sin(), a.cos() * b.sin()],
        [a.sin() * b.cos(), a.cos(), a.sin() * b.sin()],
        [-b.sin(), 0.0, b.cos()],
    ];
    let rot = |x: [f64; 3]| [0, 1, 2].map(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2]);
    let mut rotated = file;
    for n in &mut rotated.nodes {
        n.xyz = rot(n.xyz);
    }
    for j in &mut rotated.joints {
        j.axis = j.axis.map(rot);
    }
    let top = rotated.top_surface.as_mut().unwrap();
    top.reference_normal = rot(top.reference_normal);
    let (theta_r, engaged_r) = solve(&Model::new(rotated).unwrap());
    assert!(
        (theta - theta_r).abs() <= tolerance * theta,
        "{theta} vs {theta_r}"
    );
    if both_kinds {
        assert_eq!(engaged, engaged_r);
        assert!(engaged.iter().any(|&e| e) && engaged.iter().any(|&e| !e));
    }
}

/// Vertical displacement of the top level \[mm\] of the N-stage prism with every diagonal
/// shortened by `delta`, every joint's clearance `g` (0 without backlash), by hand.
///
/// With the diagonals all shortened alike, the prism stays symmetric: no twist (each face's
/// two crossed diagonals are mirror images), every level an equilateral triangle whose side
/// changes by `a_k` (`a_0 = 0`, the fixed bottom), every stage's height by `Δh_s`. To first
/// order a longeron then lengthens by `Δh_s` and a diagonal by
/// `Δℓ = (h·Δh_s + l·(a_{s−1} + a_s)/2)/ℓ_d` (the horizontal span of a face diagonal grows by
/// the mean of its two levels' side changes, each vertex `l/2` from the face's midline), so
/// the energy of the symmetric modes is
///
/// ```text
/// Π = Σ_s [3·½·k_s·(Δh_s + G)² + 6·½·k_d·(Δℓ_s + δ)²] + Σ_k 3·½·k_b·a_k²
/// ```
///
/// with the longerons compressed (each of the `G = 2g` of its two holes taken up: the joints
/// bear along it) and `k_s = 1/(1/k_l + 2/k_t)` the longeron in series with its two contacts,
/// or `k_s = k_l`, `G = 0` without backlash. Its stationary point is the 2N × 2N linear
/// system solved here. The top level is `Σ Δh_s` lower; backlash lowers it by the stacked
/// clearances `2g·N` less the elastic shortening that the slackened diagonals no longer
/// cause, both linear in `g`.
fn top_by_hand(stages: usize, delta: f64, g: f64, contact: f64) -> f64 {
    let (l, h) = (380.0f64, 380.0f64);
    let ld = l.hypot(h);
    let (kl, kb, kd) = (
        70_000.0 * 14.9 / h,
        70_000.0 * 14.9 / l,
        70_000.0 * 3.1 / ld,
    );
    let (ks, big_g) = if g > 0.0 || contact.is_finite() {
        (1.0 / (1.0 / kl + 2.0 / contact), 2.0 * g)
    } else {
        (kl, 0.0)
    };
    let (ch, cl) = (h / ld, l / ld);
    // Unknowns: Δh_1..Δh_N, then a_1..a_N. Row of ∂Π/∂x = A x − b = 0.
    let n = 2 * stages;
    let mut a = vec![vec![0.0; n + 1]; n];
    // Adds c·(the diagonal stretch's coefficients of stage s) into row `row`, constant
    // term to the right-hand side.
    let stretch = |s: usize| {
        let mut coef = vec![0.0; n];
        coef[s - 1] = ch;
        if s > 1 {
            coef[stages + s - 2] += cl / 2.0;
        }
        coef[stages + s - 1] += cl / 2.0;
        coef
    };
    for s in 1..=stages {
        let t = stretch(s);
        // ∂/∂Δh_s: 3·k_s·(Δh_s + G) + 6·k_d·T_s·c_h.
        let row = &mut a[s - 1];
        row[s - 1] += 3.0 * ks;
        row[n] -= 3.0 * ks * big_g;
        for (r, c) in row.iter_mut().zip(&t) {
            *r += 6.0 * kd * ch * c;
        }
        row[n] -= 6.0 * kd * ch * delta;
        // ∂/∂a_k for the levels k = s − 1 (if free) and s: 6·k_d·T_s·c_l/2 each.
        for k in [s - 1, s] {
            if k == 0 {
                continue;
            }
            let row = &mut a[stages + k - 1];
            for (r, c) in row.iter_mut().zip(&t) {
                *r += 3.0 * kd * cl * c;
            }
            row[n] -= 3.0 * kd * cl * delta;
        }
    }
    for k in 1..=stages {
        a[stages + k - 1][stages + k - 1] += 3.0 * kb;
    }
    // Gaussian elimination with partial pivoting.
    for c in 0..n {
        let p = (c..n)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap();
        a.swap(c, p);
        let pivot = a[c].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != c {
                let f = row[c] / pivot[c];
                for (x, p) in row.iter_mut().zip(&pivot).skip(c) {
                    *x -= f * p;
                }
            }
        }
    }
    (0..stages).map(|s| a[s][n] / a[s][s]).sum()
}

/// A hand check: the 5-stage truss, every clearance `g`, no length errors but
/// every diagonal shortened by 0.05 mm. Every joint bears, each joint's force lies along its
/// longeron with its offset `g` (plus the contact's penetration `F/k_t`) along that force,
/// and the top surface is lower than without backlash by [`top_by_hand`]'s difference, to
/// 3 %, for two clearances (the difference is linear in `g`).
#[test]
fn five_stages_drop_by_the_stacked_clearances_less_the_lost_pretension() {
    let stages = 5;
    let delta = 0.05;
    let solve = |g: Option<f64>| {
        let model = PrismOptions {
            diagonal_length: None,
            backlash: g.map(|g| BacklashOptions {
                clearance: g,
                ..BacklashOptions::default()
            }),
            ..PrismOptions::with_stages(stages)
        }
        .model()
        .unwrap();
        let errors: Vec<f64> = model
            .members()
            .iter()
            .map(|m| if m.group == "diagonal" { -delta } else { 0.0 })
            .collect();
        let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
        let report = solver.solve(&errors).unwrap();
        let top: f64 = (0..3)
            .map(|j| solver.displacement(model.node_index(&format!("n{stages}.{j}")).unwrap())[2])
            .sum::<f64>()
            / 3.0;
        (model, solver, report, top)
    };
    let (_, _, _, rigid) = solve(None);
    let by_hand_rigid = top_by_hand(stages, delta, 0.0, f64::INFINITY);
    assert!(
        (rigid - by_hand_rigid).abs() < 0.03 * by_hand_rigid.abs(),
        "without backlash: {rigid} vs {by_hand_rigid} by hand"
    );
    let mut drops = Vec::new();
    for g in [0.005, 0.01] {
        let (model, solver, report, top) = solve(Some(g));
        assert_eq!(model.joints().len(), 30);
        assert_eq!(report.loose_joints, 0, "g = {g}: every joint bears");
        let kt = model.joints()[0].tension_stiffness;
        let by_hand = top_by_hand(stages, delta, g, kt) - by_hand_rigid;
        let drop = top - rigid;
        assert!(
            (drop - by_hand).abs() < 0.03 * by_hand.abs(),
            "g = {g}: top lower by {drop} mm, by hand {by_hand} mm (stacked {} mm)",
            -2.0 * g * stages as f64
        );
        eprintln!("g = {g} mm: top lower by {drop:.6} mm; by hand {by_hand:.6} mm");
        drops.push(drop / g);
        for (j, joint) in model.joints().iter().enumerate() {
            let st = solver.joint_state(j);
            // The longeron's current axis, from its holes.
            let m = model
                .members()
                .iter()
                .find(|m| m.nodes.contains(&joint.hole))
                .unwrap();
            let ends = m.nodes.map(|n| {
                let (x, u) = (model.nodes()[n].xyz, solver.displacement(n));
                [x[0] + u[0], x[1] + u[1], x[2] + u[2]]
            });
            let axis = sub(ends[1], ends[0]);
            let f = st.force;
            let sine = norm([
                f[1] * axis[2] - f[2] * axis[1],
                f[2] * axis[0] - f[0] * axis[2],
                f[0] * axis[1] - f[1] * axis[0],
            ]) / (norm(f) * norm(axis));
            assert!(
                sine < 1e-9,
                "{}: force off its longeron by {sine}",
                joint.id
            );
            assert!(st.contact > 0.1, "{}: bears {} N", joint.id, st.contact);
            assert!(
                (st.distance - (g + st.contact / kt)).abs() < 1e-12,
                "{}: offset {} for g {g}",
                joint.id,
                st.distance
            );
            let along = (0..3).map(|d| st.offset[d] * f[d]).sum::<f64>() / (norm(f) * st.distance);
            assert!(
                along > 1.0 - 1e-12,
                "{}: offset not along its force",
                joint.id
            );
        }
    }
    assert!(
        (drops[0] - drops[1]).abs() < 0.01 * drops[1].abs(),
        "not linear in g: {drops:?} mm per mm"
    );
}

/// θ_P95 \[rad\], σ_t and the top surface's mean displacement \[mm\] of a set of samples.
type Statistics = (f64, f64, [f64; 3]);

/// The [`Statistics`] of the 5-stage truss at the Fig. 16 study's smallest σ (0.0067 mm,
/// diagonals U[−3σ, 0], clearances U[0.004, 0.017] mm), over 400 samples, with the joints'
/// regularisation `k_c/k_t = ratio` and the prism's default diagonals.
fn fig16_statistics(ratio: f64) -> Statistics {
    fig16_statistics_with(ratio, truss_core::DEFAULT_COMPRESSION_RATIO)
}

/// [`fig16_statistics`] with the diagonals' compression ratio `diagonal_ratio` (their
/// stiffness when slack over their stiffness in tension).
fn fig16_statistics_with(ratio: f64, diagonal_ratio: f64) -> Statistics {
    let model = PrismOptions {
        compression_ratio: diagonal_ratio,
        backlash: Some(BacklashOptions {
            compression_ratio: ratio,
            ..BacklashOptions::default()
        }),
        ..PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let sigma = 0.0067;
    let mut rng = Normals::new(16);
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let top: Vec<usize> = (0..3)
        .map(|j| model.node_index(&format!("n5.{j}")).unwrap())
        .collect();
    let (mut thetas, mut tan_sq, mut mean) = (Vec::new(), 0.0, [0.0; 3]);
    let samples = 400;
    for _ in 0..samples {
        let (errors, clearances) = fig16_draw(&model, sigma, &mut rng);
        solver
            .solve_perturbed(Perturbation {
                length_errors: &errors,
                clearances: &clearances,
                ..Perturbation::default()
            })
            .unwrap();
        let d = solver.distortion().unwrap();
        thetas.push(d.theta_p);
        tan_sq += d.tan_theta_x.powi(2) + d.tan_theta_y.powi(2);
        for &n in &top {
            let u = solver.displacement(n);
            for k in 0..3 {
                mean[k] += u[k] / (3.0 * samples as f64);
            }
        }
    }
    thetas.sort_by(f64::total_cmp);
    let p95 = thetas[(0.95 * samples as f64) as usize];
    (p95, (tan_sq / (2.0 * samples as f64)).sqrt(), mean)
}

/// The joints need no regularisation: θ_P95, σ_t and the top surface's mean position agree
/// within 1 % between a regularisation and one 1,000 times smaller (1e-18 against 1e-21 of
/// the contact stiffness), and between 1e-21 and none at all (the default: a loose pin
/// carries no force). At the limit a floating stage's slack diagonals carry exactly nothing
/// in compression, so a loose longeron's regularisation is the only stiffness that holds
/// it and must be negligible against everything else: at 1e-18 it is 3e-10 N/mm; at 1e-15
/// (3e-7 N/mm) it picks the floating stages' positions, and θ_P95 moves by 8 % (measured).
#[test]
fn the_answer_does_not_depend_on_the_regularisation() {
    let runs: Vec<(f64, Statistics)> = [1e-18, 1e-21, 0.0]
        .into_iter()
        .map(|r| (r, fig16_statistics(r)))
        .collect();
    assert_neighbours_agree("k_c/k_t", &runs);
}

/// Asserts that θ_P95, σ_t and the mean top position of each run agree within 1 % with the
/// next one's; `what` names the ratio that differs between them.
fn assert_neighbours_agree(what: &str, runs: &[(f64, Statistics)]) {
    for pair in runs.windows(2) {
        let ((ra, (pa, sa, ma)), (rb, (pb, sb, mb))) = (pair[0], pair[1]);
        eprintln!("{what} {ra:e}: θ_P95 {pa:.6e}, σ_t {sa:.6e}, mean top {ma:?} mm");
        eprintln!("{what} {rb:e}: θ_P95 {pb:.6e}, σ_t {sb:.6e}, mean top {mb:?} mm");
        assert!(
            (pa - pb).abs() <= 0.01 * pb,
            "θ_P95 {pa} at {what} {ra:e}, {pb} at {rb:e}"
        );
        assert!(
            (sa - sb).abs() <= 0.01 * sb,
            "σ_t {sa} at {what} {ra:e}, {sb} at {rb:e}"
        );
        let gap = norm(sub(ma, mb));
        assert!(
            gap <= 0.01 * norm(mb),
            "mean top {ma:?} at {what} {ra:e}, {mb:?} at {rb:e}"
        );
    }
}

/// The default is the limit `r → 0` of the slack diagonals' compression ratio (the paper's
/// zero), and a ratio of 1e-4 is not. In this study almost every sample has a longeron
/// floating in its holes, and the stages around it are held only by the geometric stiffness
/// of what pretension is left and by the slack diagonals' `r·E·A/L₀` = r · 404 N/mm. θ_P95,
/// σ_t and the mean top position agree within 1 % between the default, 1e-8 and 1e-9 (400
/// samples), while at 1e-4 θ_P95 is more than 3 % higher (about 6 %). Slow: solves at 1e-9
/// take some 20 iterations.
#[test]
#[ignore = "slow: 1,600 backlash solves at small ratios, run optimised by scripts/test.sh"]
fn the_default_is_the_diagonals_limit_and_1e4_is_not() {
    let runs: Vec<(f64, Statistics)> = [truss_core::DEFAULT_COMPRESSION_RATIO, 1e-8, 1e-9]
        .into_iter()
        .map(|r| (r, fig16_statistics_with(0.0, r)))
        .collect();
    assert_neighbours_agree("diagonals' ratio", &runs);
    let (p_limit, _, _) = runs[2].1;
    let (p_regularised, _, _) = fig16_statistics_with(0.0, 1e-4);
    println!(
        "diagonals' ratio 1e-4 against 1e-9: θ_P95 {:+.2} %",
        100.0 * (p_regularised / p_limit - 1.0)
    );
    assert!(
        p_regularised > 1.03 * p_limit,
        "{p_regularised} vs {p_limit}"
    );
}

/// θ_P of each of `samples` samples of the Fig. 16 case (σ = 0.0067 mm, diagonals
/// U[−3σ, 0], clearances U[0.004, 0.017] mm; the draws of [`fig16_statistics_with`], from
/// `seed`) at the diagonals' compression ratio `diagonal_ratio`, with whether it floats
/// (`None` where the solve failed).
fn fig16_thetas(seed: u64, samples: usize, diagonal_ratio: f64) -> Vec<Option<(f64, bool)>> {
    let model = PrismOptions {
        compression_ratio: diagonal_ratio,
        backlash: Some(BacklashOptions::default()),
        ..PrismOptions::with_stages(5)
    }
    .model()
    .unwrap();
    let sigma = 0.0067;
    let mut rng = Normals::new(seed);
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    (0..samples)
        .map(|_| {
            let (errors, clearances) = fig16_draw(&model, sigma, &mut rng);
            let report = solver
                .solve_perturbed(Perturbation {
                    length_errors: &errors,
                    clearances: &clearances,
                    ..Perturbation::default()
                })
                .ok()?;
            Some((solver.distortion()?.theta_p, report.floating))
        })
        .collect()
}

/// The acceptance test of the physical default: on the same 1,500 draws of the Fig. 16
/// case, the default's θ_P95 is within 1 % of that at a compression ratio of 1e-10, and the
/// median sample differs by less than 0.1 %; at the old regularisation, 1e-4, θ_P95 is more
/// than 3 % off. (At 1e-10 the slack diagonals' stiffness, 4e-8 N/mm, is near the solver's
/// force resolution: a few samples there do not converge and are left out of the
/// comparison, and some tenth of those that float sit in another of the equilibria their
/// stage allows; the statistics do not notice.)
#[test]
#[ignore = "slow: 4,500 backlash solves, run optimised by scripts/test.sh"]
fn the_default_holds_the_fig16_case_at_its_limit() {
    let samples = 1500;
    let default = fig16_thetas(26, samples, truss_core::DEFAULT_COMPRESSION_RATIO);
    let limit = fig16_thetas(26, samples, 1e-10);
    let old = fig16_thetas(26, samples, 1e-4);
    assert!(
        default.iter().all(Option::is_some),
        "a default solve failed"
    );
    let both = |a: &[Option<(f64, bool)>]| -> Vec<(f64, f64)> {
        a.iter()
            .zip(&limit)
            .filter_map(|(x, y)| Some((x.as_ref()?.0, y.as_ref()?.0)))
            .collect()
    };
    let p95 = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[(0.95 * v.len() as f64) as usize]
    };
    let pairs = both(&default);
    assert!(
        pairs.len() >= samples - 15,
        "{} of {samples} compared",
        pairs.len()
    );
    let (mut d, mut l): (Vec<f64>, Vec<f64>) = pairs.iter().copied().unzip();
    let mut rel: Vec<f64> = pairs.iter().map(|(a, b)| (a / b - 1.0).abs()).collect();
    rel.sort_by(f64::total_cmp);
    let (pd, pl) = (p95(&mut d), p95(&mut l));
    println!(
        "default against 1e-10: θ_P95 {pd:.6e} / {pl:.6e} ({:+.3} %), median |Δθ|/θ {:.2e}, \
         {} samples compared, {} float",
        100.0 * (pd / pl - 1.0),
        rel[rel.len() / 2],
        pairs.len(),
        default.iter().flatten().filter(|(_, f)| *f).count()
    );
    assert!((pd - pl).abs() <= 0.01 * pl, "θ_P95 {pd} against {pl}");
    assert!(rel[rel.len() / 2] <= 1e-3, "median {}", rel[rel.len() / 2]);
    let (mut o, _): (Vec<f64>, Vec<f64>) = both(&old).into_iter().unzip();
    let po = p95(&mut o);
    assert!(po > 1.03 * pl, "at 1e-4 θ_P95 {po} against {pl}");
}

/// A model that is a mechanism even with every joint in contact and every cable taut (here
/// the 3-stage prism with pin joints, its middle stage's diagonals removed: that stage
/// racks freely) is refused when the model is read, before any sample is drawn, naming a
/// node of that stage that moves freely; with the diagonals in place the same model compiles (the
/// stages float in their clearances only at the limit, which the solver handles).
#[test]
fn a_mechanism_with_every_joint_bearing_is_refused_before_any_solve() {
    let options = PrismOptions {
        backlash: Some(BacklashOptions::default()),
        ..PrismOptions::with_stages(3)
    };
    let whole = Model::new(options.file().unwrap()).unwrap();
    Solver::new(&whole, SolveOptions::default()).unwrap();
    let mut file = options.file().unwrap();
    let before = file.members.len();
    file.members.retain(|m| !m.id.starts_with("diagonal.1."));
    assert!(file.members.len() < before, "no diagonal of stage 1 found");
    let message = match Model::new(file) {
        Ok(_) => panic!("a racking stage was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        message.contains("mechanism") && message.contains("\"n1."),
        "{message}"
    );
}
