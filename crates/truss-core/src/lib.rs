//! # truss-core: static equilibrium of a pin-jointed truss with tension-only cables
//!
//! The solver behind truss-mc. Given a truss model (nodes, members, supports, loads) and a
//! small error in each member's length, it finds the static equilibrium with full geometric
//! nonlinearity and measures how far the top surface tilts: the distortion angle θ_P of
//! Kobayashi et al., "Effect of Member Length Uncertainty and Backlash on Deformation Accuracy
//! for a High-Precision Space Truss Structure" (Trans. JSASS, 2021), here called "the paper".
//!
//! ## Units
//!
//! Every number in this crate, its model file and its outputs is in these units. The paper
//! gives Young's modulus in GPa: 70 GPa is written 70 000 MPa.
//!
//! | quantity            | unit            | examples                                   |
//! |---------------------|-----------------|--------------------------------------------|
//! | length, position    | mm              | `xyz`, `natural_length`, displacements     |
//! | area                | mm²             | `area`                                     |
//! | Young's modulus     | MPa = N/mm²     | `youngs_modulus`                           |
//! | force               | N               | `loads`, axial forces, residuals           |
//! | stiffness           | N/mm            | tangent stiffness entries, joint stiffness |
//! | clearance           | mm              | a joint's `clearance` (hole minus shaft diameter) |
//! | energy              | N·mm            | total potential energy                     |
//! | angle               | rad             | θ_P; tan θ_x and tan θ_y are dimensionless |
//!
//! ## Sign convention
//!
//! Axial force is positive in tension. A member's *length error* is its natural
//! (stress-free) length minus its nominal length: a positive error is a member made too long.
//! Displacements are measured from the nodes' nominal positions in the model file.
//!
//! ## Formulation
//!
//! Each member `m` joining nodes `i → j` with nominal vector `D = X_j − X_i` (length `L_r`),
//! natural length `L₀`, axial stiffness `k = E·A/L₀` and displacements `u` has current vector
//! `c = D + u_j − u_i`, current length `L = |c|` and elongation
//!
//! ```text
//! e = L − L₀ = (2 D·(u_j − u_i) + |u_j − u_i|²) / (L + L_r) + (L_r − L₀)
//! ```
//!
//! written so that no two nearly equal lengths are ever subtracted: the imperfections of
//! interest are micrometres on 380 mm members, and the naive `|c| − L₀` would lose six of the
//! sixteen digits. The axial force is `N = k_e·e` (engineering strain against the natural
//! length), where `k_e = k`, except for a slack cable (`e < 0`), where `k_e = r·k` with the
//! cable's small compression stiffness ratio `r` (see [`Behaviour`]). The member's strain
//! energy is `W = ½·k_e·e²`, continuously differentiable in `u`; equilibrium is the stationary
//! point of the total potential energy `Π(u) = Σ W_m − fᵀu`, found by Newton's method with a
//! line search ([`solver`]).
//!
//! Pin joints with backlash (the paper's section 4, see [`joint`]) have free play: a loose
//! pin carries no force, a loaded pin bears on its hole's edge. Every member end has its own
//! hole (two joints at each node between two stages of the prism), so a hole node carries
//! one member and is eliminated exactly: the member and its joints become a bar with a dead
//! band of the joints' total clearance, a tension-only and a compression-only half in
//! parallel, and which joints bear is found like the slack cables. Model files list joints
//! under `joints`; the prism generator adds one per longeron end with
//! [`prism::PrismOptions::backlash`].
//!
//! ## Distortion angle
//!
//! The top surface's normal `n_t = (p₂ − p₁) × (p₃ − p₁)` of its three nodes, and
//! `θ_P = atan2(|n_t × n_b|, n_t·n_b)` against the reference normal `n_b` (paper eq. 2,
//! computed with `atan2` instead of the paper's `acos`, which loses half the digits of an
//! angle of 1e-5 rad), with `tan θ_x = −n_tx/n_tz` and `tan θ_y = −n_ty/n_tz` (eqs. 6, 8, 9).
//! See [`measure`].
//!
//! ## Decenter and despace
//!
//! The top centroid's displacement against the bottom's (the supported nodes'),
//! `δ = (u₁ + u₂ + u₃)/3 − Σ s_k/m` \[mm\], in the bottom's frame: `decenter_x = δ·e_x`,
//! `decenter_y = δ·e_y` (the shift in the bottom plane, `e_x`, `e_y` perpendicular to `n_b`),
//! `decenter = √(decenter_x² + decenter_y²)`, and `despace = δ·n_b` (along the normal,
//! signed). See [`measure::placement`] and [`output::placement`].
//!
//! ## Reproducibility
//!
//! The solver uses only IEEE-754 arithmetic in a fixed order, a block-banded Cholesky of
//! our own (no run-time SIMD dispatch), and the pure-Rust `libm` for `atan2`, so the same
//! input gives the same bits on every x86-64 machine, whatever the thread count.

pub mod block;
mod capacitance;
pub mod element;
mod errors;
pub mod joint;
pub mod limit;
mod linearised;
pub mod measure;
pub mod model;
pub mod model_file;
mod model_read;
mod ordering;
pub mod output;
pub mod prism;
pub mod prism_spec;
pub mod solver;
mod structure;

pub use errors::{InputRefusal, ModelError, SolveError, readable};
pub use measure::{Distortion, Placement, distortion, placement};
pub use model::{Behaviour, Joint, Member, Model, Node, TopSurface};
pub use model_file::ModelFile;
pub use solver::{Equilibrium, IterationRecord, SolveOptions, SolveReport, Solver};
pub use structure::Structure;

/// Default compression stiffness ratio of a cable: 0, the paper's (Table 1: a diagonal
/// carries nothing in compression).
///
/// A cable of ratio 0 is solved as the limit `r → 0`: at a small working ratio where the
/// model's bars frame the top surface's tilt, and otherwise at `r = 0` itself, by
/// continuation (see [`limit`], which says how and what is tested). Where some stage is
/// held by nothing in that limit, the sample is reported *floating*
/// ([`SolveReport::floating`]). A ratio above 0 in a model file or job is a model choice and
/// is used as it is.
pub const DEFAULT_COMPRESSION_RATIO: f64 = 0.0;

/// The largest length error this model answers for, as a fraction of the member's natural
/// length: `|e| ≤ 0.01·L₀` (3.8 mm on the paper's 380 mm members).
///
/// The member law is linear elastic in the engineering strain, `N = E·A·(L − L₀)/L₀`, with
/// no yield. In a statically indeterminate truss (the prism, with its pretensioned
/// diagonals) a member made `e` too long cannot take its length freely: the others hold it,
/// and the mismatch becomes strain of the order of `e/L₀` shared among the members of the
/// closed loops it sits in. The elastic strain limit `σ_y/E` of structural metals is at most
/// about 1 %: 0.12 % for structural steel (250 MPa / 200 GPa), 0.4 % for 6061-T6 aluminium
/// (275 MPa / 69 GPa), 0.8 % for Ti-6Al-4V (880 MPa / 114 GPa). An error of more than 1 %
/// of the length could only be taken up by yielding, which the model does not represent,
/// so its answer would be meaningless (an equilibrium that "converges" with displacements
/// of hundreds of mm and forces of kN); and a member 1 % off is not a tolerance but another
/// design, to be written as its own natural length in a model file. The bound refuses only
/// the meaningless: the paper's σ are below 0.1 mm, 0.03 % of a member.
pub const MAX_LENGTH_ERROR_FRACTION: f64 = 0.01;
