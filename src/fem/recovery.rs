//! Recovery of tangential derivatives of P1 functions on curves.

use crate::geometry::CurveMesh;
use nalgebra::{Matrix3, Vector3};

/// Tangential derivatives `∂_s u` at the vertices of a curve (periodic or not) by
/// patch recovery: the slope at `s = 0` of the least-squares quadratic in arclength
/// through the values at the vertex and its two neighbours on either side (exact
/// for quadratics, so `O(h²)` for smooth `u`, and it averages out mesh-level noise).
/// Components of fewer than five vertices use the central difference quotient.
pub fn tangential_derivative(mesh: &CurveMesh, u: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; mesh.num_vertices()];
    for (cyc, (pts, shift)) in mesh.cycles().iter().zip(mesh.lifted_cycles()) {
        let n = cyc.len();
        let next = |k: usize| if k + 1 < n { pts[k + 1] } else { pts[0] + shift };
        let len: Vec<f64> = (0..n).map(|k| (next(k) - pts[k]).norm()).collect();
        for k in 0..n {
            let (lp, ln) = (len[(k + n - 1) % n], len[k]);
            if n < 5 {
                out[cyc[k]] = (u[cyc[(k + 1) % n]] - u[cyc[(k + n - 1) % n]]) / (lp + ln);
                continue;
            }
            // arclength offsets of k−2..k+2
            let s = [-(len[(k + n - 2) % n] + lp), -lp, 0.0, ln, ln + len[(k + 1) % n]];
            let v: [f64; 5] = std::array::from_fn(|j| u[cyc[(k + n + j - 2) % n]]);
            out[cyc[k]] = quadratic_slope(&s, &v);
        }
    }
    out
}

/// Slope at 0 of the least-squares quadratic through `(s_j, v_j)`.
fn quadratic_slope(s: &[f64; 5], v: &[f64; 5]) -> f64 {
    let scale = (s[4] - s[0]).abs().max(f64::MIN_POSITIVE);
    let (mut m, mut r) = (Matrix3::<f64>::zeros(), Vector3::<f64>::zeros());
    for (&sj, &vj) in s.iter().zip(v) {
        let t = sj / scale;
        let phi = Vector3::new(1.0, t, t * t);
        m += phi * phi.transpose();
        r += phi * vj;
    }
    m.lu().solve(&r).map_or(0.0, |c| c[1] / scale)
}
