//! The low-rank basis over the cables, the last stage of compiling a structure: with the
//! factorised all-taut `K₀`, `Z = K₀⁻¹B` and `G = BᵀK₀⁻¹B` over the one-sided members
//! `B = [b_c]`, which the linearised problem (the `linearised` module) updates `K₀` with by
//! the Woodbury identity for each slack set.

use super::parts::CompiledMember;
use crate::block::BlockBandMatrix;

/// Models with more cables than this solve each piece by factorising `K_S` instead: the
/// capacitance matrix would cost more than the banded factorisation.
pub(crate) const MAX_WOODBURY_CABLES: usize = 96;

/// Woodbury data for one model: `Z = K₀⁻¹B` and `G = BᵀK₀⁻¹B` over its cables.
#[derive(Debug, Clone)]
pub(crate) struct CableBasis {
    /// Member index of each cable.
    pub cables: Vec<usize>,
    /// `Z`, column per cable, each of length `free`.
    pub z: Vec<f64>,
    /// `G`, row-major `n_c × n_c`.
    pub g: Vec<f64>,
    /// `Gᵀ`, row-major (the columns of `G`, which rounding leaves not quite symmetric).
    pub g_t: Vec<f64>,
    /// `1/((1 − r_c)·k_c)` per cable, with nominal `k_c` \[mm/N\].
    pub w_inv: Vec<f64>,
    /// `σ_c` per cable: +1 tension-only (slack when `e < 0`), −1 compression-only (slack
    /// when `e > 0`).
    pub sense: Vec<f64>,
    /// The largest slack set solved by the capacitance matrix: `⌊∛(3·n·b²)⌋`, where its
    /// Cholesky (`|S|³/6` multiply–adds) costs as much as the banded one of `K_S` (`n·b²/2`,
    /// `n` unknowns, `b = 3·(q + 1)` rows of band for `q` block off-diagonals).
    pub max_slack: usize,
}

impl CableBasis {
    /// The basis of `members` (with `free` rows) over the factorised `nominal` `K₀`, for a
    /// model with at least one and at most [`MAX_WOODBURY_CABLES`] cables.
    pub fn for_members(
        members: &[CompiledMember],
        free: usize,
        nominal: &BlockBandMatrix,
    ) -> Option<Self> {
        let cables = members.iter().filter(|m| m.is_cable).count();
        (cables > 0 && cables <= MAX_WOODBURY_CABLES).then(|| Self::new(members, free, nominal))
    }

    /// Precomputes `Z` and `G` with the factorised `K₀`.
    fn new(members: &[CompiledMember], free: usize, nominal: &BlockBandMatrix) -> Self {
        let n = free;
        let cables: Vec<usize> = (0..members.len())
            .filter(|&m| members[m].is_cable)
            .collect();
        let nc = cables.len();
        let mut z = vec![0.0; n * nc];
        let mut w_inv = vec![0.0; nc];
        let mut col = vec![0.0; n + 1];
        for (k, &m) in cables.iter().enumerate() {
            col.fill(0.0);
            members[m].scatter_b(free, 1.0, &mut col);
            nominal.solve_in_place(&mut col[..n]);
            z[k * n..(k + 1) * n].copy_from_slice(&col[..n]);
            let c = &members[m];
            w_inv[k] = c.natural_length / ((1.0 - c.compression_ratio) * c.rigidity);
        }
        let mut g = vec![0.0; nc * nc];
        for (a, &ma) in cables.iter().enumerate() {
            for b in 0..nc {
                g[a * nc + b] = members[ma].gather_b(free, &z[b * n..(b + 1) * n]);
            }
        }
        let mut g_t = vec![0.0; nc * nc];
        for a in 0..nc {
            for b in 0..nc {
                g_t[b * nc + a] = g[a * nc + b];
            }
        }
        let sense = cables.iter().map(|&m| members[m].sense).collect();
        let band = 3.0 * (nominal.bandwidth() as f64 + 1.0);
        let max_slack = (3.0 * n as f64 * band * band).cbrt().floor() as usize;
        Self {
            cables,
            z,
            g,
            g_t,
            w_inv,
            sense,
            max_slack,
        }
    }
}
