//! Slack cables that carry nothing: the limit `r → 0` of the compression ratio, and
//! whether the top surface's tilt is framed by members or held by pretension alone.
//!
//! ## The limit
//!
//! The paper's diagonals carry no compression (Table 1: zero stiffness in compression). A
//! cable of compression ratio `r = 0` (the default) stands for that: the solver answers for
//! the limit `r → 0`. At `r = 0` a panel whose bracing is all slack is a mechanism, and a
//! stage whose members all carry nothing (its longerons loose in their holes, its diagonals
//! slack) is held by nothing: the equilibrium of `r = 0` is then not a point, and the answer
//! is the one the limit selects. What holds the top surface's tilt (the only thing a Monte
//! Carlo sample reports) decides how it is reached, once per model:
//!
//! - **Framed by bars** ([`crate::Structure::tilt_framed`]): where the model's two-sided
//!   members (bars: the prism's battens and longerons) hold the tilt by themselves, slack
//!   cables change it only through the racking of panels whose bracing is slack, which
//!   moves the top nodes sideways, not up: at second order. Such models solve at
//!   [`FRAMED_RATIO`], where the slack cables' stiffness also outweighs the compressed
//!   frames' negative geometric stiffness, so that such panels do not rack (which would
//!   cost iterations and change nothing the samples report). Tested: the θ_P of the paper's
//!   prism at `FRAMED_RATIO` and at 1e-8 differ by at most 2e-4 of the case's median θ_P,
//!   sample by sample.
//! - **Otherwise** (pin joints in free play, whose longerons are one-sided): a stage whose
//!   longerons float in their holes tilts with its slack diagonals, and any working ratio
//!   would set the answer through their stiffness `r·k`. Such models are solved at the
//!   limit itself: the equilibrium branch is continued from [`LIMIT_RATIO`] down by tenfold
//!   steps until an exact solve at `r = 0` (one-sided members as contact: a slack cable's
//!   compression stiffness exactly zero) reaches it without any member changing side. The
//!   limit is an equilibrium of `r = 0`: where members bear, theirs; where a panel's frame
//!   is compressed and its bracing slack, the state after it has racked until a diagonal
//!   engages; where a stage carries nothing at all, the position of least compression energy
//!   of its slack cables among the equilibria (the leading order of `r·Q` as `r → 0`).
//!   Tested against an independent reference solver (arbitrary precision, continuation to
//!   `r = 1e-30`) on samples of the paper's Fig. 16 case, and against hand-derived limits.
//!
//! A ratio given explicitly in a model file or job (any `r > 0`) is a model choice and is
//! used as it is.
//!
//! ## Floating
//!
//! In the limit, a stage held only by what pretension is left, or by nothing, sits wherever
//! friction, the diagonals' bending stiffness or the assembly left it: the model's answer
//! there rests on effects it leaves out, and a tiny force moves it. A sample is **floating**
//! when the members that bear at the limit (bars, taut cables, bearing joints; a one-sided
//! member at its kink carrying no more than the solve resolves counts as slack) do not hold
//! it: the tangent at the limit, with them alone and the geometric stiffness of their
//! forces, is not positive definite, so some stage moves under an arbitrarily small load
//! (its holding force is 0; see [`crate::SolveReport::floating`]). Models whose tilt is
//! framed by bars never float.

pub use crate::structure::{FRAMED_RATIO, LIMIT_RATIO};
