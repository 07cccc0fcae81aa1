//! Profile-likelihood intervals of a fitted candidate's parameters.
//!
//! ## Definition
//!
//! For parameter `j` the profile log-likelihood `ℓ_p(θⱼ)` is the maximum of ℓ over the other
//! parameters (on their feasible set, e.g. backlash's spread no larger than its mean) with `θⱼ` held, and its
//! 95 % interval is the set of values where
//!
//! ```text
//! D(θⱼ) = 2(ℓ̂ − ℓ_p(θⱼ)) ≤ qⱼ = χ²₁(0.95) · c · λⱼ,    c = 1 + n/N,
//! λⱼ = max(1, (A⁻¹BA⁻¹)ⱼⱼ / (A⁻¹)ⱼⱼ)
//! ```
//!
//! (the interval is the connected part of that set that holds the fit, `θ̂ⱼ`). `c` and `λⱼ`
//! are the adjustments the likelihood-ratio test makes (`diagnose`): `c` for the simulation's
//! own noise in μ and Σ; `λⱼ` for misspecification, the ratio of the parameter's sandwich
//! variance to its model-based one (Royall & Tsou 2003, "Interpreting statistical evidence
//! by using imperfect models: robust adjusted likelihood functions"), the one-parameter form
//! of the test's `λ̄ = tr(A⁻¹B)/k`, and like it never below 1 (an interval never narrower
//! than the model's own); 1 when `A` is not positive definite. Where ℓ is quadratic the
//! interval is exactly the sandwich Wald interval of [`crate::likelihood::fit`]; where it is not (slack
//! cables, a fit near the edge of the plausible range, a scale) it follows ℓ itself and is
//! the same in any parametrisation. An end that reaches the plausible range is cut there and
//! flagged (`lower_at_range_end`, `upper_at_range_end`).
//!
//! ## Joint intervals
//!
//! Each interval above holds its own parameter with 95 % confidence; all k of them at once
//! hold with less (as little as 1 − 0.05k). For a statement about all parameters together,
//! the joint 95 % region `{θ : 2(ℓ̂ − ℓ(θ)) ≤ q_k = χ²_k(0.95)·c·λ̄}` is projected on each
//! parameter: its joint interval is the same profile computation with the threshold `q_k`
//! (`λ̄` the test's own), and every parameter of a θ in the region lies in its joint
//! interval. The projection stays valid where the truth is on the edge of a feasible set
//! that couples the parameters, where a single parameter's profile is not: under a ball
//! \|θ\| ≤ 1 of three, holding θ₁ at ±1 leaves the other two no room, so `D(±1)` is the
//! joint statistic of all three, distributed (the ball locally a half-space) as
//! ½χ²₂ + ½χ²₃ (Self & Liang 1987), which exceeds χ²₁(0.95) = 3.84 with probability
//! ½·0.147 + ½·0.279 ≈ 0.21 but χ²₃(0.95) = 7.81 with ½·0.020 + ½·0.050 ≈ 0.035. (That was
//! gravity's \|g\| ≤ 1; its components are now free in their box,
//! [`crate::candidates::gravity`].) At the end of a box, which holds one parameter only,
//! `D` is ½χ²₀ + ½χ²₁ and the threshold χ²₁(0.95) errs on the safe side (exceeded with
//! probability 0.025).
//!
//! ## Computation
//!
//! In internal coordinates, with the common random numbers of every other evaluation. Each
//! end is a root of `r(x) = √D(x) − √qⱼ`; `√D` is linear in `x` for a quadratic profile.
//! The first trial is the quadratic one, `t̂ⱼ ± √(qⱼ·(A⁻¹)ⱼⱼ)`; while `D < qⱼ` the trial moves
//! out by the secant on `√D` (by a factor 1.1 to 4 at a time) up to the range end; once the
//! root is bracketed, Illinois regula falsi on `r` until `|D − qⱼ| ≤` [`ROOT_TOLERANCE`]`·qⱼ`
//! or the bracket is a thousandth of the distance from the fit; the end is interpolated
//! linearly in `√D` (between the last point and its nearest neighbour, or within the last
//! bracket). At most [`MAX_POINTS`] profile points per end; a joint end starts from the
//! points its parameter's own end found.
//!
//! Each profile point maximises ℓ over the other parameters with the trust-region Newton
//! method of [`crate::likelihood::fit`] (tolerance [`crate::likelihood::fit::TOLERANCE`], the fit's finite-difference
//! steps), started from the nearest point already found shifted along the quadratic
//! prediction `−A₋ⱼ₋ⱼ⁻¹A₋ⱼⱼ·Δθⱼ`. Should a profile point have ℓ above `ℓ̂` by more than the
//! tolerance, the fit was not the maximum: [`Profile::Higher`] gives the point, from which
//! the caller fits again.

use crate::candidates::parameter::Parameter;
use crate::errors::DiagnoseError;
use crate::likelihood::derivatives::{MAX_STEP, Objective, total};
use crate::likelihood::fit::{Fit, Interval, Options, TOLERANCE, adjustments, maximise};
use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// χ²₁'s 95th percentile.
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;
/// Relative accuracy of `D = q` at an end.
pub const ROOT_TOLERANCE: f64 = 0.05;
/// Most profile points per end.
pub const MAX_POINTS: usize = 12;

/// What a candidate's profile needs besides the fit and ℓ.
pub struct Problem<'a> {
    /// The parameters.
    pub parameters: &'a [Parameter],
    /// Maps internal coordinates onto the feasible set, keeping the coordinate given (if
    /// any) where it is.
    pub project: &'a dyn Fn(&mut [f64], Option<usize>),
    /// `c = 1 + n/N`.
    pub inflation: f64,
}

/// A candidate's profile intervals.
#[derive(Debug, Clone)]
pub struct Intervals {
    /// Each parameter's own 95 % interval (threshold `qⱼ`).
    pub marginal: Vec<Interval>,
    /// The joint 95 % region's projection on each parameter (threshold `q_k`; empty unless
    /// asked for).
    pub joint: Vec<Interval>,
    /// Evaluations of ℓ spent.
    pub evaluations: usize,
}

/// The outcome of [`profile_intervals`].
#[derive(Debug, Clone)]
pub enum Profile {
    /// The intervals.
    Intervals(Intervals),
    /// A point (internal coordinates) whose ℓ exceeds the fit's by more than the tolerance:
    /// fit again from there.
    Higher(Vec<f64>, usize),
}

/// One profile point: the fixed coordinate's value, `√D`, and the full point.
#[derive(Debug, Clone)]
struct Point {
    x: f64,
    root: f64,
    t: Vec<f64>,
}

/// How one end ended.
enum End {
    /// Internal coordinate of the end, and whether it is the range end.
    Found(f64, bool),
    /// Not found within [`MAX_POINTS`].
    Undetermined,
    /// A higher point.
    Higher(Vec<f64>),
}

struct Profiler<'p, 'f, 'a> {
    fit: &'p Fit,
    problem: &'p Problem<'p>,
    f: &'f mut Objective<'a>,
    evaluations: usize,
}

impl Profiler<'_, '_, '_> {
    /// ℓ_p at internal coordinate `x` of parameter `j`, started from `warm` (a full point);
    /// returns ℓ_p and the maximising point.
    fn at(&mut self, j: usize, x: f64, warm: &[f64]) -> Result<(f64, Vec<f64>), DiagnoseError> {
        let k = warm.len();
        let project = self.problem.project;
        let mut start = warm.to_vec();
        start[j] = x;
        project(&mut start, Some(j));
        start[j] = x;
        if k == 1 {
            self.evaluations += 1;
            return Ok((total(&(self.f)(&start)?), start));
        }
        let full = |s: &[f64]| -> Vec<f64> {
            let mut t = Vec::with_capacity(k);
            t.extend_from_slice(&s[..j]);
            t.push(x);
            t.extend_from_slice(&s[j..]);
            t
        };
        let drop_j = |t: &[f64]| -> Vec<f64> {
            t.iter()
                .enumerate()
                .filter(|&(i, _)| i != j)
                .map(|(_, &v)| v)
                .collect()
        };
        let sub_project = |s: &mut [f64]| {
            let mut t = full(s);
            project(&mut t, Some(j));
            s.copy_from_slice(&drop_j(&t));
        };
        let f = &mut *self.f;
        let mut sub_f = |s: &[f64]| f(&full(s));
        let steps = drop_j(&self.fit.steps);
        let inner = maximise(
            &drop_j(&start),
            Options {
                steps: Some(&steps),
                curvature: false,
                clusters: None,
                rough: false,
            },
            &sub_project,
            &mut sub_f,
        )?;
        self.evaluations += inner.evaluations;
        Ok((inner.log_likelihood, full(&inner.internal)))
    }

    /// One end of parameter `side.j`'s interval in direction `side.dir` (±1) for the
    /// threshold `q`; `side.points` holds the profile points found so far on that side (the
    /// fit first), from which a later, larger threshold starts.
    fn end(
        &mut self,
        side: &mut Side,
        q: f64,
        scale: f64,
        slope: &DVector<f64>,
    ) -> Result<End, DiagnoseError> {
        let (j, dir) = (side.j, side.dir);
        let fit = self.fit;
        let x0 = fit.internal[j];
        let limit = if dir > 0.0 { 1.0 - x0 } else { x0 };
        if limit <= 0.0 {
            return Ok(End::Found(x0, true));
        }
        let target = q.sqrt();
        if let Some(p) = side
            .points
            .iter()
            .find(|p| (p.root * p.root - q).abs() <= ROOT_TOLERANCE * q)
        {
            let x = refine(p, &side.points, target);
            return Ok(End::Found(x0 + dir * x.min(limit), x >= limit));
        }
        // The bracket so far: the farthest point below q, the nearest beyond it at or above.
        let below = |p: &&Point| p.root < target;
        let mut near = side
            .points
            .iter()
            .filter(below)
            .max_by(|a, b| a.x.total_cmp(&b.x))
            .expect("the fit is below q")
            .clone();
        if near.x >= limit {
            return Ok(End::Found(x0 + dir * limit, true));
        }
        let mut before = side
            .points
            .iter()
            .filter(below)
            .filter(|p| p.x < near.x)
            .max_by(|a, b| a.x.total_cmp(&b.x))
            .cloned();
        let mut far = side
            .points
            .iter()
            .filter(|p| p.root >= target && p.x > near.x)
            .min_by(|a, b| a.x.total_cmp(&b.x))
            .cloned();
        // Residuals √D − √q of the bracket's ends as regula falsi uses them (Illinois: the
        // residual of an end kept twice in a row is halved), and which end moved last.
        let mut residuals = (
            near.root - target,
            far.as_ref().map_or(0.0, |p| p.root - target),
        );
        let mut last_far = None;
        let mut delta = next_trial(
            &near,
            before.as_ref(),
            far.as_ref(),
            target,
            scale,
            limit,
            residuals,
        );
        for _ in 0..MAX_POINTS {
            if let Some(fp) = &far
                && fp.x - near.x <= 1e-3 * fp.x
            {
                break;
            }
            // Warm start: the nearest point found, moved along the quadratic prediction.
            let from = side
                .points
                .iter()
                .min_by(|a, b| (a.x - delta).abs().total_cmp(&(b.x - delta).abs()))
                .expect("the fit is a point");
            let mut warm = from.t.clone();
            let shift = dir * (delta - from.x);
            let mut m = 0;
            for (i, w) in warm.iter_mut().enumerate() {
                if i != j {
                    *w = (*w + slope[m] * shift).clamp(0.0, 1.0);
                    m += 1;
                }
            }
            let (lp, t) = self.at(j, x0 + dir * delta, &warm)?;
            if lp > fit.log_likelihood + TOLERANCE {
                return Ok(End::Higher(t));
            }
            let d = (2.0 * (fit.log_likelihood - lp)).max(0.0);
            let p = Point {
                x: delta,
                root: d.sqrt(),
                t,
            };
            if (d - q).abs() <= ROOT_TOLERANCE * q {
                let x = refine(&p, &side.points, target);
                side.points.push(p);
                return Ok(End::Found(x0 + dir * x.min(limit), x >= limit));
            }
            side.points.push(p.clone());
            if d < q {
                if far.is_none() && delta >= limit {
                    return Ok(End::Found(x0 + dir * limit, true));
                }
                residuals.0 = p.root - target;
                if last_far == Some(false) {
                    residuals.1 *= 0.5;
                }
                last_far = Some(false);
                before = Some(std::mem::replace(&mut near, p));
            } else {
                residuals.1 = p.root - target;
                if last_far == Some(true) {
                    residuals.0 *= 0.5;
                }
                last_far = Some(true);
                far = Some(p);
            }
            delta = next_trial(
                &near,
                before.as_ref(),
                far.as_ref(),
                target,
                scale,
                limit,
                residuals,
            );
        }
        Ok(match &far {
            Some(fp) => {
                let w = (target - near.root) / (fp.root - near.root);
                End::Found(x0 + dir * (near.x + w * (fp.x - near.x)), false)
            }
            None => End::Undetermined,
        })
    }
}

/// An end accepted at `p` (within the tolerance), moved to where the line through `p` and
/// the nearest other point found puts `√D = √q` (exact for a quadratic profile), by at most
/// a tenth of its distance from the fit.
fn refine(p: &Point, points: &[Point], target: f64) -> f64 {
    let other = points
        .iter()
        .filter(|o| o.x != p.x)
        .min_by(|a, b| (a.x - p.x).abs().total_cmp(&(b.x - p.x).abs()));
    match other {
        Some(o) if (p.root - o.root) * (p.x - o.x) > 0.0 => {
            let x = p.x + (target - p.root) * (p.x - o.x) / (p.root - o.root);
            x.clamp(0.9 * p.x, 1.1 * p.x)
        }
        _ => p.x,
    }
}

/// The profile points found on one side of one parameter's fit.
struct Side {
    j: usize,
    dir: f64,
    points: Vec<Point>,
}

/// The next trial distance from the fit (module doc): with a bracket, regula falsi on the
/// residuals given; without, the secant on √D through the two farthest points below the
/// threshold (the quadratic guess from the fit alone), moving out by 1.1 to 4 times.
fn next_trial(
    near: &Point,
    before: Option<&Point>,
    far: Option<&Point>,
    target: f64,
    scale: f64,
    limit: f64,
    (r_near, r_far): (f64, f64),
) -> f64 {
    if let Some(fp) = far {
        return near.x + (fp.x - near.x) * (-r_near) / (r_far - r_near);
    }
    let Some(b) = before else {
        return (target * scale).min(limit);
    };
    let slope = (near.root - b.root) / (near.x - b.x);
    let guess = if slope > 0.0 {
        near.x + (target - near.root) / slope
    } else {
        4.0 * near.x
    };
    guess.clamp(1.1 * near.x, 4.0 * near.x).min(limit)
}

/// The profile-likelihood intervals of every parameter at `fit` (module doc), and with
/// `joint` also the joint region's projections.
pub fn profile_intervals(
    fit: &Fit,
    problem: &Problem,
    f: &mut Objective,
    joint: bool,
) -> Result<Profile, DiagnoseError> {
    let all: Vec<usize> = (0..fit.internal.len()).collect();
    profile_some(fit, problem, f, joint, &all)
}

/// [`profile_intervals`] of the parameters `which` only (their intervals in that order).
pub fn profile_some(
    fit: &Fit,
    problem: &Problem,
    f: &mut Objective,
    joint: bool,
    which: &[usize],
) -> Result<Profile, DiagnoseError> {
    let k = fit.internal.len();
    let a = &fit.curvature;
    let a_inv = nalgebra::Cholesky::new(a.clone()).map(|c| c.inverse());
    let (mean, lambdas) = adjustments(fit).unwrap_or((1.0, vec![1.0; k]));
    let q_joint = ChiSquared::new(k as f64).expect("k ≥ 1").inverse_cdf(0.95)
        * problem.inflation
        * mean.max(1.0);
    let mut profiler = Profiler {
        fit,
        problem,
        f,
        evaluations: 0,
    };
    let mut marginal = Vec::with_capacity(k);
    let mut projected = Vec::with_capacity(k);
    for &j in which {
        let q = CHI2_1_95 * problem.inflation * lambdas[j].max(1.0);
        let scale = match &a_inv {
            Some(inv) => inv[(j, j)].sqrt(),
            None if a[(j, j)] > 0.0 => 1.0 / a[(j, j)].sqrt(),
            None => MAX_STEP,
        };
        let slope = conditional_slope(a, j);
        let mut sides = [-1.0, 1.0].map(|dir| Side {
            j,
            dir,
            points: vec![Point {
                x: 0.0,
                root: 0.0,
                t: fit.internal.clone(),
            }],
        });
        let p = &problem.parameters[j];
        let thresholds = if joint && k > 1 {
            vec![q, q_joint.max(q)]
        } else {
            vec![q]
        };
        for (n, &threshold) in thresholds.iter().enumerate() {
            let mut ends = [(None, false); 2];
            for (e, side) in ends.iter_mut().zip(sides.iter_mut()) {
                match profiler.end(side, threshold, scale, &slope)? {
                    End::Found(x, cut) => *e = (Some(x), cut),
                    End::Undetermined => {}
                    End::Higher(t) => return Ok(Profile::Higher(t, profiler.evaluations)),
                }
            }
            let interval = Interval {
                lower: ends[0].0.map(|x| p.value(x)),
                upper: ends[1].0.map(|x| p.value(x)),
                lower_at_range_end: ends[0].1,
                upper_at_range_end: ends[1].1,
                method: "profile",
                threshold: Some(threshold),
            };
            if n == 0 {
                marginal.push(interval);
            } else {
                projected.push(interval);
            }
        }
    }
    if joint && k == 1 {
        projected = marginal.clone();
    }
    Ok(Profile::Intervals(Intervals {
        marginal,
        joint: projected,
        evaluations: profiler.evaluations,
    }))
}

/// `−A₋ⱼ₋ⱼ⁻¹A₋ⱼⱼ`: how the other parameters' maximum moves with parameter `j` where ℓ is
/// quadratic (zero where `A₋ⱼ₋ⱼ` is not positive definite).
fn conditional_slope(a: &DMatrix<f64>, j: usize) -> DVector<f64> {
    let k = a.nrows();
    let others: Vec<usize> = (0..k).filter(|&i| i != j).collect();
    let sub = DMatrix::from_fn(k - 1, k - 1, |r, c| a[(others[r], others[c])]);
    let col = DVector::from_fn(k - 1, |r, _| a[(others[r], j)]);
    match nalgebra::Cholesky::new(sub) {
        Some(c) => -c.solve(&col),
        None => DVector::zeros(k - 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::likelihood::fit::wald_intervals;

    fn parameter(name: &str) -> Parameter {
        Parameter {
            name: name.into(),
            unit: "-",
            low: 0.0,
            high: 1.0,
            null: 0.5,
            log: false,
        }
    }

    /// Hand derivation: for a quadratic ℓ = −½δᵀAδ the profile of θⱼ is −½δⱼ²/(A⁻¹)ⱼⱼ, so
    /// with B = A (λⱼ = 1) the profile interval is t̂ⱼ ± 1.96·√(c·(A⁻¹)ⱼⱼ), the Wald interval,
    /// for correlated parameters too.
    #[test]
    fn a_quadratic_profile_gives_the_wald_interval() {
        let (m, s) = ([0.4, 0.6], 0.03);
        // Four units whose scores vary as the likelihood says (B = A): each the same
        // correlated quadratic about a shifted centre, the shifts summing to zero.
        let shifts = [[-s, 0.0], [s, 0.0], [0.0, -s], [0.0, s]];
        let q = |d: [f64; 2]| (d[0] * d[0] + d[1] * d[1] + 1.2 * d[0] * d[1]) / (2.0 * s * s);
        let mut f = |t: &[f64]| -> Result<Vec<f64>, DiagnoseError> {
            Ok(shifts
                .iter()
                .map(|u| -q([t[0] - m[0] - u[0], t[1] - m[1] - u[1]]) / 4.0)
                .collect())
        };
        let fit = maximise(&[0.5, 0.5], Options::default(), &|_| {}, &mut f).unwrap();
        let params = [parameter("a"), parameter("b")];
        let problem = Problem {
            parameters: &params,
            project: &|_, _| {},
            inflation: 1.05,
        };
        let Profile::Intervals(Intervals { marginal: iv, .. }) =
            profile_intervals(&fit, &problem, &mut f, false).unwrap()
        else {
            panic!("higher point on a quadratic");
        };
        // Wald with λ floored at 1, from the exact inverse curvature.
        let (_, lambdas) = adjustments(&fit).unwrap();
        let a_inv = nalgebra::Cholesky::new(fit.curvature.clone())
            .unwrap()
            .inverse();
        for j in 0..2 {
            let half = (CHI2_1_95 * 1.05 * lambdas[j].max(1.0) * a_inv[(j, j)]).sqrt();
            let (lo, hi) = (iv[j].lower.unwrap(), iv[j].upper.unwrap());
            // |D − q| ≤ 5 % of q: the end within 2.5 % of the half-width.
            assert!(
                (lo - (m[j] - half)).abs() < 0.025 * half,
                "{lo} vs {}",
                m[j] - half
            );
            assert!(
                (hi - (m[j] + half)).abs() < 0.025 * half,
                "{hi} vs {}",
                m[j] + half
            );
            assert_eq!(iv[j].method, "profile");
        }
        let w = wald_intervals(&fit, &params, 1.05);
        assert_eq!(w[0].method, "wald");
    }

    /// A skewed likelihood (ℓ = n·(ln t − t/t₀) in t, a scale whose likelihood is a Gamma's,
    /// maximal at t₀): the profile interval is where ℓ falls by q/2, found by hand with a
    /// root-finder, and is asymmetric; an end beyond the range is cut there and flagged.
    #[test]
    fn a_skewed_profile_and_a_cut_end() {
        let (n, t0) = (20.0, 0.3);
        let ell = |t: f64| n * (t.ln() - t / t0);
        // One unit only: B = 0, so λ = 1 after the floor.
        let mut f = |t: &[f64]| -> Result<Vec<f64>, DiagnoseError> { Ok(vec![ell(t[0])]) };
        let fit = maximise(&[0.5], Options::default(), &|_| {}, &mut f).unwrap();
        let params = [parameter("s")];
        let problem = Problem {
            parameters: &params,
            project: &|_, _| {},
            inflation: 1.0,
        };
        let Profile::Intervals(Intervals { marginal: iv, .. }) =
            profile_intervals(&fit, &problem, &mut f, false).unwrap()
        else {
            panic!("higher point");
        };
        let lmax = ell(t0);
        let solve = |mut a: f64, mut b: f64| {
            for _ in 0..100 {
                let c = 0.5 * (a + b);
                let g = |x: f64| 2.0 * (lmax - ell(x)) - CHI2_1_95;
                if g(a) * g(c) <= 0.0 {
                    b = c;
                } else {
                    a = c;
                }
            }
            0.5 * (a + b)
        };
        let (lo, hi) = (solve(1e-6, t0), solve(t0, 1.0));
        let (a, b) = (iv[0].lower.unwrap(), iv[0].upper.unwrap());
        // |D − q| ≤ 5 % of q at each end: the end within about 2.5 % of its distance from t̂.
        assert!((a - lo).abs() < 0.03 * (t0 - lo), "{a} vs {lo}");
        assert!((b - hi).abs() < 0.03 * (hi - t0), "{b} vs {hi}");
        assert!(hi - t0 > 1.2 * (t0 - lo), "not skewed: {lo} {hi}");
        assert!(!iv[0].at_range_end());
        // Less data (n = 1.5: D(1) = 3·(ln 0.3 − 1 + 1/0.3) = 3.39 < 3.84): the upper end
        // passes 1 and is cut there.
        let mut g = |t: &[f64]| -> Result<Vec<f64>, DiagnoseError> {
            Ok(vec![1.5 * (t[0].ln() - t[0] / t0)])
        };
        let fit = maximise(&[0.5], Options::default(), &|_| {}, &mut g).unwrap();
        let Profile::Intervals(Intervals { marginal: iv, .. }) =
            profile_intervals(&fit, &problem, &mut g, false).unwrap()
        else {
            panic!("higher point");
        };
        assert_eq!(iv[0].upper, Some(1.0));
        assert!(iv[0].upper_at_range_end && !iv[0].lower_at_range_end);
    }

    /// A fit that is not the maximum (ℓ = −(t − 0.5)²/(2·0.05²) "fitted" at 0.4, ℓ there
    /// 2 below the peak): the profile meets points above it and says so, with a point
    /// higher than the fit to start again from.
    #[test]
    fn a_profile_above_the_fit_asks_for_a_new_fit() {
        let s = 0.05;
        let mut f = |t: &[f64]| -> Result<Vec<f64>, DiagnoseError> {
            Ok(vec![-(t[0] - 0.5).powi(2) / (2.0 * s * s)])
        };
        let fit = Fit {
            internal: vec![0.4],
            log_likelihood: -2.0,
            curvature: DMatrix::from_element(1, 1, 1.0 / (s * s)),
            variability: DMatrix::from_element(1, 1, 0.0),
            steps: vec![0.01],
            evaluations: 0,
            iterations: 0,
        };
        let params = [parameter("a")];
        let problem = Problem {
            parameters: &params,
            project: &|_, _| {},
            inflation: 1.0,
        };
        match profile_intervals(&fit, &problem, &mut f, true).unwrap() {
            Profile::Higher(t, _) => assert!(f(&t).unwrap()[0] > -2.0 + TOLERANCE, "{t:?}"),
            Profile::Intervals(iv) => panic!("no higher point found: {iv:?}"),
        }
    }
}
