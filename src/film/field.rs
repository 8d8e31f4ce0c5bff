//! The bulk field of the film: P1 finite elements for
//! `−Δy = 0` in `Ω`, `∂_ν y = 0` on `Γ`, `y = g` on the substrate and the walls.
//!
//! One sparse Cholesky factorization (faer) per curve; the Dirichlet columns move
//! to the right-hand side.

use super::{FilmCell, FilmMesh};
use crate::bulk::{triangle_area, BulkError};
use crate::fem::element::cotangent_stiffness;
use crate::fem::Pattern;
use crate::linalg::SparseCholesky;

/// The field on one film mesh.
#[derive(Debug, Clone)]
pub struct StressField {
    /// `y` at the mesh vertices.
    pub y: Vec<f64>,
    /// `E_h = ∫_Ω |∇y_h|²`.
    pub energy: f64,
}

/// Solves for `y` and returns it with the energy `∫_Ω |∇y_h|²`.
pub fn solve_stress(mesh: &FilmMesh, cell: &FilmCell) -> Result<StressField, BulkError> {
    let n = mesh.points.len();
    let pattern = Pattern::<3>::new(n, &mesh.triangles);
    let mut k = vec![0.0; pattern.nnz()];
    for (e, t) in mesh.triangles.iter().enumerate() {
        let area = triangle_area(&mesh.points, t);
        if !(area > 0.0) {
            return Err(BulkError::Meshing(format!("film triangle {e} is degenerate (area {area:e})")));
        }
        let local = cotangent_stiffness(&t.map(|i| mesh.points[i]), area);
        let slots = &pattern.slots()[e];
        for a in 0..3 {
            for b in 0..3 {
                k[slots[a][b]] += local[(a, b)];
            }
        }
    }
    let full = k.clone();
    // y = g on the Dirichlet vertices; their columns move to the right-hand side
    let g: Vec<f64> =
        (0..n).map(|i| if mesh.dirichlet[i] { cell.boundary.value(mesh.points[i]) } else { 0.0 }).collect();
    let mut y = g.clone();
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..n {
        for s in cp[j]..cp[j + 1] {
            let i = ri[s];
            if mesh.dirichlet[j] && !mesh.dirichlet[i] {
                y[i] -= k[s] * g[j];
            }
            if mesh.dirichlet[i] || mesh.dirichlet[j] {
                k[s] = if i == j { 1.0 } else { 0.0 };
            }
        }
    }
    let sym = pattern.symbolic().as_ref();
    let mut chol = SparseCholesky::<f64>::new(sym).map_err(BulkError::Solver)?;
    chol.factorize(sym, &k).map_err(BulkError::Solver)?;
    chol.solve_in_place(&mut y);
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(BulkError::Solver(format!("the film field is not finite at bulk vertex {i}")));
    }
    let mut ky = vec![0.0; n];
    pattern.mul(&full, &y, &mut ky);
    let energy = y.iter().zip(&ky).map(|(a, b)| a * b).sum();
    Ok(StressField { y, energy })
}
