//! Direct solve of cyclic tridiagonal systems: the lumped Schur complement of a
//! closed curve (L2/H1) couples each vertex with its two neighbours only, so each
//! component is a periodic tridiagonal system, solved in `O(n)` by the Thomas
//! algorithm plus a Sherman–Morrison correction for the two corner entries.

/// One closed component: vertex indices in cycle order, and for each the value
/// positions of `S[v_k, v_{k−1}]`, `S[v_k, v_k]`, `S[v_k, v_{k+1}]`.
#[derive(Debug, Clone)]
pub(crate) struct CyclicComponent {
    pub vertices: Vec<usize>,
    pub positions: Vec<[usize; 3]>,
}

/// `x ← T⁻¹ x` per component; false on a zero pivot (then `x` is unspecified).
pub(crate) fn cyclic_solve_checked(comps: &[CyclicComponent], diags: &[[Vec<f64>; 3]], x: &mut [f64]) -> bool {
    for (comp, [a, b, c]) in comps.iter().zip(diags) {
        let r: Vec<f64> = comp.vertices.iter().map(|&v| x[v]).collect();
        match solve_cyclic_tridiagonal(a, b, c, &r) {
            Some(y) => comp.vertices.iter().zip(y).for_each(|(&v, yi)| x[v] = yi),
            None => return false,
        }
    }
    true
}

/// [`cyclic_solve_checked`] for a preconditioner (a zero pivot cannot occur for a
/// matrix that was solved before).
pub(crate) fn cyclic_solve(comps: &[CyclicComponent], diags: &[[Vec<f64>; 3]], x: &mut [f64]) {
    cyclic_solve_checked(comps, diags, x);
}

/// Solve `T x = r` for the cyclic tridiagonal `T` with sub-diagonal `a` (`a_k` at
/// column `k−1 mod n`), diagonal `b` and super-diagonal `c` (`c_k` at `k+1 mod n`).
/// Returns `None` on a (near) zero pivot; `n ≥ 3`.
pub fn solve_cyclic_tridiagonal(a: &[f64], b: &[f64], c: &[f64], r: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    debug_assert!(n >= 3);
    let (alpha, beta) = (c[n - 1], a[0]); // T[n−1][0], T[0][n−1]
    let gamma = -b[0];
    // Thomas elimination of the tridiagonal part with b₀ − γ and b_{n−1} − αβ/γ,
    // applied at once to r and to u = (γ, 0, …, 0, α).
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    let mut cp = vec![0.0; n];
    let mut x = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut piv = b[0] - gamma;
    for k in 0..n {
        if k > 0 {
            let bk = if k == n - 1 { b[k] - alpha * beta / gamma } else { b[k] };
            piv = bk - a[k] * cp[k - 1];
        }
        if !(piv.abs() > 1e-14 * scale) {
            return None;
        }
        let ip = 1.0 / piv;
        cp[k] = c[k] * ip;
        let uk = if k == 0 {
            gamma
        } else if k == n - 1 {
            alpha
        } else {
            0.0
        };
        if k == 0 {
            x[0] = r[0] * ip;
            z[0] = uk * ip;
        } else {
            x[k] = (r[k] - a[k] * x[k - 1]) * ip;
            z[k] = (uk - a[k] * z[k - 1]) * ip;
        }
    }
    for k in (0..n - 1).rev() {
        x[k] -= cp[k] * x[k + 1];
        z[k] -= cp[k] * z[k + 1];
    }
    let denom = 1.0 + z[0] + beta * z[n - 1] / gamma;
    if denom.abs() < 1e-300 {
        return None;
    }
    let fact = (x[0] + beta * x[n - 1] / gamma) / denom;
    x.iter_mut().zip(&z).for_each(|(xi, zi)| *xi -= fact * zi);
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_dense_solve() {
        for n in [3, 4, 9] {
            let a: Vec<f64> = (0..n).map(|k| -1.0 - 0.1 * k as f64).collect();
            let b: Vec<f64> = (0..n).map(|k| 4.0 + 0.3 * k as f64).collect();
            let c: Vec<f64> = (0..n).map(|k| -0.5 + 0.05 * k as f64).collect();
            let xs: Vec<f64> = (0..n).map(|k| (k as f64 + 1.0).sin()).collect();
            let mut r = vec![0.0; n];
            for k in 0..n {
                r[k] = b[k] * xs[k] + a[k] * xs[(k + n - 1) % n] + c[k] * xs[(k + 1) % n];
            }
            let x = solve_cyclic_tridiagonal(&a, &b, &c, &r).unwrap();
            for k in 0..n {
                assert!((x[k] - xs[k]).abs() < 1e-12, "n={n} k={k}: {} vs {}", x[k], xs[k]);
            }
        }
    }
}
