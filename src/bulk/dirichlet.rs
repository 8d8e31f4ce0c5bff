//! The Laplacian on a triangulation with Dirichlet vertices, factorized once: the P1
//! stiffness matrix `K_ij = ∫ ∇φ_i·∇φ_j` with the rows and columns of the Dirichlet
//! vertices replaced by the identity (one sparse Cholesky factorization, faer), and
//! solves of `K u = b` at the free vertices with `u = g` at the Dirichlet ones (their
//! columns moved to the right-hand side). Shape design's state and adjoint and the
//! stressed film's field are such solves.

use super::mesh::{triangle_area, DomainMesh};
use super::BulkError;
use crate::fem::element::cotangent_stiffness;
use crate::fem::Pattern;
use crate::linalg::SparseCholesky;

/// `K` of one triangulation, with its Dirichlet vertices, factorized.
pub struct DirichletLaplace {
    pattern: Pattern<3>,
    /// `K` before the Dirichlet rows and columns were replaced.
    stiffness: Vec<f64>,
    dirichlet: Vec<bool>,
    factor: SparseCholesky<f64>,
}

impl DirichletLaplace {
    /// Assembles and factorizes `K` on `mesh`, with its Dirichlet vertices. `what`
    /// names the mesh in the error of a degenerate triangle (`bulk`, `film`).
    pub fn new(mesh: &DomainMesh, what: &str) -> Result<Self, BulkError> {
        let DomainMesh { points, triangles, dirichlet, .. } = mesh;
        let n = points.len();
        let pattern = Pattern::<3>::new(n, triangles);
        let mut k = vec![0.0; pattern.nnz()];
        for (e, t) in triangles.iter().enumerate() {
            let area = triangle_area(points, t);
            if area.is_nan() || area <= 0.0 {
                return Err(BulkError::Meshing(format!("{what} triangle {e} is degenerate (area {area:e})")));
            }
            let local = cotangent_stiffness(&t.map(|i| points[i]), area);
            let slots = &pattern.slots()[e];
            for a in 0..3 {
                for b in 0..3 {
                    k[slots[a][b]] += local[(a, b)];
                }
            }
        }
        let stiffness = k.clone();
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        for j in 0..n {
            for s in cp[j]..cp[j + 1] {
                let i = ri[s];
                if dirichlet[i] || dirichlet[j] {
                    k[s] = if i == j { 1.0 } else { 0.0 };
                }
            }
        }
        let sym = pattern.symbolic().as_ref();
        let mut factor = SparseCholesky::<f64>::new(sym).map_err(BulkError::Solver)?;
        factor.factorize(sym, &k).map_err(BulkError::Solver)?;
        Ok(DirichletLaplace { pattern, stiffness, dirichlet: dirichlet.to_vec(), factor })
    }

    /// `u` with `(K u)_i = b_i` at the free vertices and `u_i = g_i` at the
    /// Dirichlet ones (`b` is read at the free vertices only, `g` at the Dirichlet
    /// ones only; `g = None` is zero there).
    pub fn solve(&self, mut b: Vec<f64>, g: Option<&[f64]>) -> Vec<f64> {
        let n = self.dirichlet.len();
        let d = &self.dirichlet;
        for i in (0..n).filter(|&i| d[i]) {
            b[i] = g.map_or(0.0, |g| g[i]);
        }
        if let Some(g) = g {
            let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
            for j in (0..n).filter(|&j| d[j]) {
                for s in cp[j]..cp[j + 1] {
                    let i = ri[s];
                    if !d[i] {
                        b[i] -= self.stiffness[s] * g[j];
                    }
                }
            }
        }
        self.factor.solve_in_place(&mut b);
        b
    }

    /// `uᵀ K u = ∫ |∇u_h|²`.
    pub fn energy(&self, u: &[f64]) -> f64 {
        let mut ku = vec![0.0; u.len()];
        self.pattern.mul(&self.stiffness, u, &mut ku);
        u.iter().zip(&ku).map(|(a, b)| a * b).sum()
    }
}
