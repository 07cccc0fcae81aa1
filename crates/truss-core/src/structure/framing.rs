//! Stage 4 of compiling (after the factorisation of `K₀`): whether the bars frame the top
//! surface's tilt, and from it the working compression ratio of the cables of ratio 0. What
//! the ratios stand for and how they are tested is [`crate::limit`]'s doc; they live here, below
//! the compiler that applies them, so that the compiler imports nothing that imports it.

use super::{FIXED, Structure};
use crate::block::BlockBandMatrix;
use crate::measure::distortion;

/// The working compression ratio of a cable of ratio 0 in a model whose top surface's tilt
/// is framed by bars (see [`crate::limit`]).
pub const FRAMED_RATIO: f64 = 1e-4;

/// Where the tilt is not framed by bars, the compression ratio from which the limit `r → 0`
/// of a cable of ratio 0 is continued (see [`crate::limit`]): such cables are compiled with
/// it, and it is the first stage of the solver's continuation.
pub const LIMIT_RATIO: f64 = 1e-5;

/// A one-sided member's stiffness factor in [`tilt_framed_by_bars`]'s bars-only stiffness:
/// small enough to leave its mechanisms free, large enough to keep the matrix factorisable.
const ONE_SIDED_PROBE: f64 = 1e-9;

/// The tilt is framed by bars when their tilt compliance is at most this many times that of
/// every member together.
const FRAMED_COMPLIANCE: f64 = 4.0;

/// The loads that tilt the top surface: the gradients of tan θ_x and of tan θ_y with respect
/// to the free displacements at `u` (central differences, step a millionth of the shortest
/// member), written into `loads[0]` and `loads[1]` (length `free + 1`, zero slot last).
/// `None` without a top surface, or where a top node is a hole node (its position is its
/// joint's, not an unknown).
pub(crate) fn tilt_loads(s: &Structure, u: &[f64], loads: &mut [Vec<f64>; 2]) -> Option<()> {
    let top = s.top_surface.as_ref()?;
    if top.nodes.iter().any(|&i| s.hole_joint[i].is_some()) {
        return None;
    }
    let x = top.nodes.map(|i| s.node_xyz[i]);
    let dofs = top.nodes.map(|i| s.node_dofs[i]);
    let at = dofs.map(|d| d.map(|d| if d == FIXED { 0.0 } else { u[d as usize] }));
    let h = 1e-6 * s.shortest_member();
    for load in loads.iter_mut() {
        load.fill(0.0);
    }
    for (node, d) in dofs.iter().enumerate() {
        for dir in 0..3 {
            if d[dir] == FIXED {
                continue;
            }
            let (mut up, mut down) = (at, at);
            up[node][dir] += h;
            down[node][dir] -= h;
            let a = distortion(x, up, top.reference_normal);
            let b = distortion(x, down, top.reference_normal);
            loads[0][d[dir] as usize] = (a.tan_theta_x - b.tan_theta_x) / (2.0 * h);
            loads[1][d[dir] as usize] = (a.tan_theta_y - b.tan_theta_y) / (2.0 * h);
        }
    }
    Some(())
}

/// Whether the model's two-sided members hold the top surface's tilt by themselves: with
/// every one-sided member (cables, the halves of members in clearance holes) all but removed
/// (a factor of 1e-9 on its stiffness), the tilt compliance `gᵀK⁻¹g` of each tilting load
/// `g` ([`tilt_loads`] at the nominal geometry) is at most four times that of the all-taut
/// material stiffness `K₀`. False without a top surface.
fn tilt_framed_by_bars(s: &Structure) -> bool {
    let n = s.free;
    let mut loads = [vec![0.0; n + 1], vec![0.0; n + 1]];
    if tilt_loads(s, &vec![0.0; n + 1], &mut loads).is_none() {
        return false;
    }
    let mut bars = BlockBandMatrix::new(s.nominal.blocks(), s.bandwidth());
    s.assemble_material(&mut bars, |m| {
        if s.members[m].is_cable {
            ONE_SIDED_PROBE
        } else {
            1.0
        }
    });
    if bars.factor().is_err() {
        return false;
    }
    let compliance = |k: &BlockBandMatrix, g: &[f64]| {
        let mut x = g[..n].to_vec();
        k.solve_in_place(&mut x);
        g[..n].iter().zip(&x).map(|(a, b)| a * b).sum::<f64>()
    };
    loads.iter().all(|g| {
        let all = compliance(&s.nominal, g);
        let framed = compliance(&bars, g);
        all > 0.0 && framed.is_finite() && framed <= FRAMED_COMPLIANCE * all
    })
}

/// Whether the bars frame the tilt ([`tilt_framed_by_bars`]), and the working compression
/// ratio of the cables of ratio 0 that follows: [`FRAMED_RATIO`] if they do, else
/// [`LIMIT_RATIO`].
pub(super) fn working_ratio(s: &Structure) -> (bool, f64) {
    if tilt_framed_by_bars(s) {
        (true, FRAMED_RATIO)
    } else {
        (false, LIMIT_RATIO)
    }
}
