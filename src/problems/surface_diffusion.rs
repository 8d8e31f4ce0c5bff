//! Surface diffusion: the `H^{-1}` gradient flow of `J = γ|Γ|`, `V = γ Δ_Γ κ`
//! (`g = γ`, `f = 0`). Enclosed area/volume is conserved and `|Γ|` decreases.

use crate::flow::{Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState};
use crate::geometry::Mesh;

/// Surface diffusion of a closed curve or surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceDiffusion {
    /// Surface tension `γ > 0`.
    pub gamma: f64,
}

impl<const D: usize> Problem<D> for SurfaceDiffusion {
    fn name(&self) -> &'static str {
        "surface_diffusion"
    }

    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        Ok(self.gamma * mesh.boundary_measure())
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        let n = state.mesh.num_vertices();
        Ok(ShapeGradient { g: vec![self.gamma; n], f: vec![0.0; n], aux: Vec::new() })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::HMinus1
    }

    fn is_physical(&self) -> bool {
        true
    }
}
