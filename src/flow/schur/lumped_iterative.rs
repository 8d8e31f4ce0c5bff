//! The iterative solves of the explicit lumped Schur complement: conjugate
//! gradients on a surface's L2 complement, and GMRES preconditioned by the
//! Cholesky factor of the symmetric part where a varying `g` makes `S`
//! unsymmetric. Each returns `None` where the direct solves of
//! [`super::lumped`] take over.

use super::lumped::{Last, LumpedSolver, SchurMatrix};
use crate::fem::csc_mul;
use crate::flow::system::LinearSystem;
use crate::linalg::{gmres, pcg, SparseCholesky};

/// The most conjugate-gradient iterations tried on a surface's L2 complement
/// before the direct solve (the nuclei volume's steps take 7–61; at 100, the step
/// bench's 163,842-vertex sphere fell back and took 1.9 times the factorization).
const PCG_ITERATIONS: usize = 300;

impl LumpedSolver {
    /// `S` symmetric (surfaces, L2: a lumped mass plus a step's stiffness):
    /// Jacobi-preconditioned conjugate gradients to a relative residual of 1e-12;
    /// `None` if they do not get there in [`PCG_ITERATIONS`] (then the direct
    /// solve: a long step on a fine mesh, whose iterations would grow faster than
    /// the factorization's cost).
    pub(super) fn solve_pcg<const D: usize>(&mut self, sys: &LinearSystem<'_, D>, s: &SchurMatrix) -> Option<Vec<f64>> {
        let p = sys.pattern;
        let (col_ptr, row_idx) = (p.col_ptr(), p.row_idx());
        let diagonal: Vec<f64> = p.diag().iter().map(|&k| s.values[k]).collect();
        let mut v = vec![0.0; p.size()];
        pcg(|x, y| csc_mul(col_ptr, row_idx, &s.values, x, y), &diagonal, &s.rhs, &mut v, 1e-12, PCG_ITERATIONS)?;
        self.last = Last::None;
        Some(v)
    }

    /// `S` not symmetric only through `τ g_i Q_ij` with `g > 0` varying (e.g. `g = H`
    /// in segmentation): GMRES preconditioned by a Cholesky factorization of the
    /// symmetric part `(S + Sᵀ)/2` (one-ring pattern, symbolic factorization kept),
    /// which is close to `S` when `g` varies slowly between neighbours. `None` if the
    /// symmetric part is not positive definite or GMRES does not converge (then LU).
    pub(super) fn solve_by_symmetric_part<const D: usize>(
        &mut self,
        sys: &LinearSystem<'_, D>,
        s: &SchurMatrix,
    ) -> Option<Vec<f64>> {
        let p = sys.pattern;
        let (col_ptr, row_idx) = (p.col_ptr(), p.row_idx());
        let mut sym = s.values.clone();
        for j in 0..p.size() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[k];
                if i <= j {
                    continue;
                }
                // the transposed entry (j, i) in column i
                let col = &row_idx[col_ptr[i]..col_ptr[i + 1]];
                let t = col_ptr[i] + col.binary_search(&j).ok()?;
                let mean = 0.5 * (s.values[k] + s.values[t]);
                sym[k] = mean;
                sym[t] = mean;
            }
        }
        let symbolic = p.symbolic().as_ref();
        if self.chol.is_none() {
            self.chol = Some(SparseCholesky::new(symbolic).ok()?);
        }
        let chol = self.chol.as_mut().unwrap();
        chol.factorize(symbolic, &sym).ok()?;
        let chol = self.chol.as_ref().unwrap();
        let mut v = vec![0.0; p.size()];
        let out = gmres(
            |x, y| csc_mul(col_ptr, row_idx, &s.values, x, y),
            |x| chol.solve_in_place(x),
            &s.rhs,
            &mut v,
            1e-10,
            40,
            200,
        );
        if !out.converged {
            return None;
        }
        self.last = Last::OneRingCholesky;
        Some(v)
    }
}
