//! What the holding force of a converged sample is made of (computed by the `holding`
//! module): the force, the load that reaches it, and the limit it reaches.

/// The move of θ_P that defines the holding force, as a fraction of θ_P.
pub const HOLDING_FRACTION: f64 = 0.01;

/// What limits a sample's holding force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HoldingLimit {
    /// θ_P moves by [`HOLDING_FRACTION`] of itself.
    Tilt,
    /// This member (compiled index: a model member, or the compression-only half of a
    /// member in clearance holes after the model's members) stops bearing.
    Release {
        /// The member's compiled index.
        member: usize,
    },
    /// The tangent at the equilibrium is not positive definite.
    Unstable,
}

/// The holding force of a converged sample and the load that reaches it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Holding {
    /// `F_hold` \[N\].
    pub force: f64,
    /// The model index of the top node the load acts on.
    pub node: usize,
    /// The load's unit direction.
    pub direction: [f64; 3],
    /// Which limit it reaches first.
    pub limit: HoldingLimit,
}
