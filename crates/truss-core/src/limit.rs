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

use crate::block::BlockBandMatrix;
use crate::measure::distortion;
use crate::structure::{FIXED, Structure};

/// The working compression ratio of a cable of ratio 0 in a model whose top surface's tilt
/// is framed by bars (see the module doc).
pub const FRAMED_RATIO: f64 = 1e-4;

/// The compression ratio at which a cable of ratio 0 stands for the limit `r → 0` where
/// the tilt is not framed by bars (see the module doc).
pub const LIMIT_RATIO: f64 = 1e-7;

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
pub(crate) fn tilt_framed_by_bars(s: &Structure) -> bool {
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
