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
//! nonnegative constant in the L2/H1 case (Cholesky); for positive varying `g`,
//! GMRES preconditioned by the Cholesky factor of the symmetric part; otherwise LU.
//!
//! The `H^{-1}` complement has a two-ring stencil and is not symmetric; see
//! [`super::h_minus_1`] for its preconditioned iterative solve (sparse LU of the
//! assembled `S` is the fallback).

use crate::fem::Pattern;
use crate::flow::system::{LinearSystem, ProductWeights};
use crate::flow::FlowError;
use crate::geometry::segment_cycles;
use crate::linalg::{cyclic_solve, cyclic_solve_checked, CyclicComponent, SparseCholesky};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::MatMut;

/// The two-ring pattern used by the `H^{-1}` Schur complement.
struct TwoRing {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicSparseColMat<usize>,
    lu: Option<SymbolicLu<usize>>,
}

/// Which factorization the last solve used.
#[derive(Default)]
pub(super) enum Last {
    #[default]
    None,
    OneRingCholesky,
    Lu(Box<Lu<usize, f64>>),
    /// The curve complement's three diagonals per component (re-solved per use).
    Cyclic(Vec<[Vec<f64>; 3]>),
    /// `H^{-1}`: `P̃⁻¹ = B⁻¹ M̂ B⁻¹` with `B = M̂ + sA` factorized (one-ring
    /// Cholesky, or cyclic diagonals on curves).
    HMinus1 {
        scalar_mass: Vec<f64>,
        cyclic: Option<Vec<[Vec<f64>; 3]>>,
        /// `C = M̂ + cA` of a bending energy (curves): `P̃⁻¹ = C⁻¹ M̂ B⁻¹ M̂ B⁻¹`.
        bending: Option<Vec<[Vec<f64>; 3]>>,
    },
}

/// Stateful lumped Schur solver: keeps the symbolic factorizations (and numeric
/// workspaces) for one connectivity. Call [`LumpedSolver::reset`] when the
/// connectivity changes.
#[derive(Default)]
pub struct LumpedSolver {
    pub(super) cycles: Option<Vec<CyclicComponent>>,
    pub(super) chol: Option<SparseCholesky>,
    /// Single-precision factorization of `B` for the `H^{-1}` preconditioner.
    pub(super) chol32: Option<SparseCholesky<f32>>,
    lu: Option<SymbolicLu<usize>>,
    two_ring: Option<TwoRing>,
    pub(super) last: Last,
    /// L2 surface complements by conjugate gradients first
    /// ([`LumpedSolver::iterative`]); the direct solve otherwise, whose factor
    /// [`LumpedSolver::apply_last_factor`] applies.
    iterative: bool,
}

/// Assembled lumped Schur complement: values on a pattern plus right-hand side.
pub(crate) struct SchurMatrix {
    pub values: Vec<f64>,
    pub rhs: Vec<f64>,
    pub symmetric: bool,
}

impl LumpedSolver {
    pub fn new() -> Self {
        Self::default()
    }

    /// A solver that solves the L2 complements of surfaces by Jacobi-preconditioned
    /// conjugate gradients (a lumped mass plus a step's stiffness: a few dozen
    /// iterations) before falling back to the direct solve; not for use as a
    /// preconditioner ([`LumpedSolver::apply_last_factor`] needs a factor).
    pub fn iterative() -> Self {
        LumpedSolver { iterative: true, ..Self::default() }
    }

    /// Forget the symbolic factorizations (after a connectivity change).
    pub fn reset(&mut self) {
        *self = LumpedSolver { iterative: self.iterative, ..Self::default() };
    }

    /// Solve for the scalar normal velocity `V`.
    pub fn solve<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> Result<Vec<f64>, FlowError> {
        self.solve_fixed(sys, &[])
    }

    /// Solve for `V` with the values `fixed[i] = Some(v)` held (an empty `fixed`
    /// holds none; the L2 and H1 products only: `H^{-1}` ignores it).
    pub fn solve_fixed<const D: usize>(
        &mut self,
        sys: &LinearSystem<'_, D>,
        fixed: &[Option<f64>],
    ) -> Result<Vec<f64>, FlowError> {
        if let ProductWeights::HMinus1 = sys.product {
            if let Some(v) = self.solve_h_minus_1(sys)? {
                return Ok(v);
            }
            let s = self.assemble_h_minus_1(sys);
            return self.solve_lu(s);
        }
        let mut s = assemble_l2_h1(sys);
        if !fixed.is_empty() {
            fix_unknowns(sys.pattern, &mut s.values, &mut s.rhs, fixed);
        }
        if D == 2 {
            if let Some(v) = self.solve_cyclic(sys, &s) {
                return Ok(v);
            }
        }
        if s.symmetric {
            if D == 3 && self.iterative && matches!(sys.product, ProductWeights::L2) {
                if let Some(v) = self.solve_pcg(sys, &s) {
                    return Ok(v);
                }
            }
            let sym = sys.pattern.symbolic().as_ref();
            if self.chol.is_none() {
                self.chol = Some(SparseCholesky::new(sym).map_err(FlowError::Factorization)?);
            }
            let chol = self.chol.as_mut().unwrap();
            if chol.factorize(sym, &s.values).is_ok() {
                let mut v = s.rhs;
                chol.solve_in_place(&mut v);
                self.last = Last::OneRingCholesky;
                return Ok(v);
            }
            // not positive definite: fall back to LU
        } else if sys.g.iter().all(|&g| g > 0.0) {
            if let Some(v) = self.solve_by_symmetric_part(sys, &s) {
                return Ok(v);
            }
        }
        let (v, lu) = lu_solve(&mut self.lu, sys.pattern.symbolic(), s)?;
        self.last = Last::Lu(Box::new(lu));
        Ok(v)
    }

    /// Apply the inverse of the last factorized matrix (the Schur complement, or its
    /// SPD approximation `P` in the `H^{-1}` case) to `x`: a preconditioner.
    pub fn apply_last_factor(&self, x: &mut [f64]) {
        match &self.last {
            Last::None => {}
            Last::OneRingCholesky => self.chol.as_ref().unwrap().solve_in_place(x),
            Last::HMinus1 { scalar_mass, cyclic, bending } => {
                if let Some(c) = bending {
                    cyclic_solve(self.cycles.as_ref().unwrap(), c, x);
                    x.iter_mut().zip(scalar_mass).for_each(|(xi, m)| *xi *= m);
                }
                self.solve_b(cyclic.as_deref(), x);
                x.iter_mut().zip(scalar_mass).for_each(|(xi, m)| *xi *= m);
                self.solve_b(cyclic.as_deref(), x);
            }
            Last::Lu(lu) => {
                let n = x.len();
                lu.solve_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
            }
            Last::Cyclic(diags) => cyclic_solve(self.cycles.as_ref().unwrap(), diags, x),
        }
    }

    /// `x ← B⁻¹ x` for the factorized one-ring `B` (cyclic diagonals or Cholesky).
    pub(super) fn solve_b(&self, cyclic: Option<&[[Vec<f64>; 3]]>, x: &mut [f64]) {
        match cyclic {
            Some(diags) => cyclic_solve(self.cycles.as_ref().unwrap(), diags, x),
            None => solve_f32(self.chol32.as_ref().unwrap(), x),
        }
    }

    /// Curves (L2/H1): one cyclic tridiagonal solve per component; `None` on a zero
    /// pivot (then the sparse factorizations take over).
    fn solve_cyclic<const D: usize>(&mut self, sys: &LinearSystem<'_, D>, s: &SchurMatrix) -> Option<Vec<f64>> {
        let diags = self.cyclic_diagonals(sys, &s.values);
        let mut v = s.rhs.clone();
        if !cyclic_solve_checked(self.cycles.as_ref().unwrap(), &diags, &mut v) {
            return None;
        }
        self.last = Last::Cyclic(diags);
        Some(v)
    }

    /// The three diagonals, per curve component, of a matrix with `values` on the
    /// one-ring pattern.
    pub(super) fn cyclic_diagonals<const D: usize>(
        &mut self,
        sys: &LinearSystem<'_, D>,
        values: &[f64],
    ) -> Vec<[Vec<f64>; 3]> {
        let comps = self.cycles.get_or_insert_with(|| cyclic_components(sys));
        comps
            .iter()
            .map(|comp| std::array::from_fn(|j| comp.positions.iter().map(|p| values[p[j]]).collect()))
            .collect()
    }

    /// Sparse LU of the two-ring `S` (fallback of the `H^{-1}` path).
    fn solve_lu(&mut self, s: SchurMatrix) -> Result<Vec<f64>, FlowError> {
        let tr = self.two_ring.as_mut().expect("two-ring pattern built in assemble");
        let (v, lu) = lu_solve(&mut tr.lu, &tr.symbolic, s)?;
        self.last = Last::Lu(Box::new(lu));
        Ok(v)
    }

    fn assemble_h_minus_1<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> SchurMatrix {
        let p = sys.pattern;
        let n = p.size();
        if self.two_ring.is_none() {
            let (col_ptr, row_idx) = p.squared();
            let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx.clone());
            self.two_ring = Some(TwoRing { col_ptr, row_idx, symbolic, lu: None });
        }
        let tr = self.two_ring.as_ref().unwrap();
        let m = &sys.matrices.lumped_mass;
        let mh = &sys.matrices.scalar_mass;
        let nn = &sys.matrices.lumped_normal;
        let a = &sys.matrices.stiffness;
        let (cp, ri) = (p.col_ptr(), p.row_idx());
        let mut values = vec![0.0; tr.row_idx.len()];
        let mut pos = vec![usize::MAX; n];
        for k in 0..n {
            for q in tr.col_ptr[k]..tr.col_ptr[k + 1] {
                pos[tr.row_idx[q]] = q;
            }
            values[pos[k]] += mh[k];
            for pj in cp[k]..cp[k + 1] {
                let j = ri[pj];
                // τ (g_j / m̂_j) Q_jk
                let qjk = sys.tau * sys.g[j] / mh[j] * a[pj] * nn[j].dot(&nn[k]) / (m[j] * m[k]);
                for pi in cp[j]..cp[j + 1] {
                    values[pos[ri[pi]]] += a[pi] * qjk;
                }
            }
        }
        let w: Vec<f64> = (0..n).map(|j| sys.f[j] + sys.g[j] * nn[j].dot(&sys.ax[j]) / nn[j].norm_squared()).collect();
        let mut rhs = vec![0.0; n];
        p.mul(a, &w, &mut rhs);
        rhs.iter_mut().for_each(|r| *r = -*r);
        SchurMatrix { values, rhs, symmetric: false }
    }
}

/// Sparse LU of `S` on `pattern` (symbolic part created once in `symbolic`), and the
/// solution of `S V = rhs`.
fn lu_solve(
    symbolic: &mut Option<SymbolicLu<usize>>,
    pattern: &SymbolicSparseColMat<usize>,
    s: SchurMatrix,
) -> Result<(Vec<f64>, Lu<usize, f64>), FlowError> {
    let err = |e: String| FlowError::Factorization(e);
    if symbolic.is_none() {
        *symbolic = Some(SymbolicLu::try_new(pattern.as_ref()).map_err(|e| err(format!("{e:?}")))?);
    }
    let lu = Lu::try_new_with_symbolic(symbolic.clone().unwrap(), SparseColMatRef::new(pattern.as_ref(), &s.values))
        .map_err(|e| err(format!("{e:?}")))?;
    let mut v = s.rhs;
    let n = v.len();
    lu.solve_in_place(MatMut::from_column_major_slice_mut(&mut v, n, 1));
    Ok((v, lu))
}

/// `x ← B⁻¹ x` with a single-precision factorization (a preconditioner: the outer
/// iteration works in double precision).
pub(super) fn solve_f32(chol: &SparseCholesky<f32>, x: &mut [f64]) {
    let mut y: Vec<f32> = x.iter().map(|&v| v as f32).collect();
    chol.solve_in_place(&mut y);
    x.iter_mut().zip(&y).for_each(|(xi, &yi)| *xi = yi as f64);
}

/// Cycle order and value positions of every curve component (`D = 2`).
fn cyclic_components<const D: usize>(sys: &LinearSystem<'_, D>) -> Vec<CyclicComponent> {
    let p: &Pattern<D> = sys.pattern;
    // value position of entry (row, col)
    let at = |row: usize, col: usize| {
        let r = &p.row_idx()[p.col_ptr()[col]..p.col_ptr()[col + 1]];
        p.col_ptr()[col] + r.binary_search(&row).expect("neighbour entry in pattern")
    };
    segment_cycles(p.size(), sys.mesh.elements().iter().map(|e| (e[0], e[1])))
        .into_iter()
        .map(|vertices| {
            let m = vertices.len();
            let positions = (0..m)
                .map(|k| {
                    let (prev, cur, nxt) = (vertices[(k + m - 1) % m], vertices[k], vertices[(k + 1) % m]);
                    [at(cur, prev), p.diag()[cur], at(cur, nxt)]
                })
                .collect();
            CyclicComponent { vertices, positions }
        })
        .collect()
}

pub(crate) fn assemble_l2_h1<const D: usize>(sys: &LinearSystem<'_, D>) -> SchurMatrix {
    let p = sys.pattern;
    let mx = sys.matrices;
    let n = p.size();
    let (m, mh, nn, a) = (&mx.lumped_mass, &mx.scalar_mass, &mx.lumped_normal, &mx.stiffness);
    let (mut values, beta) = match sys.product {
        ProductWeights::H1 { alpha, beta } => {
            (mx.weighted_stiffness(sys.mesh, p, alpha), beta.at_vertices(sys.mesh, mx))
        }
        _ => (vec![0.0; p.nnz()], vec![1.0; n]),
    };
    // u_i = N⃗_i / m_i, so that S_ij += τ g_i (u_i·u_j) A_ij
    let u: Vec<_> = nn.iter().zip(m).map(|(ni, mi)| ni / *mi).collect();
    let tg: Vec<f64> = sys.g.iter().map(|g| sys.tau * g).collect();
    for j in 0..n {
        values[p.diag()[j]] += beta[j] * mh[j];
        let uj = u[j];
        for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
            let i = p.row_idx()[k];
            values[k] += tg[i] * u[i].dot(&uj) * a[k];
        }
    }
    let rhs = (0..n).map(|i| -mh[i] * sys.f[i] - sys.g[i] * u[i].dot(&sys.ax[i])).collect();
    let g0 = sys.g[0];
    let symmetric = g0 >= 0.0 && sys.g.iter().all(|&g| g == g0);
    SchurMatrix { values, rhs, symmetric }
}

/// Fix the unknowns `fixed[i] = Some(v)` of the system with `values` on `pattern`
/// and right-hand side `rhs`: their columns' other entries move to the right-hand
/// side (`r_j −= S_ji v`) and are zeroed with their rows', so that the others are
/// solved with them held (a symmetric matrix stays symmetric); their own rows read
/// `S_ii V_i = S_ii v`.
fn fix_unknowns<const D: usize>(pattern: &Pattern<D>, values: &mut [f64], rhs: &mut [f64], fixed: &[Option<f64>]) {
    let (col_ptr, row_idx, diag) = (pattern.col_ptr(), pattern.row_idx(), pattern.diag());
    for k in 0..pattern.size() {
        for e in col_ptr[k]..col_ptr[k + 1] {
            let r = row_idx[e];
            if r == k {
                continue;
            }
            if let Some(v) = fixed[k] {
                if fixed[r].is_none() {
                    rhs[r] -= values[e] * v;
                }
                values[e] = 0.0;
            } else if fixed[r].is_some() {
                values[e] = 0.0;
            }
        }
    }
    for (i, v) in fixed.iter().enumerate() {
        if let Some(v) = v {
            rhs[i] = values[diag[i]] * v;
        }
    }
}
