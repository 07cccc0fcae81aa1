//! Slack cables that carry nothing: the limit `r → 0` of the compression ratio, and
//! whether the top surface's tilt is framed by members or held by pretension alone.
//!
//! ## The limit
//!
//! The paper's diagonals carry no compression (Table 1: zero stiffness in compression). A
//! cable of compression ratio `r = 0` (the default) stands for that: the solver answers for
//! the limit `r → 0`. It cannot solve at `r = 0` itself: a panel whose bracing is all slack
//! is then a mechanism, and a stage whose members all carry nothing (its longerons loose in
//! their holes, its diagonals slack) is held by nothing, so its position is not determined
//! by the equilibrium; the limit is the position that `r → 0` selects. So a cable of ratio
//! 0 is solved at a small working ratio, chosen once per model by what holds the top
//! surface's tilt, the only thing a Monte Carlo sample reports:
//!
//! - **Framed by bars** ([`crate::Structure::tilt_framed`]): where the model's two-sided members (bars:
//!   the prism's battens and longerons) hold the tilt by themselves, slack cables change it
//!   only through the racking of panels whose bracing is slack, which moves the top nodes
//!   sideways, not up: at second order. Such models solve at [`FRAMED_RATIO`], where the
//!   slack cables' stiffness also outweighs the compressed frames' negative geometric
//!   stiffness, so that such panels do not rack (which would cost iterations and change
//!   nothing the samples report). Tested: the θ_P of the paper's prism at `FRAMED_RATIO` and
//!   at [`LIMIT_RATIO`]/10 differ by at most 2e-4 of the case's median θ_P, sample by sample.
//! - **Otherwise** (pin joints in free play, whose longerons are one-sided): a stage whose
//!   longerons float in their holes tilts with its slack diagonals, and their stiffness
//!   `r·k` sets the answer unless it is negligible. Such models solve at [`LIMIT_RATIO`],
//!   where `r·k` is 4e-5 N/mm for the paper's diagonals: below the geometric stiffness of
//!   any pretension left (`N/L`, 3e-3 N/mm for 1 N on a 380 mm member) and, where nothing is
//!   left, small enough that its only role is to pick the limit's position. Tested: the
//!   paper's Fig. 16 case against `LIMIT_RATIO`/10 and /1000.
//!
//! A ratio given explicitly in a model file or job (any `r > 0`) is a model choice and is
//! used as it is.
//!
//! ## Floating
//!
//! In the limit, a stage held only by what pretension is left, or by nothing, sits wherever
//! friction, the diagonals' bending stiffness or the assembly left it: the model's answer
//! there rests on effects it leaves out, and a tiny force moves it. A sample is **floating**
//! when, under a load that tilts the top surface, the members that bear (bars, taut cables,
//! bearing joints) take less than half of the work, the rest going to slack cables: some
//! stage's tilt is then held by pretension or regularisation alone (see
//! [`crate::SolveReport::floating`]). Models whose tilt is framed by bars never float.

pub use crate::structure::{FRAMED_RATIO, LIMIT_RATIO};
