//! The pin joint with backlash (the paper's section 4.1): a batten's shaft in a longeron's
//! hole, modelled as a virtual cable between the shaft centre and the hole centre.
//!
//! ## Geometry and physics
//!
//! A joint joins two nodes that nominally coincide: the *shaft* node, at the centre of the
//! batten's shaft, and the *hole* node, at the centre of the longeron's hole. The hole is
//! wider than the shaft by the clearance `g`, so the shaft can sit anywhere within `g` of the
//! hole's centre across the shaft's axis `a`. Along the axis the shaft is held by the
//! fitting's shoulders on both faces of the longeron's lug, with no play: the paper
//! considers backlash across the shaft only.
//!
//! With `Δ = u_hole − u_shaft` \[mm\] (the nodes coincide nominally), `P = I − a aᵀ` (the
//! projection across the axis; `P = I` for a joint without an axis, a ball in a socket),
//! `Δ⊥ = PΔ`, `d = |Δ⊥|` and `⟨x⟩₊ = max(x, 0)`, the joint's energy \[N·mm\] is
//!
//! ```text
//! W = ½·k_a·(a·Δ)² + ½·k_c·d² + ½·k_t·⟨d − g⟩₊²
//! ∂W/∂Δ   = k_a·(a·Δ)·a + k_c·Δ⊥ + k_t·⟨d − g⟩₊·q,                    q = Δ⊥/d   [N]
//! ∂²W/∂Δ² = k_a·a aᵀ + k_c·P + [d > g]·k_t·((g/d)·q qᵀ + (1 − g/d)·P)            [N/mm]
//! ```
//!
//! * `k_t` (the *tension* stiffness of the paper's virtual cable, default 10⁵ times the
//!   axial stiffness `E·A/L` of the truss member at the joint) is the contact: once the
//!   shaft touches the hole's edge (`d > g`) it penetrates by only `F/k_t`, with `F` the
//!   force through the joint.
//! * `k_a` (default `k_t`) keeps the nodes together along the axis.
//! * `k_c` (the paper's *compression* stiffness, default 10⁻⁵·k_t) is the regularisation of
//!   a loose joint. The paper's cable has natural length `g` and stiffness `k_c` when
//!   shorter, which pushes a loose shaft towards the hole's edge with force `k_c·(g − d)` in a
//!   direction that is undefined at `d = 0`, where the nodes start, and leaves a ring of
//!   equilibria at `d = g`: no unique position for a loose shaft. Here the same stiffness
//!   acts about the hole's centre instead, so the energy is smooth at `d = 0` (no direction
//!   is ever needed there), continuously differentiable everywhere, and a loose shaft has one
//!   position: centred, displaced by `F/k_c` under a force `F < k_c·g`. A joint is in contact
//!   when the force through it exceeds `k_c·g`; below that its position depends on `k_c`,
//!   which is why solves report their loose joints.
//!
//! The energy is convex in `Δ`. With `g = 0` the joint is a linear spring of stiffness
//! `k_c + k_t` across the axis, and the model tends to one without backlash as `k_t → ∞`.

use crate::element::dot;

/// Default contact stiffness of a joint: this many times the axial stiffness `E·A/L₀` of
/// the stiffest member at its nodes (the paper's 10⁵).
pub const DEFAULT_JOINT_TENSION_FACTOR: f64 = 1e5;

/// Default centring stiffness of a loose joint over its contact stiffness (the paper's
/// 10⁻⁵; with the default contact stiffness, the member's own `E·A/L₀`).
pub const DEFAULT_JOINT_COMPRESSION_RATIO: f64 = 1e-5;

/// One joint's constants for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointElement {
    /// Unit shaft axis `a`, or `None` for backlash in every direction.
    pub axis: Option<[f64; 3]>,
    /// Clearance `g` \[mm\], ≥ 0.
    pub clearance: f64,
    /// Contact stiffness `k_t` \[N/mm\].
    pub tension_stiffness: f64,
    /// Centring stiffness of a loose joint `k_c` \[N/mm\].
    pub compression_stiffness: f64,
    /// Stiffness along the shaft's axis `k_a` \[N/mm\].
    pub axial_stiffness: f64,
}

/// A joint's state at a given `Δ = u_hole − u_shaft`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointState {
    /// `Δ⊥`, the hole centre's offset from the shaft centre across the axis \[mm\].
    pub offset: [f64; 3],
    /// `d = |Δ⊥|` \[mm\].
    pub distance: f64,
    /// `∂W/∂Δ`, the force the joint exerts on the shaft node (its negative acts on the hole
    /// node) \[N\].
    pub force: [f64; 3],
    /// Contact force `k_t·⟨d − g⟩₊` \[N\]: zero for a loose joint.
    pub contact: f64,
    /// Energy `W` \[N·mm\].
    pub energy: f64,
    /// Whether the shaft touches the hole's edge (`d > g`, or any `d` when `g = 0`).
    pub engaged: bool,
    /// `∂²W/∂Δ²` as its six distinct entries `[xx, yx, yy, zx, zy, zz]` \[N/mm\].
    pub tangent: [f64; 6],
}

impl JointElement {
    /// The state at `Δ` \[mm\] (see the module doc). Never divides by zero: the contact
    /// terms are used only where `d > g > 0`, or, for `g = 0`, in a form without `d`.
    #[inline]
    pub fn state(&self, delta: [f64; 3]) -> JointState {
        let (along, perp) = match self.axis {
            Some(a) => {
                let t = dot(a, delta);
                (
                    t,
                    [
                        delta[0] - t * a[0],
                        delta[1] - t * a[1],
                        delta[2] - t * a[2],
                    ],
                )
            }
            None => (0.0, delta),
        };
        let d = dot(perp, perp).sqrt();
        let g = self.clearance;
        let (kt, kc, ka) = (
            self.tension_stiffness,
            self.compression_stiffness,
            self.axial_stiffness,
        );
        // The across-axis stiffness on P, and the extra along q: ∂W/∂Δ⊥ = s·Δ⊥.
        let (engaged, s, extra, contact, gap) = if g == 0.0 {
            (true, kc + kt, 0.0, kt * d, d)
        } else if d > g {
            let ratio = g / d;
            (
                true,
                kc + kt * (1.0 - ratio),
                kt * ratio,
                kt * (d - g),
                d - g,
            )
        } else {
            (false, kc, 0.0, 0.0, 0.0)
        };
        let mut force = perp.map(|x| s * x);
        let mut tangent = [s, 0.0, s, 0.0, 0.0, s];
        if let Some(a) = self.axis {
            for (f, ai) in force.iter_mut().zip(a) {
                *f += ka * along * ai;
            }
            // k_a·a aᵀ − s·a aᵀ (P = I − a aᵀ).
            add_outer(&mut tangent, a, ka - s);
        }
        if extra != 0.0 {
            let q = perp.map(|x| x / d);
            add_outer(&mut tangent, q, extra);
        }
        JointState {
            offset: perp,
            distance: d,
            force,
            contact,
            energy: 0.5 * ka * along * along + 0.5 * kc * d * d + 0.5 * kt * gap * gap,
            engaged,
            tangent,
        }
    }

    /// The stiffness of a loose joint, `k_a·a aᵀ + k_c·P`, as six entries \[N/mm\]: the
    /// joint's part of the linearised stiffness `K₀`.
    pub fn loose_tangent(&self) -> [f64; 6] {
        let s = self.compression_stiffness;
        let mut t = [s, 0.0, s, 0.0, 0.0, s];
        if let Some(a) = self.axis {
            add_outer(&mut t, a, self.axial_stiffness - s);
        }
        t
    }
}

/// `t += c·v vᵀ` on the six distinct entries `[xx, yx, yy, zx, zy, zz]`.
#[inline]
fn add_outer(t: &mut [f64; 6], v: [f64; 3], c: f64) {
    t[0] += c * v[0] * v[0];
    t[1] += c * v[1] * v[0];
    t[2] += c * v[1] * v[1];
    t[3] += c * v[2] * v[0];
    t[4] += c * v[2] * v[1];
    t[5] += c * v[2] * v[2];
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(axis: Option<[f64; 3]>, clearance: f64) -> JointElement {
        JointElement {
            axis,
            clearance,
            tension_stiffness: 2.7e8,
            compression_stiffness: 2.7e3,
            axial_stiffness: 1.3e8,
        }
    }

    fn entry(t: &[f64; 6], a: usize, b: usize) -> f64 {
        let (r, c) = if a >= b { (a, b) } else { (b, a) };
        t[r * (r + 1) / 2 + c]
    }

    /// Central differences of `W` give the force, and of the force the tangent, on both
    /// sides of contact, with and without an axis, and for `g = 0`.
    #[test]
    fn force_and_tangent_match_central_differences() {
        let s = 1.0 / 3f64.sqrt();
        let axes = [None, Some([0.6, 0.0, 0.8]), Some([s, -s, s])];
        for axis in axes {
            for (g, delta) in [
                (0.01, [0.004, -0.003, 0.002]), // loose
                (0.01, [0.011, -0.006, 0.004]), // in contact
                (0.0, [0.002, 0.001, -0.003]),  // no clearance
                (0.01, [0.0, 0.0, 0.0]),        // centred
            ] {
                let j = joint(axis, g);
                let st = j.state(delta);
                let h = 1e-7;
                for a in 0..3 {
                    let (mut p, mut m) = (delta, delta);
                    p[a] += h;
                    m[a] -= h;
                    let (sp, sm) = (j.state(p), j.state(m));
                    let fd = (sp.energy - sm.energy) / (2.0 * h);
                    let f = st.force[a];
                    let scale = st.force.iter().fold(1.0, |x: f64, y| x.max(y.abs()));
                    assert!(
                        (fd - f).abs() <= 1e-5 * scale,
                        "{axis:?} {g} W'[{a}] {fd} vs {f}"
                    );
                    for b in 0..3 {
                        let fdk = (sp.force[b] - sm.force[b]) / (2.0 * h);
                        let k = entry(&st.tangent, a, b);
                        let kscale = st.tangent.iter().fold(1.0, |x: f64, y| x.max(y.abs()));
                        assert!(
                            (fdk - k).abs() <= 1e-6 * kscale,
                            "{axis:?} {g} K[{a}{b}] {fdk} vs {k}"
                        );
                    }
                }
            }
        }
    }

    /// At the nominal point, where the nodes coincide and no direction exists, everything
    /// is finite: zero force, the loose stiffness; and exactly at contact (d = g) too.
    #[test]
    fn coincident_nodes_are_sound() {
        for axis in [None, Some([0.0, 1.0, 0.0])] {
            let j = joint(axis, 0.01);
            let st = j.state([0.0; 3]);
            assert_eq!(st.force, [0.0; 3]);
            assert_eq!(st.energy, 0.0);
            assert!(!st.engaged);
            assert_eq!(st.tangent, j.loose_tangent());
            let edge = j.state([0.01, 0.0, 0.0]);
            assert!(
                edge.tangent
                    .iter()
                    .chain(&edge.force)
                    .all(|x| x.is_finite())
            );
            assert_eq!(edge.contact, 0.0);
            let zero = joint(axis, 0.0).state([0.0; 3]);
            assert!(zero.engaged);
            assert!(zero.tangent.iter().all(|x| x.is_finite()));
            assert_eq!(zero.force, [0.0; 3]);
        }
    }

    /// Hand solution: a force F across the axis moves the hole by F/k_c while F < k_c·g,
    /// and by g + (F − k_c·g)/(k_c + k_t) beyond (1-D balance of the module doc's force).
    #[test]
    fn contact_threshold_is_kc_times_g() {
        let j = joint(Some([0.0, 0.0, 1.0]), 0.01);
        let (kc, kt, g) = (j.compression_stiffness, j.tension_stiffness, j.clearance);
        for f in [10.0, 26.0, 28.0, 1000.0] {
            let d = if f < kc * g {
                f / kc
            } else {
                (f + kt * g) / (kc + kt)
            };
            let st = j.state([d, 0.0, 0.0]);
            assert!((st.force[0] - f).abs() <= 1e-9 * f, "{f}: {}", st.force[0]);
            assert_eq!(st.engaged, f > kc * g);
        }
    }
}
