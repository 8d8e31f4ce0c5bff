//! The paper's path: consistent mass matrices, the Schur complement (eq. 80) applied
//! matrix-free and solved by GMRES. The inner solves with `M` (and `M⃗ = M ⊗ I`) use
//! a sparse Cholesky factorization of `M` (symbolic part reused), and GMRES is
//! right-preconditioned by the lumped Schur complement of [`super::LumpedSolver`].
//!
//! ```text
//! L2/H1: (A_α + M_β) V + τ M_g C V = −M f − M_g k⁰
//! H⁻¹:   M V + τ A (g ∘ C V)       = −A (f + g ∘ k⁰)
//! C = M⁻¹ Σ_c N_cᵀ M⁻¹ A M⁻¹ N_c,  k⁰ = M⁻¹ Σ_c N_cᵀ M⁻¹ A X_c,  V⃗_c = M⁻¹ N_c V
//! ```
//!
//! where `N_c` is the `c`-th component of `N⃗_ij = ∫ φ_i φ_j ν` (symmetric).

use super::LumpedSolver;
use crate::fem::Weight;
use crate::flow::system::{LinearSystem, ProductWeights};
use crate::flow::FlowError;
use crate::geometry::Point;
use crate::linalg::{gmres, GmresOutcome, SparseCholesky};

/// Stateful consistent-mass solver (keeps the symbolic factorizations).
#[derive(Default)]
pub struct ConsistentSolver {
    lumped: LumpedSolver,
    mass: Option<SparseCholesky>,
    /// Outcome of the last GMRES solve.
    pub last: Option<GmresOutcome>,
}

impl ConsistentSolver {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Solve for `V` and `V⃗`.
    pub fn solve<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> Result<(Vec<f64>, Vec<Point<D>>), FlowError> {
        let p = sys.pattern;
        let mx = sys.matrices;
        let n = p.size();
        let sym = p.symbolic().as_ref();
        if self.mass.is_none() {
            self.mass = Some(SparseCholesky::new(sym).map_err(FlowError::Factorization)?);
        }
        let mfac = self.mass.as_mut().unwrap();
        mfac.factorize(sym, &mx.mass).map_err(|e| FlowError::Factorization(format!("mass matrix: {e}")))?;
        let mfac = self.mass.as_ref().unwrap();
        let msolve = |x: &mut [f64]| mfac.solve_in_place(x);
        let normal = mx.consistent_normal(sys.mesh, p);
        let mut tmp = vec![0.0; n];
        let mut tmp2 = vec![0.0; n];
        // C v = M⁻¹ Σ_c N_c M⁻¹ A M⁻¹ N_c v
        let mut curvature_op = |v: &[f64], out: &mut [f64]| {
            out.iter_mut().for_each(|o| *o = 0.0);
            for nc in normal.iter() {
                p.mul(nc, v, &mut tmp);
                msolve(&mut tmp);
                p.mul(&mx.stiffness, &tmp, &mut tmp2);
                msolve(&mut tmp2);
                p.mul(nc, &tmp2, &mut tmp);
                out.iter_mut().zip(&tmp).for_each(|(o, t)| *o += t);
            }
            msolve(out);
        };
        // k⁰ = M⁻¹ Σ_c N_c M⁻¹ (A X)_c
        let mut k0 = vec![0.0; n];
        for (c, nc) in normal.iter().enumerate() {
            let mut axc: Vec<f64> = sys.ax.iter().map(|a| a[c]).collect();
            msolve(&mut axc);
            let mut t = vec![0.0; n];
            p.mul(nc, &axc, &mut t);
            k0.iter_mut().zip(&t).for_each(|(k, ti)| *k += ti);
        }
        msolve(&mut k0);

        let lumped_v = self.lumped.solve(sys)?;
        let lumped = &self.lumped;
        let mut rhs = vec![0.0; n];
        let mut cv = vec![0.0; n];
        let mut t3 = vec![0.0; n];
        let outcome;
        let mut v;
        match sys.product {
            ProductWeights::HMinus1 => {
                let w: Vec<f64> = (0..n).map(|i| sys.f[i] + sys.g[i] * k0[i]).collect();
                p.mul(&mx.stiffness, &w, &mut rhs);
                rhs.iter_mut().for_each(|r| *r = -*r);
                let apply = |x: &[f64], out: &mut [f64]| {
                    curvature_op(x, &mut cv);
                    cv.iter_mut().zip(sys.g).for_each(|(c, g)| *c *= sys.tau * g);
                    p.mul(&mx.stiffness, &cv, out);
                    p.mul(&mx.mass, x, &mut t3);
                    out.iter_mut().zip(&t3).for_each(|(o, t)| *o += t);
                };
                v = lumped_v;
                outcome = gmres(apply, |x| lumped.apply_last_factor(x), &rhs, &mut v, 1e-10, 50, 500);
            }
            _ => {
                let b = match sys.product {
                    ProductWeights::H1 { alpha, beta } => {
                        let mut b = mx.weighted_stiffness(sys.mesh, p, alpha);
                        let mb = mx.weighted_mass(sys.mesh, p, beta);
                        b.iter_mut().zip(&mb).for_each(|(x, y)| *x += y);
                        b
                    }
                    _ => mx.mass.clone(),
                };
                let mg = mx.weighted_mass(sys.mesh, p, &Weight::Vertex(sys.g.to_vec()));
                p.mul(&mx.mass, sys.f, &mut rhs);
                p.mul(&mg, &k0, &mut t3);
                rhs.iter_mut().zip(&t3).for_each(|(r, t)| *r = -*r - t);
                let mut t4 = vec![0.0; n];
                let apply = |x: &[f64], out: &mut [f64]| {
                    curvature_op(x, &mut cv);
                    p.mul(&mg, &cv, out);
                    p.mul(&b, x, &mut t4);
                    out.iter_mut().zip(&t4).for_each(|(o, t)| *o = sys.tau * *o + t);
                };
                v = lumped_v;
                outcome = gmres(apply, |x| lumped.apply_last_factor(x), &rhs, &mut v, 1e-10, 50, 500);
            }
        }
        self.last = Some(outcome);
        if !outcome.converged {
            return Err(FlowError::NoConvergence {
                residual: outcome.relative_residual,
                iterations: outcome.iterations,
            });
        }
        let mut vector = vec![Point::<D>::zeros(); n];
        for (c, nc) in normal.iter().enumerate() {
            let mut t = vec![0.0; n];
            p.mul(nc, &v, &mut t);
            msolve(&mut t);
            for i in 0..n {
                vector[i][c] = t[i];
            }
        }
        Ok((v, vector))
    }
}
