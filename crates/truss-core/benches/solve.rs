//! Benchmark of one equilibrium solve of the paper's prism with random length errors
//! (σ = 0.0063 mm on battens and longerons), for 5, 30 and 300 stages, and for the 5-stage
//! prism with backlash joints of the paper's 0.01 mm clearance and free play.
//!
//! Prints, per model: the median, 10th and 90th percentile time per solve over the samples
//! (each solve timed on its own, one thread), the median and mean Newton iterations,
//! factorisations and force evaluations, and the time of each kernel measured on its own
//! (factorise, triangular solves, evaluate, assemble) with the share of the solve that
//! counts × kernel time accounts for. For comparison, a dense Cholesky of the same 5-stage
//! tangent with faer. For 300 stages and for backlash, the histograms of the iteration and
//! factorisation counts; the ratio of the backlash model's median to the rigid one's. Where
//! the iterations come from: per count of soft directions of the linearised start (panels
//! whose bracing is all slack), the samples, their mean iterations and median time. Run with
//! `cargo bench -p truss-core`; `-- --quick` for fewer samples, `-- --only 5` (or `5b`, `30`,
//! `300`) for one model alone (for a profiler), `-- --paths` for the probe of whether the
//! converged state depends on the solver's path (see `path_independence`). Per model also
//! the batched path: every sample one at a time against in lanes (see `in_lanes`).
//! The machine is shared: run it several times and quote medians.

use std::hint::black_box;
use std::time::Instant;
use truss_core::block::BlockBandMatrix;
use truss_core::prism::{BacklashOptions, PrismOptions};
use truss_core::{SolveOptions, Solver};

/// SplitMix64 + Box–Muller: deterministic sample errors.
struct Normals(u64);

impl Normals {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// Median time of `f` over `reps` calls, in µs, from 7 batches.
fn kernel_time(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut batches: Vec<f64> = (0..7)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                f();
            }
            t.elapsed().as_secs_f64() * 1e6 / reps as f64
        })
        .collect();
    batches.sort_by(f64::total_cmp);
    batches[3]
}

/// Runs and prints one model's benchmark; returns its median time per solve \[µs\].
fn bench(stages: usize, samples: usize, backlash: bool, histogram: bool) -> f64 {
    let model = PrismOptions {
        backlash: backlash.then(BacklashOptions::default),
        ..PrismOptions::with_stages(stages)
    }
    .model()
    .unwrap();
    let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
    let mut rng = Normals(2024);
    let sigma = 0.0063;
    let errors: Vec<Vec<f64>> = (0..samples)
        .map(|_| {
            model
                .members()
                .iter()
                .map(|m| {
                    if m.group == "diagonal" {
                        0.0
                    } else {
                        sigma * rng.normal()
                    }
                })
                .collect()
        })
        .collect();
    in_lanes(&solver, &errors);
    // Warm up.
    for e in errors.iter().take(samples.min(200)) {
        solver.solve(e).unwrap();
    }
    let (mut times, mut its, mut facts, mut evals) = (vec![], vec![], vec![], vec![]);
    let mut soft = vec![];
    for e in &errors {
        let t = Instant::now();
        let r = black_box(solver.solve(black_box(e))).unwrap();
        times.push(t.elapsed().as_secs_f64() * 1e6);
        its.push(r.iterations as f64);
        facts.push(r.factorisations as f64);
        evals.push(r.evaluations as f64);
        soft.push(r.soft_directions);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mi, mf, me) = (mean(&its), mean(&facts), mean(&evals));
    let median_time = {
        let mut t = times.clone();
        t.sort_by(f64::total_cmp);
        (
            percentile(&t, 0.5),
            percentile(&t, 0.1),
            percentile(&t, 0.9),
        )
    };
    let mut sorted_its = its.clone();
    sorted_its.sort_by(f64::total_cmp);

    // Kernels on their own: the nominal stiffness of this model (same size and band).
    let s = std::sync::Arc::clone(solver.structure());
    let (nb, q) = (s.free_dofs() / 3, s.bandwidth());
    let mut k = BlockBandMatrix::new(nb, q);
    for i in 0..nb {
        for j in i.saturating_sub(q)..=i {
            let b = k.block_mut(i, j);
            for (r, row) in b.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = if i == j && r == c {
                        4.0 * (q as f64 + 1.0)
                    } else {
                        0.1 * ((i + j + r + c) % 5) as f64 - 0.2
                    };
                }
            }
        }
    }
    let reps = (200_000 / nb).max(20);
    let mut f = k.clone();
    let t_factor = kernel_time(reps, || {
        f.clone_from(&k);
        f.factor().unwrap();
    });
    let t_copy = kernel_time(reps, || f.clone_from(&k));
    f.clone_from(&k);
    f.factor().unwrap();
    let mut rhs = vec![1.0; 3 * nb];
    let t_solve = kernel_time(reps, || {
        f.solve_in_place(black_box(&mut rhs));
    });
    let e0 = &errors[0];
    let t_iteration = kernel_time(reps / 10 + 1, || {
        solver.solve(black_box(e0)).unwrap();
    });
    let r0 = solver.solve(e0).unwrap();
    let kind = if backlash { " with backlash" } else { "" };
    println!(
        "{stages:>3} stages{kind} ({} DOF, {} members, block band {q}): median {:.2} µs per solve (p10 {:.2}, p90 {:.2}) over {samples} samples",
        s.free_dofs(),
        s.member_count(),
        median_time.0,
        median_time.1,
        median_time.2
    );
    println!(
        "      iterations median {} mean {mi:.2}; factorisations mean {mf:.2}; force evaluations mean {me:.2}",
        percentile(&sorted_its, 0.5)
    );
    println!(
        "      kernels: factorise {:.2} µs, two triangular solves {:.2} µs; sample 0 ({} it, {} fact, {} eval) {:.2} µs",
        t_factor - t_copy,
        t_solve,
        r0.iterations,
        r0.factorisations,
        r0.evaluations,
        t_iteration
    );
    println!(
        "      share of the median solve in factorisations ≈ {:.0} %, in triangular solves ≈ {:.0} %",
        100.0 * mf * (t_factor - t_copy) / median_time.0,
        100.0 * (mi + 1.0) * t_solve / median_time.0
    );
    print_soft_directions(&soft, &its, &times);
    if histogram {
        for (what, counts) in [("iterations", &its), ("factorisations", &facts)] {
            let mut bins = std::collections::BTreeMap::new();
            for &i in counts.iter() {
                *bins.entry(i as u32).or_insert(0u32) += 1;
            }
            let bars: Vec<String> = bins.iter().map(|(i, c)| format!("{i}: {c}")).collect();
            println!(
                "      {what} histogram (count: samples): {}",
                bars.join(", ")
            );
        }
    }
    median_time.0
}

/// Where the iterations come from: the soft directions of each sample's linearised start
/// (panels whose bracing is all slack, held by geometric stiffness the linearised problem
/// lacks), and the mean iterations and median time of the samples with each count. Models
/// whose start is not solved by the capacitance matrix report none.
fn print_soft_directions(soft: &[u32], its: &[f64], times: &[f64]) {
    if soft.iter().all(|&s| s == 0) {
        println!("      soft directions of the linearised start: none counted");
        return;
    }
    let mut groups: std::collections::BTreeMap<u32, (Vec<f64>, Vec<f64>)> = Default::default();
    for ((&s, &i), &t) in soft.iter().zip(its).zip(times) {
        let g = groups.entry(s).or_default();
        g.0.push(i);
        g.1.push(t);
    }
    let mean = soft.iter().map(|&s| s as f64).sum::<f64>() / soft.len() as f64;
    let bars: Vec<String> = groups
        .iter_mut()
        .map(|(s, (i, t))| {
            t.sort_by(f64::total_cmp);
            format!(
                "{s}: {} samples, {:.2} it, {:.2} µs",
                i.len(),
                i.iter().sum::<f64>() / i.len() as f64,
                percentile(t, 0.5)
            )
        })
        .collect();
    println!(
        "      soft directions of the linearised start (panels with all bracing slack): mean {mean:.2}; by count (samples, mean iterations, median time): {}",
        bars.join("; ")
    );
}

/// A dense Cholesky (faer) of a 45 × 45 matrix the shape of the 5-stage tangent, for
/// comparison with the block band (with `--features cross-checks`, which brings faer).
#[cfg(feature = "cross-checks")]
fn dense_comparison() {
    use faer::Mat;
    let n = 45;
    let a = Mat::<f64>::from_fn(n, n, |i, j| {
        if i == j {
            100.0
        } else if i.abs_diff(j) <= 17 {
            0.1 * ((i + j) % 5) as f64 - 0.2
        } else {
            0.0
        }
    });
    let t = kernel_time(20_000, || {
        black_box(a.llt(faer::Side::Lower).unwrap());
    });
    println!("dense faer LLT of a 45 × 45 matrix: {t:.2} µs per factorisation (for comparison)");
}

#[cfg(not(feature = "cross-checks"))]
fn dense_comparison() {
    println!("dense faer LLT: run with --features cross-checks for the comparison");
}

/// Whether the converged state depends on the path the iteration took: the §3.4 prisms
/// (σ = 0.0667 mm on battens and longerons) solved with the default options and again
/// without reusing factorisations (a different sequence of steps, the same convergence
/// test). Prints, per stage count, the largest relative change of θ_P and of the
/// displacements, and how many samples moved by more than 1e-9 relative. Run with
/// `cargo bench -p truss-core -- --paths`.
fn path_independence(samples: usize) {
    let other = SolveOptions {
        reuse_factorisation: false,
        ..SolveOptions::default()
    };
    for stages in [1, 5, 10, 20, 30] {
        let model = PrismOptions::with_stages(stages).model().unwrap();
        let mut a = Solver::new(&model, SolveOptions::default()).unwrap();
        let mut b = Solver::new(&model, other.clone()).unwrap();
        let mut rng = Normals(34 + stages as u64);
        let (mut worst_theta, mut worst_u, mut moved) = (0.0f64, 0.0f64, 0);
        let mut worst_sample = None;
        let mut worst_errors = Vec::new();
        for k in 0..samples {
            let e: Vec<f64> = model
                .members()
                .iter()
                .map(|m| {
                    if m.group == "diagonal" {
                        0.0
                    } else {
                        0.0666666666666667 * rng.normal()
                    }
                })
                .collect();
            let (ra, rb) = (a.solve(&e).unwrap(), b.solve(&e).unwrap());
            let (ea, eb) = (a.equilibrium().unwrap(), b.equilibrium().unwrap());
            let (ta, tb) = (
                ea.distortion.unwrap().theta_p,
                eb.distortion.unwrap().theta_p,
            );
            let dt = (ta - tb).abs() / ta.abs().max(f64::MIN_POSITIVE);
            let scale = ea
                .displacements
                .iter()
                .flatten()
                .fold(0.0f64, |m, x| m.max(x.abs()));
            let du = ea
                .displacements
                .iter()
                .flatten()
                .zip(eb.displacements.iter().flatten())
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
                / scale;
            if dt > 1e-9 || du > 1e-9 {
                moved += 1;
            }
            if dt > worst_theta {
                worst_sample = Some((k, ra, rb, ea.slack.len(), eb.slack.len()));
                worst_errors = e.clone();
            }
            worst_theta = worst_theta.max(dt);
            worst_u = worst_u.max(du);
        }
        println!(
            "{stages:>3} stages: {samples} samples, max relative change of θ_P {worst_theta:.2e}, of the displacements {worst_u:.2e}; {moved} moved by more than 1e-9"
        );
        if let Some((k, ra, rb, sa, sb)) = worst_sample {
            println!(
                "      worst sample {k}: default {} it, residual {:.2e} N, step {:.2e} mm, {sa} slack; without reuse {} it, residual {:.2e} N, step {:.2e} mm, {sb} slack",
                ra.iterations, ra.residual, ra.step, rb.iterations, rb.residual, rb.step
            );
            // The same sample with a force test 100 times tighter, both ways: a flat valley
            // (one equilibrium, loosely resolved) brings the two together; two equilibria
            // stay apart.
            let mut thetas = vec![];
            for reuse in [true, false] {
                let tight = SolveOptions {
                    reuse_factorisation: reuse,
                    residual_floor: 1e-15,
                    step_tolerance: 1e-14,
                    max_iterations: 400,
                    ..SolveOptions::default()
                };
                let mut t = Solver::new(&model, tight).unwrap();
                match t.solve(&worst_errors) {
                    Ok(r) => {
                        let eq = t.equilibrium().unwrap();
                        let theta = eq.distortion.unwrap().theta_p;
                        thetas.push(theta);
                        println!(
                            "      tight, reuse {reuse}: {} it, residual {:.2e} N, θ_P {theta:.12e}, {} slack, Π {:.15e} N·mm",
                            r.iterations,
                            r.residual,
                            eq.slack.len(),
                            t.potential_energy()
                        );
                    }
                    Err(err) => println!("      tight, reuse {reuse}: {err}"),
                }
            }
            println!(
                "      default: θ_P {:.12e} and {:.12e}; Π {:.15e} and {:.15e}",
                {
                    a.solve(&worst_errors).unwrap();
                    a.distortion().unwrap().theta_p
                },
                {
                    b.solve(&worst_errors).unwrap();
                    b.distortion().unwrap().theta_p
                },
                {
                    a.solve(&worst_errors).unwrap();
                    a.potential_energy()
                },
                {
                    b.solve(&worst_errors).unwrap();
                    b.potential_energy()
                },
            );
        }
    }
}

/// The samples solved one at a time and in lanes (four side by side, their kernels
/// batched: `truss_core::solver::lanes`), all of them, three times each; prints the median
/// time per sample of each and their ratio, and checks that both give the same bits.
fn in_lanes(solver: &Solver, errors: &[Vec<f64>]) {
    use truss_core::solver::lanes::{
        BatchKernels, Kernels, LaneSolve, LaneWork, in_flight_for, run_lanes,
    };
    struct Work<'e> {
        structure: std::sync::Arc<truss_core::Structure>,
        errors: &'e [Vec<f64>],
        next: usize,
        pool: Vec<Solver>,
        out: Vec<u64>,
    }
    impl<'e> LaneWork<'e> for Work<'e> {
        type Done = (usize, Solver, u64);
        fn next<'s>(&mut self, kernels: Kernels<'s>) -> Option<LaneSolve<'s, Self::Done>>
        where
            'e: 's,
        {
            let i = self.next;
            let e = self.errors.get(i)?;
            self.next += 1;
            let mut solver = self.pool.pop().unwrap_or_else(|| {
                Solver::with_structure(self.structure.clone(), SolveOptions::default())
            });
            Some(Box::pin(async move {
                let p = truss_core::solver::Perturbation {
                    length_errors: e,
                    ..Default::default()
                };
                solver.solve_perturbed_in(p, kernels).await.unwrap();
                let bits = solver.displacement(0)[0].to_bits();
                (i, solver, bits)
            }))
        }
        fn done(&mut self, (i, solver, bits): Self::Done) {
            self.out[i] = bits;
            self.pool.push(solver);
        }
    }
    let structure = solver.structure().clone();
    let mut alone = Solver::with_structure(structure.clone(), SolveOptions::default());
    let (mut one, mut batched) = (vec![], vec![]);
    let mut want = vec![];
    let mut kernels = BatchKernels::default();
    for _ in 0..3 {
        let t = Instant::now();
        want = errors
            .iter()
            .map(|e| {
                alone.solve(black_box(e)).unwrap();
                alone.displacement(0)[0].to_bits()
            })
            .collect();
        one.push(t.elapsed().as_secs_f64() * 1e6 / errors.len() as f64);
        let mut work = Work {
            structure: structure.clone(),
            errors,
            next: 0,
            pool: vec![],
            out: vec![0; errors.len()],
        };
        let t = Instant::now();
        run_lanes(&mut work, &mut kernels, in_flight_for(&structure));
        batched.push(t.elapsed().as_secs_f64() * 1e6 / errors.len() as f64);
        assert_eq!(work.out, want, "lanes and one at a time differ");
    }
    one.sort_by(f64::total_cmp);
    batched.sort_by(f64::total_cmp);
    println!(
        "  one at a time {:.2} µs/sample, in {} lanes ({}) {:.2} µs/sample: {:.2}x (median of 3)",
        one[1],
        truss_core::solver::lanes::LANES,
        truss_core::solver::lanes::kernel_set(),
        batched[1],
        one[1] / batched[1]
    );
}

fn main() {
    if std::env::args().any(|a| a == "--paths") {
        path_independence(400);
        return;
    }
    let quick = std::env::args().any(|a| a == "--quick");
    let n = |full: usize| if quick { full / 10 } else { full };
    // `-- --only 5` (or 5b for backlash, 30, 300): that model alone, for a profiler.
    let args: Vec<String> = std::env::args().collect();
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1).cloned());
    let runs: [(&str, usize, usize, bool, bool); 4] = [
        ("5", 5, n(20_000), false, false),
        ("5b", 5, n(20_000), true, true),
        ("30", 30, n(2_000), false, false),
        ("300", 300, n(100).max(10), false, true),
    ];
    let mut medians = std::collections::BTreeMap::new();
    for (name, stages, samples, backlash, histogram) in runs {
        if only.as_deref().is_none_or(|o| o == name) {
            medians.insert(name, bench(stages, samples, backlash, histogram));
        }
    }
    if let (Some(rigid), Some(backlash)) = (medians.get("5"), medians.get("5b")) {
        println!(
            "5 stages with backlash / rigid: {:.2} (median per solve)",
            backlash / rigid
        );
    }
    if only.is_none() {
        dense_comparison();
    }
}
