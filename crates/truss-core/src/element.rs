//! The two-node axial element: elongation, force, energy, and tangent stiffness, written for
//! micrometre imperfections on members hundreds of millimetres long.
//!
//! For a member from node `i` to node `j` with nominal vector `D = X_j − X_i` (length
//! `L_r = |D|`), natural length `L₀`, relative displacement `d = u_j − u_i`:
//!
//! ```text
//! c = D + d                                    current vector \[mm\]
//! L = |c|,  n = c / L                          current length \[mm\], unit direction
//! e = L − L₀ = (2 D·d + d·d)/(L + L_r) + s₀,   s₀ = L_r − L₀          elongation \[mm\]
//! k = E·A / L₀                                 axial stiffness \[N/mm\]
//! k_e = k, or r·k for a one-sided member        effective stiffness (r: compression ratio)
//!       slack (σ·e < 0, σ = +1 tension-only, −1 compression-only)
//! N = k_e · e                                  axial force, tension positive \[N\]
//! W = ½ · k_e · e²                             strain energy \[N·mm\]
//! ∂W/∂u_j = −∂W/∂u_i = N · n                   internal force on the nodes \[N\]
//! K_jj = K_ii = −K_ij = k_e · n nᵀ + (N/L)(I − n nᵀ)    tangent stiffness \[N/mm\]
//! ```
//!
//! `(L − L_r)` is computed as `(L² − L_r²)/(L + L_r)` with `L² − L_r² = 2 D·d + d·d` exactly
//! expanded, so no two nearly equal lengths are subtracted; `s₀` is computed once per sample
//! from the nominal value and the length error. `W` is continuous with a continuous first
//! derivative at `e = 0`, where a one-sided member switches between taut and slack (`e = 0`
//! counts as taut). A cable is tension-only (`σ = +1`); the compression-only members
//! (`σ = −1`) are half of a longeron whose ends sit in clearance holes (see [`crate::joint`]).

/// The constants of one member for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialMember {
    /// Nominal vector `D = X_j − X_i` \[mm\].
    pub reference: [f64; 3],
    /// Nominal length `L_r = |D|` \[mm\].
    pub reference_length: f64,
    /// Natural length `L₀` \[mm\].
    pub natural_length: f64,
    /// `s₀ = L_r − L₀` \[mm\]; positive when the member is too short and starts in tension.
    pub initial_stretch: f64,
    /// `E·A` \[N\].
    pub rigidity: f64,
    /// Compression stiffness ratio `r`: 1 for a bar, small for a cable (the stiffness ratio
    /// of its slack side for any one-sided member).
    pub compression_ratio: f64,
    /// The side that carries load, `σ`: +1 for bars and tension-only members, −1 for a
    /// compression-only member (slack when `σ·e < 0`).
    pub sense: f64,
}

/// The state of a member at a given relative displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialState {
    /// Unit vector from node `i` to node `j` in the current configuration.
    pub direction: [f64; 3],
    /// Current length `L` \[mm\].
    pub length: f64,
    /// Elongation `e = L − L₀` \[mm\].
    pub elongation: f64,
    /// Axial force `N`, tension positive \[N\].
    pub force: f64,
    /// Effective axial stiffness `k_e` \[N/mm\].
    pub stiffness: f64,
    /// Whether a one-sided member is slack (`σ·e < 0` and `r < 1`).
    pub slack: bool,
}

impl AxialMember {
    /// A member with nominal vector `reference`, natural length `natural_length`, rigidity
    /// `E·A` and compression ratio `r`. `initial_stretch` is `s₀ = L_r − L₀`, which the
    /// caller computes without cancellation (the nominal offset minus the sample's length
    /// error).
    pub fn new(
        reference: [f64; 3],
        natural_length: f64,
        initial_stretch: f64,
        rigidity: f64,
        compression_ratio: f64,
    ) -> Self {
        Self {
            reference,
            reference_length: norm(reference),
            natural_length,
            initial_stretch,
            rigidity,
            compression_ratio,
            sense: 1.0,
        }
    }

    /// The member's state at relative displacement `d = u_j − u_i` \[mm\].
    #[inline]
    pub fn state(&self, d: [f64; 3]) -> AxialState {
        self.state_with(d, self.tension_stiffness())
    }

    /// Axial stiffness in tension `k = E·A/L₀` \[N/mm\].
    #[inline]
    pub fn tension_stiffness(&self) -> f64 {
        self.rigidity / self.natural_length
    }

    /// [`AxialMember::state`] with `k = E·A/L₀` given (computed once per sample).
    #[inline(always)]
    pub(crate) fn state_with(&self, d: [f64; 3], k: f64) -> AxialState {
        let c = add(self.reference, d);
        let length = norm(c);
        let stretch_sq = 2.0 * dot(self.reference, d) + dot(d, d);
        let elongation = stretch_sq / (length + self.reference_length) + self.initial_stretch;
        let slack = self.sense * elongation < 0.0 && self.compression_ratio < 1.0;
        let stiffness = if slack { self.compression_ratio * k } else { k };
        let inv = 1.0 / length;
        AxialState {
            direction: [c[0] * inv, c[1] * inv, c[2] * inv],
            length,
            elongation,
            force: stiffness * elongation,
            stiffness,
            slack,
        }
    }

    /// Strain energy `W = ½·k_e·e²` \[N·mm\] at relative displacement `d`.
    pub fn energy(&self, d: [f64; 3]) -> f64 {
        let s = self.state(d);
        0.5 * s.stiffness * s.elongation * s.elongation
    }
}

impl AxialState {
    /// The 3×3 tangent block `k_e n nᵀ + (N/L)(I − n nᵀ)`, as its six distinct entries
    /// `[xx, yx, yy, zx, zy, zz]` \[N/mm\].
    #[inline]
    pub fn tangent_block(&self) -> [f64; 6] {
        self.tangent_block_with(self.stiffness)
    }

    /// The tangent block with the axial stiffness `k` in place of `k_e` (the geometric part
    /// `(N/L)(I − n nᵀ)` unchanged): the block of a cable as if it switched state.
    #[inline]
    pub fn tangent_block_with(&self, k: f64) -> [f64; 6] {
        let n = self.direction;
        let g = self.force / self.length;
        let a = k - g;
        [
            a * n[0] * n[0] + g,
            a * n[1] * n[0],
            a * n[1] * n[1] + g,
            a * n[2] * n[0],
            a * n[2] * n[1],
            a * n[2] * n[2] + g,
        ]
    }
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central-difference check of the force (gradient of W) and of the tangent block
    /// (Jacobian of the force), for a bar, for a cable and for a compression-only member
    /// (the half of a member in clearance holes), each on both sides of slack.
    #[test]
    fn force_and_tangent_match_central_differences() {
        let reference = [300.0, -120.0, 180.0];
        let cases = [
            (0.01, 1.0, 1.0),
            (-0.02, 1.0, 1.0),
            (0.003, 1e-3, 1.0),
            (-0.004, 1e-3, 1.0),
            (0.003, 1e-3, -1.0),
            (-0.004, 1e-3, -1.0),
        ];
        for (stretch, ratio, sense) in cases {
            let lr = norm(reference);
            let m = AxialMember {
                sense,
                ..AxialMember::new(reference, lr - stretch, stretch, 2.17e5, ratio)
            };
            let st = m.state([0.0; 3]);
            assert_eq!(st.slack, ratio < 1.0 && sense * stretch < 0.0);
            let d0 = [0.011, -0.007, 0.013];
            let s = m.state(d0);
            let h = 1e-4;
            for a in 0..3 {
                let mut dp = d0;
                let mut dm = d0;
                dp[a] += h;
                dm[a] -= h;
                let fd = (m.energy(dp) - m.energy(dm)) / (2.0 * h);
                let f = s.force * s.direction[a];
                assert!((fd - f).abs() <= 1e-6 * f.abs().max(1.0), "{fd} vs {f}");
                let (sp, sm) = (m.state(dp), m.state(dm));
                let kb = s.tangent_block();
                for b in 0..3 {
                    let fdk = (sp.force * sp.direction[b] - sm.force * sm.direction[b]) / (2.0 * h);
                    let (r, c) = if a >= b { (a, b) } else { (b, a) };
                    let k = kb[r * (r + 1) / 2 + c];
                    assert!(
                        (fdk - k).abs() <= 1e-6 * k.abs().max(1.0),
                        "K[{a}{b}] {fdk} vs {k}"
                    );
                }
            }
        }
    }

    /// The cancellation-free elongation agrees with a direct evaluation in a case where the
    /// direct one is exact enough, and stays accurate where the direct one is not.
    #[test]
    fn elongation_is_cancellation_free() {
        let reference = [380.0, 0.0, 0.0];
        let m = AxialMember::new(reference, 380.0, 0.0, 1.0, 1.0);
        // Stretch by 1e-9 mm along the axis: the direct |c| − L₀ would be 380.000000001 − 380,
        // whose rounding error (≈ 6e-14) is 6e-5 of the answer.
        let e = m.state([1e-9, 0.0, 0.0]).elongation;
        assert!((e - 1e-9).abs() < 1e-24, "{e}");
        // A pure transverse displacement t: e = √(L² + t²) − L = t²/(√(L² + t²) + L).
        let t = 1e-3;
        let exact = t * t / ((380.0f64 * 380.0 + t * t).sqrt() + 380.0);
        let e = m.state([0.0, t, 0.0]).elongation;
        assert!((e - exact).abs() <= 1e-15 * exact, "{e} vs {exact}");
    }
}
