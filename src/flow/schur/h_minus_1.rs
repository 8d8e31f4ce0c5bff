//! The lumped `H^{-1}` step (surface diffusion) solved without assembling its
//! two-ring Schur complement.
//!
//! With `s = √(τ ḡ)` (`ḡ` the mean of `|g|`) and `B = M̂ + s A` (one-ring, SPD), the
//! matrix `P̃ = B M̂⁻¹ B = M̂ + 2sA + s² A M̂⁻¹ A` is spectrally equivalent to
//! `S = M̂ + τ A diag(g/m̂) Q` up to a factor 2 (for each eigenmode of `M̂⁻¹A` with
//! eigenvalue λ, `(1 + sλ)² / (1 + s²λ²) ∈ [1, 2]`), and `Q = A + O(κ² M)`. GMRES
//! on `S`, applied matrix-free as `S v = m̂ ∘ v + τ A ((g/m̂) ∘ (Q v))`, with the
//! right preconditioner `P̃⁻¹ = B⁻¹ M̂ B⁻¹` therefore converges in a few iterations,
//! at the cost of one one-ring factorization of `B` per step (a cyclic tridiagonal
//! solve on curves): the same order of work as an L2 step. On surfaces `B` is
//! factorized in single precision (half the memory traffic in the triangular
//! solves, which dominate); GMRES in double precision makes up for it.
//!
//! With a bending energy `ε/2 ∫ κ²` (curves) the implicit part of the chemical
//! potential is `(g + ε M̂⁻¹A) K`, so `S = M̂ + τ A (diag(g) + ε M̂⁻¹A) M̂⁻¹ Q`
//! with symbol `1 + τgλ² + τελ³`. The preconditioner is then
//! `P̃ = B M̂⁻¹ B M̂⁻¹ C` with `B = M̂ + sA`, `C = M̂ + cA`, symbol
//! `(1 + sλ)²(1 + cλ)`: `s = √(τḡ)`, `c = ε/ḡ` (so that `s²c = τε`) while
//! `τḡ > (τε)^{2/3}`, else `s = c = (τε)^{1/3}`. In the first case every term of
//! the product is bounded by a multiple of the symbol's terms (ratio in `[2/9, 1]`),
//! in the second `τḡ ≤ c²` and the ratio lies in `[1/4, 1.15]`.

use super::lumped::{solve_f32, Last, LumpedSolver};
use crate::flow::system::LinearSystem;
use crate::flow::FlowError;
use crate::linalg::{cyclic_solve_checked, gmres, SparseCholesky};

impl LumpedSolver {
    /// `Some(V)`, or `None` if `B` could not be factorized or GMRES stalled (the
    /// caller then factorizes the assembled two-ring `S` by sparse LU).
    pub(super) fn solve_h_minus_1<const D: usize>(
        &mut self,
        sys: &LinearSystem<'_, D>,
    ) -> Result<Option<Vec<f64>>, FlowError> {
        let p = sys.pattern;
        let mx = sys.matrices;
        let n = p.size();
        let (m, mh, nn, a) = (&mx.lumped_mass, &mx.scalar_mass, &mx.lumped_normal, &mx.stiffness);
        let u: Vec<_> = nn.iter().zip(m).map(|(ni, mi)| ni / *mi).collect();
        // Q on the one-ring pattern, and B = M̂ + sA
        let gbar = sys.g.iter().map(|g| g.abs()).sum::<f64>() / n as f64;
        let eps = sys.bending;
        let (s, c) = if eps > 0.0 {
            let c3 = (sys.tau * eps).cbrt();
            if sys.tau * gbar > c3 * c3 {
                ((sys.tau * gbar).sqrt(), eps / gbar)
            } else {
                (c3, c3)
            }
        } else {
            ((sys.tau * gbar).sqrt(), 0.0)
        };
        let mut q = vec![0.0; p.nnz()];
        let mut b: Vec<f64> = a.iter().map(|x| s * x).collect();
        for j in 0..n {
            b[p.diag()[j]] += mh[j];
            for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                q[k] = a[k] * u[p.row_idx()[k]].dot(&u[j]);
            }
        }
        let cyclic = if D == 2 { Some(self.cyclic_diagonals(sys, &b)) } else { None };
        // C = M̂ + cA (bending only; curves, checked by the driver)
        let bending_factor = (eps > 0.0 && D == 2).then(|| {
            let mut cv: Vec<f64> = a.iter().map(|x| c * x).collect();
            for j in 0..n {
                cv[p.diag()[j]] += mh[j];
            }
            self.cyclic_diagonals(sys, &cv)
        });
        if cyclic.is_none() {
            let sym = p.symbolic().as_ref();
            if self.chol32.is_none() {
                self.chol32 = Some(SparseCholesky::new(sym).map_err(FlowError::Factorization)?);
            }
            let b32: Vec<f32> = b.iter().map(|&x| x as f32).collect();
            if self.chol32.as_mut().unwrap().factorize(sym, &b32).is_err() {
                return Ok(None);
            }
        }
        // right-hand side −A (f + g κ⁰ + ε M̂⁻¹A κ⁰), κ⁰_j = N⃗_j·(A X)_j / |N⃗_j|²
        let mut w: Vec<f64> =
            (0..n).map(|j| sys.f[j] + sys.g[j] * nn[j].dot(&sys.ax[j]) / nn[j].norm_squared()).collect();
        let mut t2 = vec![0.0; n];
        if eps > 0.0 {
            let k0: Vec<f64> = (0..n).map(|j| nn[j].dot(&sys.ax[j]) / nn[j].norm_squared()).collect();
            p.mul(a, &k0, &mut t2);
            w.iter_mut().zip(&t2).zip(mh).for_each(|((wj, ak), mj)| *wj += eps * ak / mj);
        }
        let mut rhs = vec![0.0; n];
        p.mul(a, &w, &mut rhs);
        rhs.iter_mut().for_each(|r| *r = -*r);

        let scale: Vec<f64> = (0..n).map(|j| sys.tau * sys.g[j] / mh[j]).collect();
        let mut t = vec![0.0; n];
        let apply = |v: &[f64], out: &mut [f64]| {
            p.mul(&q, v, &mut t);
            if eps > 0.0 {
                // δK = τ M̂⁻¹ Q v; the potential's change (g + ε M̂⁻¹A) δK
                t.iter_mut().zip(mh).for_each(|(ti, mj)| *ti *= sys.tau / mj);
                p.mul(a, &t, &mut t2);
                for j in 0..n {
                    t[j] = sys.g[j] * t[j] + eps * t2[j] / mh[j];
                }
            } else {
                t.iter_mut().zip(&scale).for_each(|(ti, sc)| *ti *= sc);
            }
            p.mul(a, &t, out);
            out.iter_mut().zip(mh).zip(v).for_each(|((o, mi), vi)| *o += mi * vi);
        };
        let comps = self.cycles.clone();
        let chol = self.chol32.as_ref();
        let mut ok = true;
        let mut precondition = |x: &mut [f64]| {
            let mut solve = |d: Option<&Vec<[Vec<f64>; 3]>>, x: &mut [f64]| match d {
                Some(d) => ok &= cyclic_solve_checked(comps.as_deref().unwrap(), d, x),
                None => solve_f32(chol.unwrap(), x),
            };
            if let Some(cd) = &bending_factor {
                solve(Some(cd), x);
                x.iter_mut().zip(mh).for_each(|(xi, mi)| *xi *= mi);
            }
            solve(cyclic.as_ref(), x);
            x.iter_mut().zip(mh).for_each(|(xi, mi)| *xi *= mi);
            solve(cyclic.as_ref(), x);
        };
        let mut v = rhs.clone();
        precondition(&mut v);
        let out = gmres(apply, &mut precondition, &rhs, &mut v, 1e-8, 40, 400);
        if !(out.converged && ok) {
            if eps > 0.0 {
                // the assembled two-ring fallback has no bending term
                return Err(FlowError::NoConvergence { residual: out.relative_residual, iterations: out.iterations });
            }
            return Ok(None);
        }
        self.last = Last::HMinus1 { scalar_mass: mh.clone(), cyclic, bending: bending_factor };
        Ok(Some(v))
    }
}
