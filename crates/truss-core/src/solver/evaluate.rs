//! Evaluating the out-of-balance force and the member states at a point, and small vector
//! helpers shared by the solver's steps.

use crate::element::{AxialMember, AxialState};
use crate::structure::{Link, Structure};

/// Result of evaluating the out-of-balance force at a point.
#[derive(Debug, Clone, Copy)]
pub(super) struct Evaluation {
    /// Max |r| over free DOFs \[N\].
    pub residual: f64,
    /// Max |N| over members \[N\].
    pub force_scale: f64,
    /// Strain energy Σ ½·k_e·e² \[N·mm\].
    pub strain: f64,
}

/// `r = g(u) − f` and the member states at `u`; returns max |r| and max |N|.
#[cfg(test)]
pub(super) fn evaluate(
    s: &Structure,
    members: &[AxialMember],
    loads: &[f64],
    u: &[f64],
    r: &mut [f64],
    states: &mut [AxialState],
) -> Evaluation {
    let k = members.iter().map(AxialMember::tension_stiffness);
    evaluate_with(s, members, k, loads, u, r, states)
}

/// `r = g(u) − f` and the member states at `u`, with each member's `k = E·A/L₀` given (in
/// member order); returns max |r|, the largest member force and the strain energy.
///
/// Member by member: gather `d = u_j − u_i` by node blocks (a node without a block is
/// fixed: zero), the state, then scatter `∓N·n` into the rows of the two nodes. A member
/// with a partly fixed node scatters row by row, skipping the fixed ones.
#[allow(clippy::too_many_arguments)]
pub(super) fn evaluate_with(
    s: &Structure,
    members: &[AxialMember],
    k: impl Iterator<Item = f64>,
    loads: &[f64],
    u: &[f64],
    r: &mut [f64],
    states: &mut [AxialState],
) -> Evaluation {
    let n = s.free;
    for (ri, f) in r.iter_mut().zip(loads) {
        *ri = -f;
    }
    let (ub, _) = u[..n].as_chunks::<3>();
    let mut force_scale = 0.0f64;
    let mut strain = 0.0f64;
    for (((c, m), st), k) in s.members.iter().zip(members).zip(states.iter_mut()).zip(k) {
        let [a, b] = c.link.ends;
        let ua = ub.get(a).copied().unwrap_or([0.0; 3]);
        let uj = ub.get(b).copied().unwrap_or([0.0; 3]);
        *st = m.state_with([uj[0] - ua[0], uj[1] - ua[1], uj[2] - ua[2]], k);
        let f = st.force;
        strain += 0.5 * f * st.elongation;
        // `force_scale.max(|f|)` (a NaN force is skipped) without its NaN handling.
        let abs = f.abs();
        force_scale = if abs > force_scale { abs } else { force_scale };
        let fk = [
            f * st.direction[0],
            f * st.direction[1],
            f * st.direction[2],
        ];
        scatter(r, n, &c.link, fk);
    }
    r[n] = 0.0;
    Evaluation {
        residual: max_abs(&r[..n]),
        force_scale,
        strain,
    }
}

/// `r_i −= f`, `r_j += f` for an element from node `i` to node `j` (fixed rows skipped).
#[inline(always)]
fn scatter(r: &mut [f64], n: usize, c: &Link, fk: [f64; 3]) {
    if c.masked {
        let dof = c.dofs;
        for k in 0..3 {
            r[dof[k]] -= fk[k];
            r[dof[3 + k]] += fk[k];
        }
    } else {
        let [a, b] = c.ends;
        let (rb, _) = r[..n].as_chunks_mut::<3>();
        if let Some(ra) = rb.get_mut(a) {
            for (x, y) in ra.iter_mut().zip(&fk) {
                *x -= y;
            }
        }
        if let Some(rj) = rb.get_mut(b) {
            for (x, y) in rj.iter_mut().zip(&fk) {
                *x += y;
            }
        }
    }
}

/// Largest absolute value; NaN if any entry is NaN (`f64::max` alone would drop it).
/// Branch-free: a comparison that a NaN fails, and a flag for NaNs.
pub(super) fn max_abs(x: &[f64]) -> f64 {
    let mut m = 0.0f64;
    let mut nan = false;
    for v in x {
        let a = v.abs();
        nan |= a.is_nan();
        m = if a > m { a } else { m };
    }
    if nan { f64::NAN } else { m }
}

pub(super) fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
