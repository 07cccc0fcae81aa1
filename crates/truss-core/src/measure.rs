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
//!
//! ## Decenter and despace
//!
//! The image of a telescope whose optical bench this is also moves when the top surface
//! shifts sideways against the bottom's axis (decenter) and when the distance between them
//! changes (despace). With the top surface's three nodes' displacements `u₁, u₂, u₃` and the
//! supported nodes' (every node with a fixed direction: the bottom) `s₁ … s_m`, the top
//! centroid's displacement relative to the bottom's is
//!
//! ```text
//! δ = (u₁ + u₂ + u₃)/3 − (s₁ + … + s_m)/m                  (0 for the second term when m = 0) [mm]
//! decenter_x = δ·e_x,   decenter_y = δ·e_y                  the shift in the bottom plane [mm]
//! decenter   = √(decenter_x² + decenter_y²)                                              [mm]
//! despace    = δ·n_b                                        along the bottom's normal, signed:
//!                                                           positive when the top moves away [mm]
//! ```
//!
//! The frame is the bottom's: its normal `n_b` is the reference normal θ_P is measured
//! against, `e_x` is the model's x axis made perpendicular to it,
//! `e_x = (x̂ − (x̂·n_b) n_b)/|…|` (the y axis instead where `|x̂·n_b| > 0.9`), and
//! `e_y = n_b × e_x`; for `n_b = ẑ` (the paper's prism) `e_x = x̂` and `e_y = ŷ`. Its origin
//! follows the supported nodes' centroid, so that a support that lets a node slide moves
//! the frame with it; it does not turn with them, as θ_P's `n_b` does not. For the prism,
//! whose bottom nodes are fixed, the second term is 0 and δ is the top centroid's own
//! displacement. Only displacements enter (never the 380 mm coordinates), so the
//! micrometres keep their digits. Under small errors δ is linear in them: decenter_x and
//! decenter_y are nearly normal with a common spread where the truss is symmetric under a
//! rotation about its axis (the prism's 120°), so decenter is nearly Rayleigh, the paper's
//! eq. 28 argument for θ_P applied to the centroid's two components; despace is nearly
//! normal.
//!
//! Both are measured from the model's coordinates, as θ_P is, so they include what the
//! error-free structure already does under its pretension and effects: the prism's
//! pretensioned diagonals compress its longerons, so that with no length error at all the
//! top sits lower by 0.94 µm (5 stages, Table 1) or 5.58 µm (30 stages), by symmetry with
//! no decenter and no tilt. That offset is in every sample's despace and in its mean.

use crate::element::{add, dot, norm, sub};
use serde::Serialize;

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

/// Where the top surface's centroid sits against the bottom's frame (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Placement {
    /// The centroid's shift along the bottom frame's `e_x` \[mm\].
    pub decenter_x: f64,
    /// The centroid's shift along the bottom frame's `e_y` \[mm\].
    pub decenter_y: f64,
    /// `√(decenter_x² + decenter_y²)` \[mm\].
    pub decenter: f64,
    /// The centroid's displacement along the bottom's normal `n_b`, signed \[mm\].
    pub despace: f64,
}

/// The bottom frame's in-plane axes `(e_x, e_y)` for its unit normal `n_b` (see the module
/// doc): `e_x` the x axis made perpendicular to `n_b` (the y axis where `|x̂·n_b| > 0.9`),
/// `e_y = n_b × e_x`.
pub fn in_plane_axes(n_b: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let axis = if n_b[0].abs() > 0.9 {
        [0.0, 1.0, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let along = dot(axis, n_b);
    let v = [
        axis[0] - along * n_b[0],
        axis[1] - along * n_b[1],
        axis[2] - along * n_b[2],
    ];
    let l = norm(v);
    let e_x = [v[0] / l, v[1] / l, v[2] / l];
    (e_x, cross(n_b, e_x))
}

/// The placement of the surface whose three nodes are displaced by `top` against the frame
/// of the bottom, whose supported nodes are displaced by `bottom` (both \[mm\]; `bottom` may
/// be empty), with unit normal `n_b` (see the module doc).
pub fn placement(top: [[f64; 3]; 3], bottom: &[[f64; 3]], n_b: [f64; 3]) -> Placement {
    let centroid = |points: &[[f64; 3]]| {
        let mut c = [0.0; 3];
        for p in points {
            c = add(c, *p);
        }
        let n = points.len().max(1) as f64;
        [c[0] / n, c[1] / n, c[2] / n]
    };
    let delta = sub(centroid(&top), centroid(bottom));
    let (e_x, e_y) = in_plane_axes(n_b);
    let (decenter_x, decenter_y) = (dot(delta, e_x), dot(delta, e_y));
    Placement {
        decenter_x,
        decenter_y,
        decenter: decenter_x.hypot(decenter_y),
        despace: dot(delta, n_b),
    }
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

/// The gradient of θ_P with respect to the three nodes' displacements, `∂θ_P/∂u_k` \[rad/mm\]
/// (rows in the nodes' order), at the point [`distortion`] measures; `None` where θ_P = 0
/// (its gradient is not defined there) or the surface is degenerate.
///
/// With `n = e₁ × e₂` (`e₁ = p₂ − p₁`, `e₂ = p₃ − p₁`), `w = n × n_b`, `s = |w|`, `c = n·n_b`:
///
/// ```text
/// ∂s/∂n = (n_b × w)/s,   ∂c/∂n = n_b,   a = ∂θ_P/∂n = (c·∂s/∂n − s·∂c/∂n)/(s² + c²)
/// δθ_P = a·(δe₁ × e₂ + e₁ × δe₂)  ⇒  ∂θ_P/∂u₂ = e₂ × a,  ∂θ_P/∂u₃ = a × e₁,
///                                     ∂θ_P/∂u₁ = −(∂θ_P/∂u₂ + ∂θ_P/∂u₃)
/// ```
pub fn theta_gradient(x: [[f64; 3]; 3], u: [[f64; 3]; 3], n_b: [f64; 3]) -> Option<[[f64; 3]; 3]> {
    let e1 = add(sub(x[1], x[0]), sub(u[1], u[0]));
    let e2 = add(sub(x[2], x[0]), sub(u[2], u[0]));
    let n = cross(e1, e2);
    let w = cross(n, n_b);
    let s = norm(w);
    let c = dot(n, n_b);
    let r2 = s * s + c * c;
    if !(s > 0.0 && r2 > 0.0 && r2.is_finite()) {
        return None;
    }
    let ds = cross(n_b, w);
    let a = [
        (c * ds[0] / s - s * n_b[0]) / r2,
        (c * ds[1] / s - s * n_b[1]) / r2,
        (c * ds[2] / s - s * n_b[2]) / r2,
    ];
    let g2 = cross(e2, a);
    let g3 = cross(a, e1);
    let g1 = [-(g2[0] + g3[0]), -(g2[1] + g3[1]), -(g2[2] + g3[2])];
    Some([g1, g2, g3])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: a top centroid displaced by (3, −4, 2) µm over a fixed bottom has decenter
    /// (3, −4), 5 µm, and despace 2 µm; a bottom that slides by the same vector moves the
    /// frame with it (nothing left); a tilted reference normal keeps the frame orthonormal,
    /// and δ's components in it have δ's length.
    #[test]
    fn placement_by_hand() {
        let d = [0.003, -0.004, 0.002];
        // Three nodes whose mean is d, none equal to it.
        let top = [
            [0.001, -0.004, 0.005],
            [0.004, -0.006, 0.0],
            [0.004, -0.002, 0.001],
        ];
        let p = placement(top, &[], [0.0, 0.0, 1.0]);
        assert!((p.decenter_x - d[0]).abs() < 1e-18, "{p:?}");
        assert!((p.decenter_y - d[1]).abs() < 1e-18, "{p:?}");
        assert!((p.decenter - 0.005).abs() < 1e-17, "{p:?}");
        assert!((p.despace - d[2]).abs() < 1e-18, "{p:?}");
        let moved = placement(top, &[d, d], [0.0, 0.0, 1.0]);
        assert!(
            moved.decenter < 1e-18 && moved.despace.abs() < 1e-18,
            "{moved:?}"
        );
        let nb = {
            let v: [f64; 3] = [0.3, -0.2, 1.0];
            let l = norm(v);
            [v[0] / l, v[1] / l, v[2] / l]
        };
        let (ex, ey) = in_plane_axes(nb);
        for (a, b) in [(ex, ex), (ey, ey), (nb, nb)] {
            assert!((dot(a, b) - 1.0).abs() < 1e-15);
        }
        for (a, b) in [(ex, ey), (ex, nb), (ey, nb)] {
            assert!(dot(a, b).abs() < 1e-15);
        }
        let t = placement(top, &[], nb);
        let length = (t.decenter * t.decenter + t.despace * t.despace).sqrt();
        assert!((length - norm(d)).abs() < 1e-17, "{t:?}");
        // A normal along x takes the y axis for e_x.
        let (ex, _) = in_plane_axes([1.0, 0.0, 0.0]);
        assert_eq!(ex, [0.0, 1.0, 0.0]);
    }

    /// [`theta_gradient`] against central differences of [`distortion`] on a tilted,
    /// displaced triangle and a reference normal off the axes.
    #[test]
    fn theta_gradient_matches_central_differences() {
        let x = [
            [0.0, 0.0, 1900.0],
            [380.0, 0.0, 1900.0],
            [190.0, 329.09, 1900.0],
        ];
        let u = [
            [0.011, -0.004, 0.021],
            [-0.007, 0.013, -0.018],
            [0.002, 0.009, 0.034],
        ];
        let nb = {
            let v = [0.01, -0.02, 1.0];
            let l = norm(v);
            [v[0] / l, v[1] / l, v[2] / l]
        };
        let g = theta_gradient(x, u, nb).unwrap();
        let largest = g.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let h = 1e-6;
        for k in 0..3 {
            for d in 0..3 {
                let (mut up, mut down) = (u, u);
                up[k][d] += h;
                down[k][d] -= h;
                let fd =
                    (distortion(x, up, nb).theta_p - distortion(x, down, nb).theta_p) / (2.0 * h);
                assert!(
                    (fd - g[k][d]).abs() <= 1e-6 * largest,
                    "node {k} dir {d}: {fd} vs {}",
                    g[k][d]
                );
            }
        }
        // A flat, undisplaced surface against its own normal: θ_P = 0, no gradient.
        assert!(theta_gradient(x, [[0.0; 3]; 3], [0.0, 0.0, 1.0]).is_none());
    }

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
