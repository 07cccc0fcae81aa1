//! The line search: a bracket on the directional derivative of the energy with a
//! sufficient-decrease test, seeded by an exact minimiser of the piecewise quadratic model
//! along the line.

use super::evaluate::{dot_n, max_abs};
use super::lanes::{Evaluate, Kernels};
use super::{Evaluation, Solver};
use crate::SolveError;

/// A trial is accepted when `|φ'(α)| ≤ ETA·|φ'_min|`.
const ETA: f64 = 0.5;

/// Armijo's sufficient-decrease constant `c₁`.
const C1: f64 = 1e-4;

/// The rounding noise of `Π` at the floor, relative to `|Σ W| + |fᵀu|`.
const ENERGY_NOISE: f64 = 1e-11;

/// A step is at most this many times `max(‖u‖∞, s)` (and the fourfold growth of the
/// bracket's expansion).
const TRUST_GROWTH: f64 = 4.0;

/// A step moves a node by at most this fraction of the shortest member.
const TRUST_MEMBER_FRACTION: f64 = 0.2;

/// A chord step's first trial is the last chord step's secant root when it lies in
/// `(1/FIRST_TRIAL_RANGE, FIRST_TRIAL_RANGE)` (see [`Solver::first_trial`]).
const FIRST_TRIAL_RANGE: f64 = 4.0;

/// At most this many trial points per line search.
const MAX_TRIALS: u32 = 100;

impl Solver {
    /// Line search along `self.work.d` from `self.work.u` (see the module doc); moves `self.work.u`,
    /// `self.work.r` and `self.work.states` to the accepted point and returns α, its evaluation and
    /// `max |d|`. `chord`: the step's operator is older than the current point (see
    /// [`Solver::first_trial`]).
    ///
    /// Keeps a bracket: `a`, the largest α seen with `φ' < 0` and sufficient decrease, and
    /// `b`, the smallest α seen with `φ' > 0`, or without sufficient decrease, or a
    /// non-finite force (where a member would collapse). The trials are: the full step
    /// (unless `expand`; for a chord step, [`Solver::first_trial`]), then the minimiser
    /// predicted by [`Solver::predict_alpha`], then false position or bisection inside the
    /// bracket, or fourfold growth while there is no upper end. A trial is accepted when
    /// `|φ'(α)| ≤ η·|φ'_min|`, `φ'_min` the steepest descent rate seen (φ'(0) for a Newton
    /// step; larger along a direction of negative curvature, whose `φ'(0)` may be near
    /// zero), and the energy has fallen enough:
    ///
    /// ```text
    /// Π(u + α·d) ≤ Π(u) + c₁·α·φ'(0) + τ,    c₁ = 1e-4,
    /// τ = 1e-11·(|Σ W| + |fᵀu|)   (the rounding noise of Π at the floor)
    /// ```
    ///
    /// (Armijo's condition, blind below the noise τ, where φ' alone decides): without it a
    /// long step could cross a ridge of the energy and land on a worse point where φ' is
    /// small again. The step is also capped at a trust length, `4·max(‖u‖∞, s)` with `s`
    /// the sample's largest initial stretch, and a fifth of the shortest member. Returns an
    /// error, for the caller to damp its steps, when the direction does not descend
    /// (`φ'(0) ≥ 0`) or no acceptable α is found.
    pub(super) async fn line_search(
        &mut self,
        iteration: u32,
        current: Evaluation,
        expand: bool,
        chord: bool,
        kernels: Kernels<'_>,
    ) -> Result<(f64, Evaluation, f64), SolveError> {
        let n = self.structure.free;
        let phi0 = dot_n(&self.work.r[..n], &self.work.d[..n]);
        let d_max = max_abs(&self.work.d[..n]);
        let u_max = max_abs(&self.work.u[..n]);
        let trust = (TRUST_GROWTH * u_max.max(self.sample.scale))
            .min(TRUST_MEMBER_FRACTION * self.shortest_member());
        let cap = trust / d_max.max(f64::MIN_POSITIVE);
        let work0 = dot_n(&self.sample.loads[..n], &self.work.u[..n]);
        let energy0 = current.strain - work0;
        let noise = ENERGY_NOISE * (current.strain.abs() + work0.abs());
        if !expand && (phi0 >= 0.0 || phi0.is_nan()) {
            // Not a descent direction (a model step whose switched cables point it
            // uphill): the caller damps its steps, which makes the direction descend.
            return Err(SolveError::NotConverged {
                iterations: iteration,
                residual: current.residual,
                step: 0.0,
            });
        }
        let (mut a, mut phi_a) = (0.0, phi0);
        let (mut b, mut phi_b) = (f64::INFINITY, f64::INFINITY);
        let mut steepest = phi0.min(0.0);
        let mut side = 0i8;
        for trial in 0..MAX_TRIALS {
            let alpha = if trial == 0 && !expand {
                if chord && self.options.chord_secant {
                    self.first_trial(cap)
                } else {
                    1.0f64.min(cap)
                }
            } else if trial <= 1 {
                let predicted = self.predict_alpha(phi0, cap);
                if predicted > a && predicted < b {
                    predicted
                } else if b.is_finite() {
                    0.5 * (a + b)
                } else {
                    (TRUST_GROWTH * a).max(f64::MIN_POSITIVE).min(cap)
                }
            } else if !b.is_finite() {
                (TRUST_GROWTH * a).min(cap)
            } else if phi_b.is_finite() && phi_b > phi_a && side != 0 {
                (b - phi_b * (b - a) / (phi_b - phi_a))
                    .clamp(a + 1e-3 * (b - a), b - 1e-3 * (b - a))
            } else {
                0.5 * (a + b)
            };
            let eval = self.try_step(alpha, kernels).await;
            let phi = dot_n(&self.work.trial_r[..n], &self.work.d[..n]);
            let energy = eval.strain - dot_n(&self.sample.loads[..n], &self.work.trial_u[..n]);
            let decrease = energy <= energy0 + C1 * alpha * phi0.min(0.0) + noise;
            if phi.is_finite() && decrease {
                steepest = steepest.min(phi);
            }
            let descending = phi.is_finite() && phi < 0.0 && decrease;
            // Accept: close enough to a root; or a Newton step still descending (the next
            // iteration goes on from there); or the cap reached while still descending.
            // Always with sufficient decrease.
            let accept = phi.is_finite()
                && decrease
                && (phi.abs() <= ETA * steepest.abs()
                    || (trial == 0 && !expand && phi <= 0.0)
                    || (descending && alpha >= cap));
            if accept {
                // The root of φ' by the secant through φ'(0) and φ'(α), for the next chord
                // step (NaN: none; see `Solver::first_trial`).
                self.chord_secant = if chord {
                    alpha * phi0 / (phi0 - phi)
                } else {
                    f64::NAN
                };
                self.accept();
                return Ok((alpha, eval, d_max));
            }
            if descending {
                (a, phi_a) = (alpha, phi);
                if side == -1 {
                    phi_b *= 0.5;
                }
                side = -1;
            } else {
                // Past the minimum, over a ridge (no sufficient decrease: bisect), or a
                // collapsed member.
                (b, phi_b) = (alpha, if decrease { phi } else { f64::INFINITY });
                if side == 1 {
                    phi_a *= 0.5;
                }
                side = 1;
            }
            if b.is_finite() && b - a <= f64::EPSILON * b {
                break;
            }
        }
        Err(SolveError::NotConverged {
            iterations: iteration,
            residual: current.residual,
            step: a * d_max,
        })
    }

    /// The first trial of a step whose operator is older than the current point (a chord
    /// step): the secant minimiser of the last chord step,
    ///
    /// ```text
    /// α = α₀·φ₀'(0) / (φ₀'(0) − φ₀'(α₀))    (α₀, φ₀': the last chord step's)
    /// ```
    ///
    /// when it lies in `(1/FIRST_TRIAL_RANGE, FIRST_TRIAL_RANGE)`, else the full step. A
    /// chord step `d = −M⁻¹r` with an earlier tangent `M` is too short (or long) by the
    /// same factor along the directions in which the tangent changed since (a panel whose
    /// bracing is slack, whose stiffness the geometric terms set): the last step measured
    /// that factor along its own line, and the next step's error lies mostly along the
    /// same directions. Costs nothing: φ' at the accepted point is computed anyway.
    fn first_trial(&self, cap: f64) -> f64 {
        let a = self.chord_secant;
        if a > 1.0 / FIRST_TRIAL_RANGE && a < FIRST_TRIAL_RANGE {
            a.min(cap)
        } else {
            1.0f64.min(cap)
        }
    }

    /// Predicts the minimiser of `φ(α) = Π(u + α·d)` in `(0, cap]` from a piecewise
    /// quadratic model: `φ''` starts at `dᵀK(u)d` (with the geometric stiffness) and jumps
    /// by `±(1 − r)·k·(n·Δd)²` where a one-sided member's linearised elongation `e + α·(n·Δd)` changes
    /// sign. The breakpoints
    /// are walked in order from `φ'(0)` to the first root of `φ'`.
    pub(super) fn predict_alpha(&mut self, phi0: f64, cap: f64) -> f64 {
        let d = &self.work.d;
        let mut curvature = 0.0;
        self.work.breakpoints.clear();
        for (((c, st), m), &k) in self
            .structure
            .members
            .iter()
            .zip(&self.work.states)
            .zip(&self.sample.members)
            .zip(&self.sample.tension)
        {
            let dv = [
                d[c.link.dofs[3]] - d[c.link.dofs[0]],
                d[c.link.dofs[4]] - d[c.link.dofs[1]],
                d[c.link.dofs[5]] - d[c.link.dofs[2]],
            ];
            let along = st.direction[0] * dv[0] + st.direction[1] * dv[1] + st.direction[2] * dv[2];
            let total = dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2];
            curvature +=
                st.stiffness * along * along + st.force / st.length * (total - along * along);
            if c.is_cable && along != 0.0 {
                let at = -st.elongation / along;
                if at > 0.0 && at < cap {
                    let jump = (1.0 - m.compression_ratio) * k * along * along;
                    // Slack → taut stiffens; taut → slack softens.
                    self.work
                        .breakpoints
                        .push((at, if st.slack { jump } else { -jump }));
                }
            }
        }
        self.work
            .breakpoints
            .sort_unstable_by(|x, y| x.0.partial_cmp(&y.0).unwrap_or(std::cmp::Ordering::Equal));
        let (mut alpha, mut slope, mut phi) = (0.0, curvature, phi0);
        for &(at, jump) in &self.work.breakpoints {
            if slope > 0.0 {
                let root = alpha - phi / slope;
                if root <= at {
                    return root.max(0.0);
                }
            }
            phi += slope * (at - alpha);
            alpha = at;
            slope += jump;
        }
        if slope > 0.0 {
            (alpha - phi / slope).clamp(0.0, cap)
        } else {
            cap
        }
    }

    /// Evaluates the trial point `u + α·d` into the trial buffers.
    pub(super) async fn try_step(&mut self, alpha: f64, kernels: Kernels<'_>) -> Evaluation {
        self.evaluations += 1;
        for ((t, u), d) in self
            .work
            .trial_u
            .iter_mut()
            .zip(&self.work.u)
            .zip(&self.work.d)
        {
            *t = u + alpha * d;
        }
        kernels
            .evaluate(Evaluate {
                structure: &self.structure,
                key: self.sample_key,
                members: &mut self.sample.members,
                tension: &mut self.sample.tension,
                loads: &mut self.sample.loads,
                u: &mut self.work.trial_u,
                r: &mut self.work.trial_r,
                states: &mut self.work.trial_states,
            })
            .await
    }

    /// Makes the trial point current.
    pub(super) fn accept(&mut self) {
        std::mem::swap(&mut self.work.u, &mut self.work.trial_u);
        std::mem::swap(&mut self.work.r, &mut self.work.trial_r);
        std::mem::swap(&mut self.work.states, &mut self.work.trial_states);
    }

    pub(super) fn shortest_member(&self) -> f64 {
        self.shortest
    }
}
