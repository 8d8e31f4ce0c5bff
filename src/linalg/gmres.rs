//! Restarted GMRES with right preconditioning (flexible form: the preconditioned
//! Krylov vectors `z_j = P⁻¹ v_j` are kept, so `x += Σ y_j z_j`). faer has no GMRES;
//! the Schur complement of the consistent-mass path is non-symmetric in general.

/// Result of a GMRES solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresOutcome {
    pub iterations: usize,
    /// Final residual `‖b − A x‖ / ‖b‖`.
    pub relative_residual: f64,
    pub converged: bool,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve `A x = b` with `apply(v, out)` computing `out = A v` and
/// `precondition(v)` overwriting `v` with `P⁻¹ v`. `x` holds the initial guess.
pub fn gmres(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&mut [f64]),
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    restart: usize,
    max_iterations: usize,
) -> GmresOutcome {
    let n = b.len();
    let bnorm = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
    let mut r = vec![0.0; n];
    let mut iterations = 0;
    loop {
        apply(x, &mut r);
        r.iter_mut().zip(b).for_each(|(ri, bi)| *ri = bi - *ri);
        let beta = dot(&r, &r).sqrt();
        if beta / bnorm <= tol || iterations >= max_iterations {
            return GmresOutcome { iterations, relative_residual: beta / bnorm, converged: beta / bnorm <= tol };
        }
        let m = restart.max(1);
        let mut v: Vec<Vec<f64>> = vec![r.iter().map(|ri| ri / beta).collect()];
        let mut z: Vec<Vec<f64>> = Vec::with_capacity(m);
        let mut h = vec![vec![0.0; m]; m + 1];
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta;
        let mut k = 0;
        while k < m && iterations < max_iterations {
            let mut zk = v[k].clone();
            precondition(&mut zk);
            let mut w = vec![0.0; n];
            apply(&zk, &mut w);
            z.push(zk);
            for (i, vi) in v.iter().enumerate() {
                let hik = dot(&w, vi);
                h[i][k] = hik;
                w.iter_mut().zip(vi).for_each(|(wj, vj)| *wj -= hik * vj);
            }
            let hn = dot(&w, &w).sqrt();
            h[k + 1][k] = hn;
            for i in 0..k {
                let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
                h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
                h[i][k] = t;
            }
            let rho = (h[k][k] * h[k][k] + h[k + 1][k] * h[k + 1][k]).sqrt();
            if rho == 0.0 {
                break;
            }
            cs[k] = h[k][k] / rho;
            sn[k] = h[k + 1][k] / rho;
            h[k][k] = rho;
            h[k + 1][k] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            iterations += 1;
            k += 1;
            if g[k].abs() / bnorm <= tol || hn == 0.0 {
                break;
            }
            v.push(w.iter().map(|wj| wj / hn).collect());
        }
        // back substitution H y = g
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let s: f64 = (i + 1..k).map(|j| h[i][j] * y[j]).sum();
            y[i] = (g[i] - s) / h[i][i];
        }
        for (yj, zj) in y.iter().zip(&z) {
            x.iter_mut().zip(zj).for_each(|(xi, zi)| *xi += yj * zi);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_nonsymmetric_tridiagonal() {
        let n = 50;
        let apply = |v: &[f64], out: &mut [f64]| {
            for i in 0..n {
                out[i] = 4.0 * v[i]
                    - if i > 0 { 1.5 * v[i - 1] } else { 0.0 }
                    - if i + 1 < n { 0.5 * v[i + 1] } else { 0.0 };
            }
        };
        let xs: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut b = vec![0.0; n];
        apply(&xs, &mut b);
        let mut x = vec![0.0; n];
        let out = gmres(apply, |_| {}, &b, &mut x, 1e-12, 10, 500);
        assert!(out.converged, "{out:?}");
        assert!(x.iter().zip(&xs).all(|(a, b)| (a - b).abs() < 1e-9));
    }
}
