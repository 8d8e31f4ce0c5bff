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
            pattern.add_local(&mut k, e, |a, b| local[(a, b)]);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;

    /// The unit square on an `n × n` grid of squares, each cut into two
    /// counter-clockwise triangles; the boundary vertices are the Dirichlet ones.
    fn square(n: usize) -> DomainMesh {
        let id = |i: usize, j: usize| i + (n + 1) * j;
        let points = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| Point::<2>::new(i as f64 / n as f64, j as f64 / n as f64)))
            .collect();
        let triangles = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
                })
            })
            .collect();
        let dirichlet = (0..=n).flat_map(|j| (0..=n).map(move |i| i == 0 || j == 0 || i == n || j == n)).collect();
        DomainMesh { points, triangles, dirichlet, curve_vertices: 0 }
    }

    /// P1 elements reproduce a linear harmonic function from its boundary values,
    /// and `uᵀ K u` is its Dirichlet energy `(b² + c²)·|Ω|`.
    #[test]
    fn linear_data_are_reproduced_with_their_energy() {
        let mesh = square(6);
        let laplace = DirichletLaplace::new(&mesh, "test").unwrap();
        let (a, b, c) = (0.3, -1.2, 0.7);
        let g: Vec<f64> = mesh.points.iter().map(|p| a + b * p.x + c * p.y).collect();
        let u = laplace.solve(vec![0.0; g.len()], Some(&g));
        let err = u.iter().zip(&g).map(|(u, g)| (u - g).abs()).fold(0.0, f64::max);
        assert!(err < 1e-12, "{err:e}");
        assert!((laplace.energy(&u) - (b * b + c * c)).abs() < 1e-12);
    }

    /// A degenerate triangle is an error naming the mesh and the triangle.
    #[test]
    fn a_degenerate_triangle_is_named() {
        let mut mesh = square(2);
        mesh.triangles[3] = [mesh.triangles[3][0], mesh.triangles[3][0], mesh.triangles[3][2]];
        let e = DirichletLaplace::new(&mesh, "film").err().unwrap();
        assert!(e.to_string().contains("film triangle 3 is degenerate"), "{e}");
    }
}
