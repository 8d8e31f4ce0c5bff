//! The bulk field of the film: P1 finite elements for
//! `−Δy = 0` in `Ω`, `∂_ν y = 0` on `Γ`, `y = g` on the substrate and the walls.
//!
//! One [`DirichletLaplace`] solve per curve (the Dirichlet columns move to the
//! right-hand side).

use super::FilmCell;
use crate::bulk::{BulkError, DirichletLaplace, DomainMesh};

/// The field on one film mesh.
#[derive(Debug, Clone)]
pub struct StressField {
    /// `y` at the mesh vertices.
    pub y: Vec<f64>,
    /// `E_h = ∫_Ω |∇y_h|²`.
    pub energy: f64,
}

/// Solves for `y` and returns it with the energy `∫_Ω |∇y|²`.
pub fn solve_stress(mesh: &DomainMesh, cell: &FilmCell) -> Result<StressField, BulkError> {
    let laplace = DirichletLaplace::new(mesh, "film")?;
    let n = mesh.points.len();
    let g: Vec<f64> =
        (0..n).map(|i| if mesh.dirichlet[i] { cell.boundary.value(mesh.points[i]) } else { 0.0 }).collect();
    let y = laplace.solve(vec![0.0; n], Some(&g));
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(BulkError::Solver(format!("the film field is not finite at bulk vertex {i}")));
    }
    let energy = laplace.energy(&y);
    Ok(StressField { y, energy })
}
