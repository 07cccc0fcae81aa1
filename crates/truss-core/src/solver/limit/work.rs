//! What the solver outside this module uses of it: the limit solver's buffers and the
//! noise band of a one-sided member's kink (a leaf: it imports nothing of the solver).

use super::reduced::Reduced;

/// A pivot at most this fraction of its row's diagonal is solved in the reduced space.
pub(crate) const SOFT_PIVOT: f64 = 1e-8;

/// A one-sided member within this fraction of the sample's largest initial stretch of its
/// kink is at its kink (the rounding of the elongations is below 1e-12 of it).
pub(crate) const KINK: f64 = 1e-9;

/// The limit solver's buffers.
#[derive(Debug, Clone, Default)]
pub(crate) struct LimitWork {
    /// The tangent's diagonal before factorisation.
    pub diag: Vec<f64>,
    /// The reduced space's directions `w_j`.
    pub w: Vec<Vec<f64>>,
    /// A step's right-hand side.
    pub rhs: Vec<f64>,
    /// The point of the last converged stage.
    pub saved: Vec<f64>,
    /// The reduced problem.
    pub reduced: Reduced,
}

impl LimitWork {
    /// Buffers for `free` unknowns.
    pub fn new(free: usize) -> Self {
        Self {
            diag: vec![0.0; free],
            w: Vec::new(),
            rhs: vec![0.0; free + 1],
            saved: vec![0.0; free + 1],
            reduced: Reduced::default(),
        }
    }
}
