//! The pin joint with backlash (the paper's section 4.1): a batten's shaft in a longeron's
//! hole, with free play. A loose pin carries no force; a loaded pin sits on its hole's edge.
//!
//! ## Geometry and physics
//!
//! A joint joins two nodes that nominally coincide: the *shaft* node, at the centre of the
//! batten's shaft, and the *hole* node, at the centre of one member end's hole (a longeron's,
//! in the paper's truss). The hole is wider than the shaft by the clearance `g` \[mm\], so the
//! shaft can sit anywhere within `g` of the hole's centre across the shaft's axis `a`, and
//! there it transmits **no force**. A shaft that transmits a force `F` \[N\] is pressed
//! against the hole's edge in the direction of that force, penetrating it by `F/k_t`
//! (`k_t` the contact stiffness, by default 10⁵ times the member's `E·A/L₀`, the paper's
//! virtual cable's tension stiffness). Along the axis the shaft is held by the fitting's
//! shoulders, with no play: the paper considers backlash across the shaft only.
//!
//! ## One hole, one member end
//!
//! Every member end has its own hole: in a deployable mast each stage's longerons are
//! separate members, so a node between two stages holds two joints (the longeron below's
//! hole and the longeron above's) on the batten's shaft, with independent clearances. A hole
//! node therefore carries exactly one member, and the model checks this (see
//! [`crate::model`]). That member is a pin-ended bar, perpendicular to the shaft's axis as in
//! any clevis, so the force through the hole is the member's axial force `N` along the
//! member's direction `n`, which lies across the axis.
//!
//! ## Exact condensation: a member with a dead band
//!
//! Take a member of natural length `L₀` and axial stiffness `k = E·A/L₀` whose ends `i`, `j`
//! sit in holes of clearances `g_i`, `g_j` (`g = 0` and `k_t = ∞` for an end without a joint)
//! on shafts a distance `ℓ` apart. With `N ≠ 0` both shafts bear on their holes' edges along
//! `n`, so the holes are offset from the shafts by `Δ_i = (sgn N·g_i + N/k_t,i)·n` and
//! `Δ_j = −(sgn N·g_j + N/k_t,j)·n`, and `ℓ = L₀ + N/k + Σ (sgn N·g + N/k_t)`. With
//! `e = ℓ − L₀`, the total clearance `G = g_i + g_j` and the series stiffness
//! `k_s = 1/(1/k + Σ 1/k_t)`:
//!
//! ```text
//! N = k_s·(e − G)   for e > G        (tension: both holes pulled onto their shafts)
//! N = 0             for |e| ≤ G      (free play: the shafts move freely in their holes)
//! N = k_s·(e + G)   for e < −G       (compression)
//! ```
//!
//! a bar with a dead band of width `2G`, acting between the two *shaft* nodes. Its energy
//! `W = ½·k_s·⟨|e| − G⟩₊²` is convex and continuously differentiable, and it is the sum of
//! two one-sided members in parallel between the shafts: a tension-only one of natural
//! length `L₀ + G` and a compression-only one of natural length `L₀ − G`, both of stiffness
//! `k_s` (see [`crate::element`]). So the solver never sees the hole nodes: they are
//! eliminated exactly, the truss keeps the degrees of freedom it has without backlash, and
//! which joints bear is found by the same active-set steps that find the slack cables.
//! After a solve each hole is put back, at the offsets above; a loose member's slip `e` is
//! shared between its holes in proportion to their clearances, one of the positions that are
//! all in equilibrium (the statics does not fix it), and the joint is reported loose.
//!
//! The dead band needs no stiffness: `N = 0` there is the physical limit. A regularisation
//! `k_c = r·k_t` per joint (`r` the joint's `compression_ratio`, default 0) may be kept for
//! studies; it adds the joints' `k_c` in series, `k_r = 1/Σ(1/k_c)`, across the whole range
//! of `e` (each half carries `k_r/2` on its slack side). What does not depend on the
//! regularisation is shown in REPRODUCTION.md.
//!
//! Neglected, and why: the shaft axis's component of `n` (the member rotates out of the
//! plane across the axis by the deformation's rotation, about 1e-4 rad, which shortens the
//! dead band by a relative 1e-8) and the joints' compliance along the axis.

/// Default contact stiffness of a joint: this many times the axial stiffness `E·A/L₀` of
/// the stiffest member at its nodes (the paper's 10⁵).
pub const DEFAULT_JOINT_TENSION_FACTOR: f64 = 1e5;

/// Default regularisation of a loose joint, `k_c/k_t`: none, the physical limit (a loose
/// pin carries no force).
pub const DEFAULT_JOINT_COMPRESSION_RATIO: f64 = 0.0;

/// A joint's state at an equilibrium, reconstructed from its member's (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointState {
    /// `Δ`, the hole centre's offset from the shaft centre \[mm\].
    pub offset: [f64; 3],
    /// `|Δ|` \[mm\]: the clearance plus the penetration `F/k_t` when the joint bears.
    pub distance: f64,
    /// The force the joint exerts on the shaft node \[N\] (its negative acts on the hole).
    pub force: [f64; 3],
    /// Contact force `|F|` \[N\]: zero for a loose joint.
    pub contact: f64,
    /// Whether the shaft bears on the hole's edge.
    pub engaged: bool,
}

/// A joint's state as the tools print it per joint id (`truss solve`, `mc-shard reproduce
/// --detail`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct JointSummary {
    /// Hole centre minus shaft centre \[mm\].
    pub offset: [f64; 3],
    /// Contact force \[N\]; 0 when loose.
    pub contact: f64,
    /// Whether the pin is loose in its hole (carries no force).
    pub loose: bool,
}

impl From<JointState> for JointSummary {
    fn from(st: JointState) -> Self {
        Self {
            offset: st.offset,
            contact: st.contact,
            loose: !st.engaged,
        }
    }
}

/// One end of a member with a dead band, for [`joint_state`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JointEnd {
    /// Whether the joint is at the member's first node `i` (else at `j`).
    pub at_start: bool,
    /// Its clearance `g` \[mm\].
    pub clearance: f64,
    /// Its contact stiffness `k_t` \[N/mm\].
    pub tension_stiffness: f64,
}

/// The member's side of [`joint_state`]: its state at the equilibrium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BandState {
    /// Current unit direction `n` from node `i` to node `j`.
    pub direction: [f64; 3],
    /// Axial force `N`, tension positive \[N\].
    pub force: f64,
    /// `e = ℓ − L₀` \[mm\], the shafts' distance over the member's natural length.
    pub elongation: f64,
    /// Total clearance `G` of the member's joints \[mm\].
    pub total_clearance: f64,
    /// Whether the member bears (one of its halves taut): `|e| ≥ G`.
    pub bearing: bool,
}

/// The joint at `end` of a member in state `m` (module doc): a bearing joint's offset is
/// `(sgn N·g + N/k_t)` along `n` at the start, the opposite at the end, which is `g` plus
/// the penetration along the force the joint exerts on its shaft; a loose joint takes the
/// share `g/G` of the slip `e` and exerts no force.
pub(crate) fn joint_state(end: JointEnd, m: BandState) -> JointState {
    let side = if end.at_start { 1.0 } else { -1.0 };
    let (along, contact) = if m.bearing {
        let sign = if m.force < 0.0 { -1.0 } else { 1.0 };
        (
            side * (sign * end.clearance + m.force / end.tension_stiffness),
            m.force.abs(),
        )
    } else if m.total_clearance > 0.0 {
        (side * m.elongation * end.clearance / m.total_clearance, 0.0)
    } else {
        (0.0, 0.0)
    };
    let n = m.direction;
    let transmitted = if m.bearing { side * m.force } else { 0.0 };
    JointState {
        offset: n.map(|x| along * x),
        distance: along.abs(),
        force: n.map(|x| transmitted * x),
        contact,
        engaged: m.bearing,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn end(at_start: bool, g: f64) -> JointEnd {
        JointEnd {
            at_start,
            clearance: g,
            tension_stiffness: 2.7e8,
        }
    }

    /// Hand check of the module doc's kinematics: shafts at `ℓ = L₀ + N/k + Σ(sgn N·g +
    /// N/k_t)` are the holes' distance `L₀ + N/k` plus the two offsets along `n`, in tension
    /// and in compression; each offset points along the force on its shaft.
    #[test]
    fn bearing_offsets_close_the_member() {
        let n = [0.0, 0.6, 0.8];
        let (gi, gj, k, l0) = (0.004, 0.013, 2745.0, 380.0);
        for force in [3.5, -7.25] {
            let (a, b) = (end(true, gi), end(false, gj));
            let sign: f64 = if force < 0.0 { -1.0 } else { 1.0 };
            let ell = l0
                + force / k
                + sign * (gi + gj)
                + force / a.tension_stiffness
                + force / b.tension_stiffness;
            let m = BandState {
                direction: n,
                force,
                elongation: ell - l0,
                total_clearance: gi + gj,
                bearing: true,
            };
            let (si, sj) = (joint_state(a, m), joint_state(b, m));
            // Shaft j − shaft i along n = (hole j − Δ_j) − (hole i − Δ_i).
            let holes = l0 + force / k;
            let shafts = holes - sj.offset[2] / n[2] + si.offset[2] / n[2];
            assert!((shafts - ell).abs() < 1e-12, "{shafts} vs {ell}");
            for (st, g) in [(si, gi), (sj, gj)] {
                assert!(st.engaged);
                assert!((st.distance - (g + force.abs() / 2.7e8)).abs() < 1e-15);
                assert_eq!(st.contact, force.abs());
                let along: f64 = (0..3).map(|d| st.offset[d] * st.force[d]).sum();
                assert!(along > 0.0, "offset along the force on the shaft");
            }
        }
    }

    /// A loose member's slip is shared in proportion to the clearances, each within its
    /// clearance, with no force.
    #[test]
    fn loose_joints_share_the_slip() {
        let m = BandState {
            direction: [1.0, 0.0, 0.0],
            force: 0.0,
            elongation: -0.01,
            total_clearance: 0.02,
            bearing: false,
        };
        let (a, b) = (
            joint_state(end(true, 0.005), m),
            joint_state(end(false, 0.015), m),
        );
        assert!((a.offset[0] + 0.0025).abs() < 1e-15 && a.offset[1..] == [0.0, 0.0]);
        assert!((b.offset[0] - 0.0075).abs() < 1e-15 && b.offset[1..] == [0.0, 0.0]);
        assert!(!a.engaged && a.contact == 0.0 && a.force == [0.0; 3]);
        // Shafts' distance = holes' distance (L₀) − Δ_j + Δ_i = L₀ + e.
        assert!((a.offset[0] - b.offset[0] - m.elongation).abs() < 1e-15);
    }
}
