//! Conjugate gradients with a diagonal (Jacobi) preconditioner, for symmetric
//! positive definite systems whose diagonal dominates enough that a few dozen
//! iterations reach a tight residual (a mass matrix plus a short step's
//! stiffness).

/// Solve `A x = b` (`apply(x, y)`: `y = A x`; `diagonal`: `A`'s) from `x = 0` until
/// `‖b − A x‖ ≤ tol ‖b‖`. Returns the iterations taken, or `None` if `max_iter`
/// did not reach the tolerance or the matrix showed itself not positive definite
/// (`x` is then unspecified).
pub fn pcg(
    apply: impl Fn(&[f64], &mut [f64]),
    diagonal: &[f64],
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    max_iter: usize,
) -> Option<usize> {
    let n = b.len();
    if diagonal.iter().any(|&d| d.is_nan() || d <= 0.0) {
        return None;
    }
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    x.iter_mut().for_each(|v| *v = 0.0);
    let goal = tol * dot(b, b).sqrt();
    let mut r = b.to_vec();
    if dot(&r, &r).sqrt() <= goal {
        return Some(0);
    }
    let mut z: Vec<f64> = r.iter().zip(diagonal).map(|(r, d)| r / d).collect();
    let mut p = z.clone();
    let mut ap = vec![0.0; n];
    let mut rz = dot(&r, &z);
    for k in 1..=max_iter {
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        // not positive definite (or NaN)
        if pap.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        if dot(&r, &r).sqrt() <= goal {
            return Some(k);
        }
        for i in 0..n {
            z[i] = r[i] / diagonal[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D mass-plus-stiffness matrix `2 + 2s` on the diagonal, `−s` beside it:
    /// the solution of a known right-hand side, in fewer iterations than unknowns.
    #[test]
    fn solves_a_diagonally_dominant_system() {
        let (n, s) = (200, 3.0);
        let apply = |x: &[f64], y: &mut [f64]| {
            for i in 0..n {
                let left = if i > 0 { x[i - 1] } else { 0.0 };
                let right = if i + 1 < n { x[i + 1] } else { 0.0 };
                y[i] = (2.0 + 2.0 * s) * x[i] - s * (left + right);
            }
        };
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        apply(&exact, &mut b);
        let mut x = vec![0.0; n];
        let iterations = pcg(apply, &vec![2.0 + 2.0 * s; n], &b, &mut x, 1e-12, 500).unwrap();
        assert!(iterations < 100, "{iterations}");
        let error = x.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(error < 1e-10, "{error}");
        // not positive definite: refused
        assert!(
            pcg(|x, y| y.iter_mut().zip(x).for_each(|(y, x)| *y = -x), &vec![1.0; n], &b, &mut x, 1e-12, 50).is_none()
        );
    }
}
