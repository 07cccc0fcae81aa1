//! # truss-tolerance: which members matter, and what tolerance each group should get
//!
//! `truss tolerance --job JOB --case CASE --target-angle 9.69e-5|--target-arcsec 20
//! [--percentile 95] [--cost GROUP=W …] [--fix GROUP=SIGMA …] --out DIR` answers three questions about a job's
//! case whose member groups have zero-mean length errors (σ in mm):
//!
//! 1. **Sensitivity** ([`sensitivity`]): each member's and each group's share of the variance
//!    of tan θ_x and tan θ_y, with bootstrap intervals, and each group's ∂θ_Pq/∂σ_g \[rad/mm\].
//! 2. **Allocation** ([`allocate`]): the per-group σ that meets `θ_Pq ≤ θ*` at the least cost
//!    `K = Σ_g w_g n_g / σ_g` (n_g members, weight w_g, default 1; `--fix` pins a group).
//! 3. **Verification** ([`verify`]): the allocated case is run (in-process, 20,000 samples by
//!    default) and its θ_Pq with a 95 % interval is checked against the target.
//! 4. **Budget** ([`study`]): where the job states an alignment budget (θ_P, decenter,
//!    despace), the allocation is held to every line and the common factor on its σ that
//!    meets them all is found, naming the line that binds.
//!
//! The sensitivity run has 4,000 samples by default (at least 1,000 and ten per member
//! with an error). Every run draws sample `k` of the case as the job does (its seed, the case
//! name, `k`), and the bootstraps are keyed by the job's seed and the sample index, so the
//! whole study is a function of the job and the options, not of the thread count.
//!
//! ## What the method rests on (units: mm, rad; arcsec only where labelled)
//!
//! **Homogeneity.** With no loads, effects or clearances the equilibrium depends on the length
//! errors `e` only, and the tilt `t = (tan θ_x, tan θ_y)` is positively homogeneous of
//! degree 1, `t(c·e) = c·t(e)` for `c > 0`, *if every length offset scales with `e`*. Drawing
//! sample `k` as `e_i = σ_g z_i` with `z` fixed by (seed, case, k), scaling every σ by `c`
//! then scales every sample's θ_P, θ_Pq and its bootstrap interval by `c`. The paper's
//! prism is homogeneous only approximately: Table 1's diagonals (537.4 mm) are 1.15 µm
//! shorter than the face diagonal 380·√2 mm, a fixed pre-tension that does not scale with σ,
//! so near a change of slack set a sample's θ_P does not follow a rescale of σ in exact
//! proportion. So a rescale is always followed by a new run.
//!
//! **Piecewise linearity.** Within one set of slack diagonals `t = J_s·e`; the set changes
//! with `e`. The sensitivity is therefore measured on the Monte Carlo draws at the case's own
//! σ (regression, [`sensitivity`]), not by a derivative at the nominal state, and the draws
//! are regenerated from the job's seed, never stored.
//!
//! **Gaussian tilt.** A linear function of independent errors of many members is nearly
//! Gaussian, `t ~ N(0, Σ)`, with `Σ(σ) = Σ_g σ_g² C_g` (`C_g` \[mm⁻²\] from the regression). Then
//! θ_Pq follows from Σ by Hoyt's law ([`percentile`]), which for an isotropic tilt
//! (`Σ = σ_t² I`, the prism by its 120° symmetry) is Rayleigh's law (paper eq. 28):
//!
//! ```text
//! tan θ_Pq = σ_t √(−2 ln(1 − q)),      σ_t² = Σ_g S_g σ_g²,   S_g = tr C_g / 2  [mm⁻²]
//! ```
//!
//! **Optimum.** Minimising `Σ_g w_g n_g / σ_g` subject to `Σ_g S_g σ_g² = V*` gives
//! `σ_g ∝ (w_g n_g / S_g)^{1/3}` (Lagrange; convex, so global; derivation in [`allocate`]).
//! Fixed groups use up `S_g σ_g²` of the budget first; if they alone reach the target, the
//! target is unreachable (an error naming them).
//!
//! **Correction by a one-dimensional rescale.** The model leaves out the nonlinear part of
//! the variance (reported as `nonlinear`) and the Gaussian approximation. So the allocation
//! is run, and the ratio `f = θ_Pq,upper(MC) / θ_Pq(model)` measured; the model's target
//! becomes `θ*(1 − 3·10⁻³)/f`, the allocation is redone (the free groups' σ ratios stay the
//! model's optimum; without fixed groups this is the homogeneity rescale
//! `σ ← σ·θ*(1 − 3·10⁻³)/θ_Pq,upper`) and run again, up to three runs in all, until the run
//! verifies ([`verify`]). The 3·10⁻³ keeps the residual non-homogeneity from tipping a
//! rescaled run over θ*. The common σ that meets the target (`uniform_sigma`) is found the
//! same way, from the model's common σ.
//!
//! **Group derivatives.** `∂θ_Pq/∂σ_g` is the model's derivative (central differences of the
//! Hoyt quantile) times the calibration `θ_Pq(MC)/θ_Pq(model)` at the case's σ, so that
//! Euler's relation `Σ_g σ_g ∂θ_Pq/∂σ_g = θ_Pq` holds for the measured value. In the
//! isotropic case `∂θ_Pq/∂σ_g ≈ θ_Pq · share_g / (σ_g · Σ_h share_h)`.
//!
//! ## Limits
//!
//! Cases with effects (gravity, a temperature field) or pin joints with clearance are
//! refused: the tilt is then not homogeneous in the errors. A group whose length error its
//! distribution cannot scale to a σ (one not zero-mean, or a constant: see
//! `truss_job::distribution::Kind::with_sigma`), or has σ = 0, is refused (its influence
//! cannot be measured). A group whose share is below 10⁻⁹ has an unbounded tolerance: refused unless
//! `--fix`ed. The regression's cost grows with the square of the number of members with
//! errors; it suits models of up to a few hundred.
//!
//! **Production lots.** A group's lot part (members of a lot share one draw) is a group of
//! the study of its own, `GROUP.lot`, held at its σ like a `--fix`ed group: its share of the
//! tilt's variance and its covariance come from the members' regression coefficients summed
//! over each lot ([`sensitivity`]), and the allocation spends what is left of the target on
//! the own parts ([`allocate`]). Its own part must have σ > 0 like any group's (the
//! regression needs the members' errors to differ within a lot).
//!
//! ## Output (in `--out DIR`)
//!
//! `allocated-job.json` (the input job, the case's σ replaced by the allocation),
//! `tolerance.json` ([`report`] documents its fields), `tolerance.md`, and the SVG plots
//! `shares-groups.svg` and `shares-members.svg` ([`plot`]): each written through a temporary
//! file and never through a link (a link, a non-file or a file this writer cannot prove it
//! wrote, crate `run-dir`, at any of these names is refused before the study runs), the directory locked while they are written, and listed in
//! `.truss-tolerance.manifest` (crate `run-dir`). `--cost` and `--fix` name each group once.

pub mod allocate;
pub mod errors;
pub mod options;
pub mod outcome;
pub mod percentile;
pub mod plot;
pub mod report;
pub mod sensitivity;
pub mod setup;
pub mod simulate;
pub mod study;
pub mod verify;

pub use errors::ToleranceError;
pub use options::{Options, TargetAngle};
pub use outcome::{GroupResult, Tolerance};
pub use study::run;
