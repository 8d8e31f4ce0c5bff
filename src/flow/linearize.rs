//! The linearization of a step on `Γ_n`: the P1 matrices, `A X`, the discrete
//! curvature, the problem's shape gradient and the weights of the scalar product;
//! and the per-vertex fields of a state for output.

use super::driver::Flow;
use super::problem::{curvature_and_normals, OwnField, SurfaceState};
use super::step::SolverKind;
use super::system::{LinearSystem, ProductWeights, ScalarProduct};
use super::FlowError;
use crate::fem::Weight;
use crate::geometry::Point;

/// Per-vertex fields of a state for output ([`Flow::vertex_fields`]).
#[derive(Debug, Clone, PartialEq)]
pub struct VertexFields {
    pub curvature: Vec<f64>,
    pub normal_velocity: Vec<f64>,
    pub own: Option<OwnField>,
}

/// What a step needs from `Γ_n`.
pub(super) struct Linearization<const D: usize> {
    pub ax: Vec<Point<D>>,
    pub curvature: Vec<f64>,
    /// Unit vertex normals (those of the curvature).
    pub normals: Vec<Point<D>>,
    pub grad: super::problem::ShapeGradient,
    pub product: ProductWeights,
}

impl<const D: usize> Flow<'_, D> {
    /// Assemble on `Γ_n`: `A X`, the discrete curvature, the shape gradient and the
    /// weights of the scalar product.
    pub(super) fn linearize(&mut self) -> Result<Linearization<D>, FlowError> {
        let s = &self.settings;
        self.matrices.assemble_into(&self.mesh, &self.pattern, s.solver == SolverKind::Consistent);
        let matrices = &self.matrices;
        let ax = matrices.stiffness_times_positions(&self.mesh, &self.pattern);
        let (curvature, normals) = curvature_and_normals(matrices, &ax);
        let state = SurfaceState { mesh: &self.mesh, matrices, curvature: &curvature, normals: &normals };
        let grad = self.problem.shape_gradient(&state).map_err(|e| FlowError::Problem(e.0))?;
        check_values("g", &grad.g, self.mesh.num_vertices())?;
        check_values("f", &grad.f, self.mesh.num_vertices())?;
        let product = match s.scalar_product {
            ScalarProduct::L2 => ProductWeights::L2,
            ScalarProduct::HMinus1 => ProductWeights::HMinus1,
            ScalarProduct::H1 => {
                ProductWeights::H1 { alpha: Weight::Constant(s.alpha), beta: Weight::Constant(s.beta) }
            }
            ScalarProduct::H1Newton => match self.problem.h1_weights(&state, &grad) {
                Some(w) => {
                    for (what, weight) in [("alpha", &w.alpha), ("beta", &w.beta)] {
                        weight.check(&self.mesh).map_err(|r| FlowError::Problem(format!("{what}: {r}")))?;
                    }
                    ProductWeights::H1 { alpha: w.alpha, beta: w.beta }
                }
                None => ProductWeights::H1 { alpha: Weight::Constant(s.alpha), beta: Weight::Constant(s.beta) },
            },
        };
        Ok(Linearization { ax, curvature, normals, grad, product })
    }

    /// Per-vertex fields of the current state for output: the discrete curvature
    /// `κ_i`, the normal velocity `V_i` of the next step with the last `τ` (nothing
    /// moves) and the problem's own field, if it has one.
    pub fn vertex_fields(&mut self) -> Result<VertexFields, FlowError> {
        let lin = self.linearize()?;
        let limits = self.problem.step_limits(&self.mesh);
        let sys = LinearSystem {
            mesh: &self.mesh,
            pattern: &self.pattern,
            matrices: &self.matrices,
            ax: &lin.ax,
            g: &lin.grad.g,
            f: &lin.grad.f,
            product: &lin.product,
            tau: self.tau,
            bending: self.problem.bending(),
            limits: limits.as_deref(),
        };
        let vel = self.solver.velocity(&sys)?;
        let state = SurfaceState {
            mesh: &self.mesh,
            matrices: &self.matrices,
            curvature: &lin.curvature,
            normals: &lin.normals,
        };
        let own = self.problem.own_field(&state, &lin.grad).filter(|f| f.values.len() == lin.curvature.len());
        Ok(VertexFields { curvature: lin.curvature, normal_velocity: vel.normal, own })
    }
}

fn check_values(what: &'static str, v: &[f64], n: usize) -> Result<(), FlowError> {
    if v.len() != n {
        return Err(FlowError::Problem(format!("{what} has {} values for {n} vertices", v.len())));
    }
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(FlowError::NonFiniteInput { what, index }),
        None => Ok(()),
    }
}
