//! Evaluating the out-of-balance force and the member states at a point, and small vector
//! helpers shared by the solver's steps.

use super::Evaluation;
use crate::element::{AxialMember, AxialState};
use crate::structure::Structure;

/// `r = g(u) − f` and the member states at `u`; returns max |r| and max |N|.
pub(super) fn evaluate(
    s: &Structure,
    members: &[AxialMember],
    loads: &[f64],
    u: &[f64],
    r: &mut [f64],
    states: &mut [AxialState],
) -> Evaluation {
    let n = s.free;
    for (ri, f) in r.iter_mut().zip(loads) {
        *ri = -f;
    }
    let mut force_scale = 0.0f64;
    for ((c, m), st) in s.members.iter().zip(members).zip(states.iter_mut()) {
        let dof = c.dofs;
        let d = [
            u[dof[3]] - u[dof[0]],
            u[dof[4]] - u[dof[1]],
            u[dof[5]] - u[dof[2]],
        ];
        *st = m.state(d);
        let f = st.force;
        force_scale = force_scale.max(f.abs());
        for k in 0..3 {
            let fk = f * st.direction[k];
            r[dof[k]] -= fk;
            r[dof[3 + k]] += fk;
        }
    }
    r[n] = 0.0;
    Evaluation {
        residual: max_abs(&r[..n]),
        force_scale,
    }
}

/// Largest absolute value; NaN if any entry is NaN (`f64::max` alone would drop it).
pub(super) fn max_abs(x: &[f64]) -> f64 {
    let mut m = 0.0f64;
    for v in x {
        if v.is_nan() {
            return f64::NAN;
        }
        m = m.max(v.abs());
    }
    m
}

pub(super) fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
