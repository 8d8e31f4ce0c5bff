//! Curvature flow: `J = γ|Γ| + λ|Ω|`, `G = γκ + λ` (`g = γ`, `f = λ`).
//!
//! With the L2 product and `λ = 0` this is curve-shortening / mean curvature flow,
//! with the exact solutions `R(t) = √(R0² − 2t)` (circle) and `√(R0² − 4t)` (sphere).

use crate::flow::{Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState};
use crate::geometry::Mesh;

/// Perimeter/area (2D) or area/volume (3D) functional.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureFlow {
    /// Weight `γ > 0` of the perimeter / surface area.
    pub gamma: f64,
    /// Weight `λ` of the enclosed area / volume.
    pub lambda: f64,
}

impl<const D: usize> Problem<D> for CurvatureFlow {
    fn name(&self) -> &'static str {
        "curvature_flow"
    }

    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        Ok(self.gamma * mesh.boundary_measure() + self.lambda * mesh.enclosed_measure())
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        let n = state.mesh.num_vertices();
        Ok(ShapeGradient { g: vec![self.gamma; n], f: vec![self.lambda; n], aux: Vec::new() })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::L2
    }
}
