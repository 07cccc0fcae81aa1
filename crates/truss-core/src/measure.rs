//! The distortion angle θ_P of a surface through three nodes (paper section 2.2 and 3.2).
//!
//! With the three nodes' deformed positions `p₁, p₂, p₃` (paper Fig. 5 order):
//!
//! ```text
//! n_t = (p₂ − p₁) × (p₃ − p₁)                          surface normal (eq. 5)
//! θ_P = atan2(|n_t × n_b|, n_t · n_b)                   angle to the reference n_b (eq. 2) \[rad\]
//! tan θ_x = −n_tx / n_tz,   tan θ_y = −n_ty / n_tz       (eqs. 6, 8, 9) \[-\]
//! ```
//!
//! The paper writes θ_P = cos⁻¹(n_t·n_b / |n_t||n_b|). For θ_P ≈ 1e-5 rad the cosine is
//! 1 − 5e-11, and `acos` of a number that close to 1 keeps only about half of the digits:
//! `atan2` of the sine and cosine parts is accurate to the last bit. Differences of positions
//! are formed as (nominal difference) + (displacement difference), so the micrometre
//! displacements are not rounded against the 380 mm coordinates.
//!
//! `atan2` is the pure-Rust `libm` implementation, so θ_P has the same bits on every machine.

use crate::element::{add, dot, norm, sub};

/// The tilt of a surface against a reference normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// Distortion angle θ_P \[rad\], in [0, π].
    pub theta_p: f64,
    /// tan θ_x = −n_tx/n_tz \[-\] (paper eq. 8).
    pub tan_theta_x: f64,
    /// tan θ_y = −n_ty/n_tz \[-\] (paper eq. 9).
    pub tan_theta_y: f64,
    /// The unit normal of the deformed surface.
    pub normal: [f64; 3],
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The distortion of the surface through nodes with nominal positions `x` and displacements
/// `u` (both \[mm\], in the paper's Fig. 5 order), against the unit reference normal `n_b`.
pub fn distortion(x: [[f64; 3]; 3], u: [[f64; 3]; 3], n_b: [f64; 3]) -> Distortion {
    let e1 = add(sub(x[1], x[0]), sub(u[1], u[0]));
    let e2 = add(sub(x[2], x[0]), sub(u[2], u[0]));
    let n = cross(e1, e2);
    let len = norm(n);
    let normal = [n[0] / len, n[1] / len, n[2] / len];
    let sin = norm(cross(n, n_b));
    let cos = dot(n, n_b);
    Distortion {
        theta_p: libm::atan2(sin, cos),
        tan_theta_x: -n[0] / n[2],
        tan_theta_y: -n[1] / n[2],
        normal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Paper eqs. 8, 9 and 17: for vertical displacements of an equilateral triangle of side
    /// `l` in the plane z = 0, tan θ_x = (z₂ − z₁)/l and tan θ_y = (2z₃ − z₁ − z₂)/(√3·l),
    /// the slopes of the tilted plane in x and y; θ_P = atan √(tan²θ_x + tan²θ_y) (eq. 7).
    /// (Eq. 18 prints tan θ_y with the opposite sign, a slip: eqs. 6 and 9, which the code
    /// follows, give the slope. The sign does not change any statistic of θ_P.)
    #[test]
    fn vertical_displacements_give_the_papers_slopes() {
        let l = 380.0;
        let x = [
            [0.0, 0.0, 0.0],
            [l, 0.0, 0.0],
            [l / 2.0, 3f64.sqrt() / 2.0 * l, 0.0],
        ];
        let z = [1e-3, 4e-3, -2e-3];
        let u = [[0.0, 0.0, z[0]], [0.0, 0.0, z[1]], [0.0, 0.0, z[2]]];
        let d = distortion(x, u, [0.0, 0.0, 1.0]);
        let tx = (z[1] - z[0]) / l;
        let ty = (2.0 * z[2] - z[0] - z[1]) / (3f64.sqrt() * l);
        assert!(
            (d.tan_theta_x - tx).abs() < 1e-15 * tx.abs(),
            "{} vs {tx}",
            d.tan_theta_x
        );
        assert!(
            (d.tan_theta_y - ty).abs() < 1e-15 * ty.abs(),
            "{} vs {ty}",
            d.tan_theta_y
        );
        let theta = (tx * tx + ty * ty).sqrt().atan();
        assert!(
            (d.theta_p - theta).abs() < 1e-15 * theta,
            "{} vs {theta}",
            d.theta_p
        );
    }

    /// `acos` of the normalised dot product loses digits at 1e-5 rad; `atan2` does not.
    #[test]
    fn atan2_keeps_the_digits_acos_loses() {
        let theta: f64 = 1.234_567_890_123e-5;
        let n_b = [0.0, 0.0, 1.0];
        let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        // Tilt the unit square's corner so the normal is at exactly `theta` from z in x–z.
        let t = theta.tan();
        let u = [[0.0; 3], [0.0, 0.0, -t], [0.0; 3]];
        let d = distortion(x, u, n_b);
        assert!((d.theta_p - theta).abs() <= 2e-16 * theta, "{}", d.theta_p);
        let n = d.normal;
        let acos = (dot(n, n_b) / norm(n)).acos();
        assert!(
            (acos - theta).abs() > 1e-9 * theta,
            "acos was unexpectedly exact"
        );
    }
}
