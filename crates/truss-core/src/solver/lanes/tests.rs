//! The batched path against the one-sample path, bit for bit: an evaluation in any lane, and
//! whole solves in lanes beside other samples (of the same structure and of another), on
//! the baseline x86-64 kernels and on the best this processor has.

use super::band::{BandLanes, FactorLane, SolveLane};
use super::evaluate::{EvalBuffers, EvalLanes};
use super::*;
use crate::element::AxialState;
use crate::prism::{BacklashOptions, PrismOptions};
use crate::solver::tests::Normals as Stream;
use crate::solver::{Perturbation, SolveOptions, SolveReport, Solver};
use crate::{Model, SolveError};

/// The paper's prism of `stages` stages (with pin joints in free play for `backlash`).
fn prism(stages: usize, backlash: bool) -> Model {
    PrismOptions {
        backlash: backlash.then(|| BacklashOptions {
            clearance: 0.004,
            ..BacklashOptions::default()
        }),
        ..PrismOptions::with_stages(stages)
    }
    .model()
    .unwrap()
}

/// Length errors σ·N(0, 1) on every member, σ = 6.3 µm (diagonals included, so that some
/// go slack and some stay taut).
fn errors(model: &Model, stream: &mut Stream) -> Vec<f64> {
    model
        .members()
        .iter()
        .map(|_| 0.0063 * stream.normal())
        .collect()
}

/// Both instruction sets: the baseline one, and the best this processor has.
fn arches() -> [pulp::Arch; 2] {
    [pulp::Arch::Scalar, pulp::Arch::new()]
}

fn state_bits(s: &AxialState) -> [u64; 8] {
    [
        s.direction[0].to_bits(),
        s.direction[1].to_bits(),
        s.direction[2].to_bits(),
        s.length.to_bits(),
        s.elongation.to_bits(),
        s.force.to_bits(),
        s.stiffness.to_bits(),
        u64::from(s.slack),
    ]
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// A solver holding a sample's constants, and a point near its equilibrium (the
/// equilibrium moved by up to 2 µm, so some cables change state).
fn sample_at(model: &Model, stream: &mut Stream) -> (Solver, Vec<f64>) {
    let mut solver = Solver::new(model, SolveOptions::default()).unwrap();
    let e = errors(model, stream);
    solver.solve(&e).unwrap();
    let n = solver.structure.free;
    let mut u = solver.work.u.clone();
    for x in &mut u[..n] {
        *x += 0.002 * (stream.uniform() - 0.5);
    }
    (solver, u)
}

/// The one-sample evaluation of `solver`'s sample at `u`: r, states and the evaluation's
/// numbers, as bits.
fn one_sample(solver: &Solver, u: &[f64]) -> (Vec<u64>, Vec<[u64; 8]>, [u64; 3]) {
    let mut r = vec![0.0; u.len()];
    let mut states = solver.work.states.clone();
    let e = evaluate_with(
        &solver.structure,
        &solver.sample.members,
        solver.sample.tension.iter().copied(),
        &solver.sample.loads,
        u,
        &mut r,
        &mut states,
    );
    (
        bits(&r),
        states.iter().map(state_bits).collect(),
        [
            e.residual.to_bits(),
            e.force_scale.to_bits(),
            e.strain.to_bits(),
        ],
    )
}

#[test]
fn an_evaluation_in_any_lane_is_the_one_sample_evaluation_bit_for_bit() {
    for backlash in [false, true] {
        let model = prism(3, backlash);
        let mut stream = Stream(7 + u64::from(backlash));
        let samples: Vec<(Solver, Vec<f64>)> =
            (0..6).map(|_| sample_at(&model, &mut stream)).collect();
        let structure = Arc::clone(&samples[0].0.structure);
        for arch in arches() {
            let mut lanes = EvalLanes::<LANES>::new(&structure, arch);
            // Which sample each lane holds, pass after pass: full, partial, lanes changing
            // samples (their cached constants must follow), a lane alone.
            let passes: [[Option<usize>; LANES]; 5] = [
                [Some(0), Some(1), Some(2), Some(3)],
                [None, Some(4), None, Some(5)],
                [Some(5), Some(4), Some(3), Some(2)],
                [Some(1), None, None, None],
                [Some(0), Some(0), Some(1), Some(1)],
            ];
            for pass in passes {
                let mut buffers: [Option<EvalBuffers>; LANES] = std::array::from_fn(|l| {
                    pass[l].map(|k| {
                        let (solver, u) = &samples[k];
                        EvalBuffers {
                            members: solver.sample.members.clone(),
                            tension: solver.sample.tension.clone(),
                            loads: solver.sample.loads.clone(),
                            u: u.clone(),
                            r: vec![f64::NAN; u.len()],
                            states: solver.work.trial_states.clone(),
                        }
                    })
                });
                let mut io: [Option<((usize, u64), &mut EvalBuffers)>; LANES] =
                    std::array::from_fn(|_| None);
                for ((x, b), k) in io.iter_mut().zip(buffers.iter_mut()).zip(pass) {
                    *x = b.as_mut().map(|b| ((k.unwrap(), 1), b));
                }
                let evaluations = lanes.evaluate(&structure, &mut io);
                for l in 0..LANES {
                    let Some(k) = pass[l] else {
                        assert!(evaluations[l].is_none());
                        continue;
                    };
                    let (solver, u) = &samples[k];
                    let (r, states, e) = one_sample(solver, u);
                    let b = buffers[l].as_ref().unwrap();
                    let got = evaluations[l].unwrap();
                    let what = format!("backlash {backlash}, {arch:?}, lane {l}, sample {k}");
                    assert_eq!(bits(&b.r), r, "r: {what}");
                    let got_states: Vec<[u64; 8]> = b.states.iter().map(state_bits).collect();
                    assert_eq!(got_states, states, "states: {what}");
                    assert_eq!(
                        [
                            got.residual.to_bits(),
                            got.force_scale.to_bits(),
                            got.strain.to_bits()
                        ],
                        e,
                        "evaluation: {what}"
                    );
                }
            }
        }
    }
}

/// What a solve leaves, as bits: its report, its displacements and member forces.
fn outcome(solver: &Solver, result: Result<SolveReport, SolveError>) -> String {
    match result {
        Ok(report) => {
            let n = solver.structure.free;
            format!(
                "{report:?} u {:?} N {:?}",
                bits(&solver.work.u[..n]),
                solver
                    .work
                    .states
                    .iter()
                    .map(|s| s.force.to_bits())
                    .collect::<Vec<_>>()
            )
        }
        Err(e) => format!("{e:?}"),
    }
}

/// Solves every sample of `samples` (a model's index and length errors) in lanes, with a
/// pool of solvers per model reused from sample to sample; returns each outcome in order.
fn in_lanes(
    models: &[Model],
    samples: &[(usize, Vec<f64>)],
    arch: pulp::Arch,
    batched_dofs: usize,
    in_flight: usize,
) -> Vec<String> {
    struct Work<'m> {
        structures: Vec<Arc<crate::Structure>>,
        samples: &'m [(usize, Vec<f64>)],
        next: usize,
        pool: Vec<Vec<Solver>>,
        outcomes: Vec<Option<String>>,
    }
    impl<'m> LaneWork<'m> for Work<'m> {
        type Done = (usize, usize, Solver, String);
        fn next<'s>(&mut self, kernels: Kernels<'s>) -> Option<LaneSolve<'s, Self::Done>>
        where
            'm: 's,
        {
            let i = self.next;
            let (m, errors) = self.samples.get(i)?;
            self.next += 1;
            let mut solver = self.pool[*m].pop().unwrap_or_else(|| {
                Solver::with_structure(Arc::clone(&self.structures[*m]), SolveOptions::default())
            });
            let m = *m;
            Some(Box::pin(async move {
                let p = Perturbation {
                    length_errors: errors,
                    ..Perturbation::default()
                };
                let result = solver.solve_perturbed_in(p, kernels).await;
                let out = outcome(&solver, result);
                (i, m, solver, out)
            }))
        }
        fn done(&mut self, (i, m, solver, out): Self::Done) {
            self.outcomes[i] = Some(out);
            self.pool[m].push(solver);
        }
    }
    let mut work = Work {
        structures: models
            .iter()
            .map(|m| Arc::new(crate::Structure::new(m).unwrap()))
            .collect(),
        samples,
        next: 0,
        pool: models.iter().map(|_| Vec::new()).collect(),
        outcomes: vec![None; samples.len()],
    };
    let mut kernels = BatchKernels::with_arch(arch);
    kernels.batched_dofs = batched_dofs;
    run_lanes(&mut work, &mut kernels, in_flight);
    work.outcomes.into_iter().map(Option::unwrap).collect()
}

#[test]
fn solves_in_lanes_are_the_one_sample_solves_bit_for_bit() {
    let models = [prism(5, false), prism(2, true)];
    let mut stream = Stream(2024);
    // Runs of one model and of the other, so that a batch holds both at times.
    let samples: Vec<(usize, Vec<f64>)> = (0..23)
        .map(|i| {
            let m = usize::from(i % 7 >= 5);
            (m, errors(&models[m], &mut stream))
        })
        .collect();
    let alone: Vec<String> = samples
        .iter()
        .map(|(m, e)| {
            let mut solver = Solver::new(&models[*m], SolveOptions::default()).unwrap();
            let result = solver.solve(e);
            outcome(&solver, result)
        })
        .collect();
    // Batched on both instruction sets, and one lane at a time (a structure too large to
    // batch); one solve per lane, and more solves in flight than lanes (solves then move
    // between lanes, and meet lanes whose caches hold other samples).
    for (arch, batched_dofs) in [
        (pulp::Arch::Scalar, BATCHED_DOFS),
        (pulp::Arch::new(), BATCHED_DOFS),
        (pulp::Arch::new(), 0),
    ] {
        for in_flight in [LANES, LANES + 1, IN_FLIGHT] {
            let batched = in_lanes(&models, &samples, arch, batched_dofs, in_flight);
            for (i, (a, b)) in alone.iter().zip(&batched).enumerate() {
                assert_eq!(
                    a, b,
                    "sample {i}, {arch:?}, batched up to {batched_dofs}, {in_flight} in flight"
                );
            }
        }
    }
}

/// A symmetric banded matrix of `nb` block rows and half-bandwidth `q` with entries in
/// (−0.5, 0.5) and `diagonal` added on the diagonal: positive definite when `diagonal` is
/// large, indefinite when it is small.
fn band(nb: usize, q: usize, diagonal: f64, stream: &mut Stream) -> crate::block::BlockBandMatrix {
    let mut m = crate::block::BlockBandMatrix::new(nb, q);
    for i in 0..nb {
        for j in i.saturating_sub(q)..=i {
            let b = m.block_mut(i, j);
            for (r, row) in b.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = stream.uniform() - 0.5;
                    if i == j && r == c {
                        *x += diagonal;
                    }
                }
            }
            if i == j {
                // Symmetric: the upper triangle mirrors the lower.
                *b = std::array::from_fn(|r| std::array::from_fn(|c| b[r.max(c)][r.min(c)]));
            }
        }
    }
    m
}

fn factor_bits(m: &crate::block::BlockBandMatrix) -> (Vec<u64>, Vec<u64>) {
    let (blocks, inv) = m.factor_parts();
    (
        blocks
            .iter()
            .flatten()
            .flatten()
            .map(|x| x.to_bits())
            .collect(),
        inv.iter().flatten().map(|x| x.to_bits()).collect(),
    )
}

/// The batched factorisation and solves against the one-sample ones, bit for bit: positive
/// definite and indefinite matrices side by side (an indefinite lane is factorised again
/// by the one-sample code, its failed pivot recorded), solves with a factor the lanes hold,
/// held across another lane's factorisation, and with one they must gather (another lane's
/// matrix).
#[test]
fn the_band_in_lanes_is_the_one_sample_band_bit_for_bit() {
    let (nb, q) = (7, 3);
    for arch in arches() {
        let mut stream = Stream(99);
        let diagonals = [20.0, 0.1, 15.0, 25.0];
        let originals: Vec<_> = diagonals
            .iter()
            .map(|&d| band(nb, q, d, &mut stream))
            .collect();
        let mut want = originals.clone();
        let mut want_failures = vec![Vec::new(); LANES];
        for (m, f) in want.iter_mut().zip(&mut want_failures) {
            m.factor_collecting(f, 1);
        }
        assert!(want[1].factor_parts().0.len() == nb * (q + 1) && !want_failures[1].is_empty());
        let mut lanes = BandLanes::<LANES>::new(nb, q, arch);
        let mut got = originals.clone();
        let mut failures = vec![vec![]; LANES];
        {
            let mut io: [Option<FactorLane<'_>>; LANES] = std::array::from_fn(|_| None);
            for ((x, m), f) in io.iter_mut().zip(got.iter_mut()).zip(failures.iter_mut()) {
                *x = Some((m, f, 1));
            }
            lanes.factor(&mut io);
        }
        for l in 0..LANES {
            assert_eq!(
                got[l].is_factored(),
                want[l].is_factored(),
                "{arch:?} lane {l}"
            );
            assert_eq!(failures[l], want_failures[l], "{arch:?} lane {l}");
            assert_eq!(
                factor_bits(&got[l]),
                factor_bits(&want[l]),
                "{arch:?} lane {l}"
            );
        }
        let rhs: Vec<Vec<f64>> = (0..LANES)
            .map(|_| (0..3 * nb).map(|_| stream.uniform() - 0.5).collect())
            .collect();
        let solved = |m: &crate::block::BlockBandMatrix, b: &[f64]| {
            let mut x = b.to_vec();
            m.solve_in_place(&mut x);
            bits(&x)
        };
        // Lanes 0, 2, 3 hold their factors; lane 1 failed and holds none.
        let mut xs = rhs.clone();
        {
            let mut io: [Option<SolveLane<'_>>; LANES] = std::array::from_fn(|_| None);
            for (l, (x, b)) in io.iter_mut().zip(xs.iter_mut()).enumerate() {
                if l != 1 {
                    *x = Some((&got[l], &mut b[..]));
                }
            }
            lanes.solve(&mut io);
        }
        for l in [0, 2, 3] {
            assert_eq!(bits(&xs[l]), solved(&want[l], &rhs[l]), "{arch:?} lane {l}");
        }
        // A factorisation in lane 1 alone leaves the other lanes' factors: lane 0 solves
        // with the one it holds; lane 3 gathers another lane's matrix.
        let mut other = originals[3].clone();
        let mut f = Vec::new();
        {
            let mut io: [Option<FactorLane<'_>>; LANES] = std::array::from_fn(|_| None);
            io[1] = Some((&mut other, &mut f, 1));
            lanes.factor(&mut io);
        }
        let mut xs = rhs.clone();
        {
            let mut io: [Option<SolveLane<'_>>; LANES] = std::array::from_fn(|_| None);
            let (first, rest) = xs.split_at_mut(1);
            io[0] = Some((&got[0], &mut first[0][..]));
            io[3] = Some((&got[2], &mut rest[2][..]));
            lanes.solve(&mut io);
        }
        assert_eq!(
            bits(&xs[0]),
            solved(&want[0], &rhs[0]),
            "{arch:?} held across a factorisation"
        );
        assert_eq!(
            bits(&xs[3]),
            solved(&want[2], &rhs[3]),
            "{arch:?} another lane's factor"
        );
    }
}
