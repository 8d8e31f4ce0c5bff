//! The lumped-mass Schur complement, assembled explicitly and factorized by faer's
//! sparse direct solvers with the symbolic factorization reused while the
//! connectivity is unchanged.
//!
//! Lumping: the vector rows of (74) use `m_i = ∫ φ_i` for `M⃗`, and `N⃗` becomes
//! `N⃗_i = ∫ φ_i ν`; the scalar rows (for `K` and `V`) use
//! `m̂_i = |N⃗_i|² / m_i`, an `O(h²)` perturbation of `m_i` chosen so that the scheme
//! keeps the structure of the continuous flow exactly at first order in τ:
//! with `V⃗_i = N⃗_i V_i / m_i` the first variations of the enclosed measure and of
//! `|Γ|` are `Σ m̂_i V_i` and `Σ m̂_i κ_i V_i`, where `κ_i = N⃗_i·(A X)_i / |N⃗_i|²`.
//! Hence surface diffusion conserves area/volume up to `O(τ²)` per step (the
//! columns of `A` sum to zero) and decreases `|Γ|`.
//!
//! Eliminating `K⃗, K, V⃗` gives, for L2 and H1 (`B = A_α + M̂_β`),
//!
//! ```text
//! S_ij = B_ij + τ g_i (N⃗_i·N⃗_j) A_ij / (m_i m_j)          (one-ring stencil)
//! (S V)_i = −m̂_i f_i − g_i N⃗_i·(A X)_i / m_i
//! ```
//!
//! and for `H^{-1}` (`M̂ V + A (g K + f) = 0`, `K = κ⁰ + τ M̂⁻¹ Q V`,
//! `Q_jk = A_jk N⃗_j·N⃗_k / (m_j m_k)`, `κ⁰_j = N⃗_j·(A X)_j / |N⃗_j|²`)
//!
//! ```text
//! S = M̂ + τ A diag(g/m̂) Q                                   (two-ring stencil)
//! S V = −A (f + g κ⁰)
//! ```
//!
//! Finally `V⃗_i = N⃗_i V_i / m_i`. `S` is symmetric positive definite when `g` is a
//! nonnegative constant in the L2/H1 case (Cholesky); otherwise LU is used.
//!
//! The `H^{-1}` complement is not symmetric (`Q ≠ A`), but `Q = A + E` with `E`
//! of the size of `κ² M`: it is solved by GMRES right-preconditioned with the
//! Cholesky factorization of the symmetric `P = M̂ + τ ḡ A M̂⁻¹ A` (same two-ring
//! pattern, `ḡ` the mean of `|g|`), which converges in a few iterations to 1e-12;
//! sparse LU of `S` is the fallback.

use super::system::{LinearSystem, ProductWeights};
use super::gmres::gmres;
use super::FlowError;
use crate::fem::csc_mul;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{MatMut, Side};

/// A numeric factorization of a Schur complement.
pub enum Factor {
    Llt(Llt<usize, f64>),
    Lu(Lu<usize, f64>),
}

impl Factor {
    /// Solve `S x = b` in place.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let n = x.len();
        let m = MatMut::from_column_major_slice_mut(x, n, 1);
        match self {
            Factor::Llt(f) => f.solve_in_place(m),
            Factor::Lu(f) => f.solve_in_place(m),
        }
    }
}

/// The two-ring pattern used by the `H^{-1}` Schur complement.
struct TwoRing {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicSparseColMat<usize>,
    lu: Option<SymbolicLu<usize>>,
    llt: Option<SymbolicLlt<usize>>,
}

/// Stateful lumped Schur solver: keeps the symbolic factorizations for one
/// connectivity. Call [`LumpedSolver::reset`] when the connectivity changes.
#[derive(Default)]
pub struct LumpedSolver {
    llt: Option<SymbolicLlt<usize>>,
    lu: Option<SymbolicLu<usize>>,
    two_ring: Option<TwoRing>,
}

/// Assembled lumped Schur complement: values on a pattern plus right-hand side.
pub(crate) struct SchurMatrix {
    pub values: Vec<f64>,
    /// Values of the SPD preconditioner `P` (two-ring case only).
    pub precond: Option<Vec<f64>>,
    pub rhs: Vec<f64>,
    pub symmetric: bool,
    pub two_ring: bool,
}

impl LumpedSolver {
    pub fn new() -> Self {
        Self::default()
    }

    /// Forget the symbolic factorizations (after a connectivity change).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Solve for the scalar normal velocity `V`; returns `V` and the factorization.
    pub fn solve<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> Result<(Vec<f64>, Factor), FlowError> {
        let s = self.assemble(sys);
        if let Some(p) = &s.precond {
            if let Some(done) = self.solve_preconditioned(&s, p)? {
                return Ok(done);
            }
        }
        let factor = self.factorize(sys, &s)?;
        let mut v = s.rhs;
        factor.solve_in_place(&mut v);
        Ok((v, factor))
    }

    /// GMRES on the two-ring `S` with the Cholesky factorization of `P`; `None` if
    /// `P` is not positive definite or GMRES stalls (then LU takes over).
    fn solve_preconditioned(&mut self, s: &SchurMatrix, p: &[f64]) -> Result<Option<(Vec<f64>, Factor)>, FlowError> {
        let tr = self.two_ring.as_mut().expect("two-ring pattern built in assemble");
        if tr.llt.is_none() {
            let sym = SymbolicLlt::try_new(tr.symbolic.as_ref(), Side::Lower)
                .map_err(|e| FlowError::Factorization(format!("{e:?}")))?;
            tr.llt = Some(sym);
        }
        let mat = SparseColMatRef::new(tr.symbolic.as_ref(), p);
        let Ok(llt) = Llt::try_new_with_symbolic(tr.llt.clone().unwrap(), mat, Side::Lower) else {
            return Ok(None);
        };
        let factor = Factor::Llt(llt);
        let mut v = s.rhs.clone();
        factor.solve_in_place(&mut v);
        let (cp, ri) = (&tr.col_ptr, &tr.row_idx);
        let apply = |x: &[f64], y: &mut [f64]| csc_mul(cp, ri, &s.values, x, y);
        let out = gmres(apply, |x| factor.solve_in_place(x), &s.rhs, &mut v, 1e-12, 30, 120);
        Ok(out.converged.then_some((v, factor)))
    }

    pub(crate) fn assemble<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> SchurMatrix {
        match sys.product {
            ProductWeights::HMinus1 => self.assemble_h_minus_1(sys),
            _ => assemble_l2_h1(sys),
        }
    }

    pub(crate) fn factorize<const D: usize>(&mut self, sys: &LinearSystem<'_, D>, s: &SchurMatrix) -> Result<Factor, FlowError> {
        let err = |e: String| FlowError::Factorization(e);
        if s.two_ring {
            let tr = self.two_ring.as_mut().expect("two-ring pattern built in assemble");
            let mat = SparseColMatRef::new(tr.symbolic.as_ref(), &s.values);
            if tr.lu.is_none() {
                tr.lu = Some(SymbolicLu::try_new(tr.symbolic.as_ref()).map_err(|e| err(format!("{e:?}")))?);
            }
            let lu = Lu::try_new_with_symbolic(tr.lu.clone().unwrap(), mat).map_err(|e| err(format!("{e:?}")))?;
            return Ok(Factor::Lu(lu));
        }
        let sym = sys.pattern.symbolic();
        let mat = SparseColMatRef::new(sym.as_ref(), &s.values);
        if s.symmetric {
            if self.llt.is_none() {
                self.llt = Some(SymbolicLlt::try_new(sym.as_ref(), Side::Lower).map_err(|e| err(format!("{e:?}")))?);
            }
            if let Ok(f) = Llt::try_new_with_symbolic(self.llt.clone().unwrap(), mat, Side::Lower) {
                return Ok(Factor::Llt(f));
            }
            // not positive definite (e.g. τ too large with g < 0): fall back to LU
        }
        if self.lu.is_none() {
            self.lu = Some(SymbolicLu::try_new(sym.as_ref()).map_err(|e| err(format!("{e:?}")))?);
        }
        let lu = Lu::try_new_with_symbolic(self.lu.clone().unwrap(), mat).map_err(|e| err(format!("{e:?}")))?;
        Ok(Factor::Lu(lu))
    }

    fn assemble_h_minus_1<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> SchurMatrix {
        let p = sys.pattern;
        let n = p.size();
        if self.two_ring.is_none() {
            let (col_ptr, row_idx) = p.squared();
            let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx.clone());
            self.two_ring = Some(TwoRing { col_ptr, row_idx, symbolic, lu: None, llt: None });
        }
        let tr = self.two_ring.as_ref().unwrap();
        let m = &sys.matrices.lumped_mass;
        let mh = &sys.matrices.scalar_mass;
        let nn = &sys.matrices.lumped_normal;
        let a = &sys.matrices.stiffness;
        let (cp, ri) = (p.col_ptr(), p.row_idx());
        let mut values = vec![0.0; tr.row_idx.len()];
        let mut precond = vec![0.0; tr.row_idx.len()];
        let gbar = sys.g.iter().map(|g| g.abs()).sum::<f64>() / n as f64;
        let mut pos = vec![usize::MAX; n];
        for k in 0..n {
            for q in tr.col_ptr[k]..tr.col_ptr[k + 1] {
                pos[tr.row_idx[q]] = q;
            }
            values[pos[k]] += mh[k];
            precond[pos[k]] += mh[k];
            for pj in cp[k]..cp[k + 1] {
                let j = ri[pj];
                // τ (g_j / m̂_j) Q_jk
                let qjk = sys.tau * sys.g[j] / mh[j] * a[pj] * nn[j].dot(&nn[k]) / (m[j] * m[k]);
                let pjk = sys.tau * gbar / mh[j] * a[pj];
                for pi in cp[j]..cp[j + 1] {
                    values[pos[ri[pi]]] += a[pi] * qjk;
                    precond[pos[ri[pi]]] += a[pi] * pjk;
                }
            }
        }
        let w: Vec<f64> = (0..n)
            .map(|j| sys.f[j] + sys.g[j] * nn[j].dot(&sys.ax[j]) / nn[j].norm_squared())
            .collect();
        let mut rhs = vec![0.0; n];
        p.mul(a, &w, &mut rhs);
        rhs.iter_mut().for_each(|r| *r = -*r);
        SchurMatrix { values, precond: Some(precond), rhs, symmetric: false, two_ring: true }
    }
}

fn assemble_l2_h1<const D: usize>(sys: &LinearSystem<'_, D>) -> SchurMatrix {
    let p = sys.pattern;
    let mx = sys.matrices;
    let n = p.size();
    let (m, mh, nn, a) = (&mx.lumped_mass, &mx.scalar_mass, &mx.lumped_normal, &mx.stiffness);
    let (mut values, beta) = match sys.product {
        ProductWeights::H1 { alpha, beta } => (
            mx.weighted_stiffness(sys.mesh, p, alpha),
            beta.at_vertices(sys.mesh, mx),
        ),
        _ => (vec![0.0; p.nnz()], vec![1.0; n]),
    };
    for j in 0..n {
        values[p.diag()[j]] += beta[j] * mh[j];
        for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
            let i = p.row_idx()[k];
            values[k] += sys.tau * sys.g[i] * nn[i].dot(&nn[j]) * a[k] / (m[i] * m[j]);
        }
    }
    let rhs = (0..n).map(|i| -mh[i] * sys.f[i] - sys.g[i] * nn[i].dot(&sys.ax[i]) / m[i]).collect();
    let g0 = sys.g[0];
    let symmetric = g0 >= 0.0 && sys.g.iter().all(|&g| g == g0);
    SchurMatrix { values, precond: None, rhs, symmetric, two_ring: false }
}
