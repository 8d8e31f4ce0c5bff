//! One semi-implicit step: the normal velocity `V` and the vector velocity `V⃗` on
//! `Γ_n` for a given `τ`, through either Schur path.

use super::active_set::solve_limited;
use super::system::{LinearSystem, ProductWeights};
use super::{ConsistentSolver, FlowError, LumpedSolver};
use crate::geometry::Point;
use serde::{Deserialize, Serialize};

/// Which Schur path solves the step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// Lumped masses, explicit sparse Schur complement, faer direct solve (default;
    /// surfaces with the L2 product by conjugate gradients first).
    #[default]
    Lumped,
    /// Consistent masses, matrix-free Schur complement, GMRES (the paper's path).
    Consistent,
}

/// Scalar normal velocity `V` and vector velocity `V⃗` at the vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Velocity<const D: usize> {
    pub normal: Vec<f64>,
    pub vector: Vec<Point<D>>,
}

/// The stateful step solver (keeps symbolic factorizations between steps).
pub struct SemiImplicitStep {
    kind: SolverKind,
    lumped: LumpedSolver,
    consistent: ConsistentSolver,
}

impl SemiImplicitStep {
    pub fn new(kind: SolverKind) -> Self {
        SemiImplicitStep { kind, lumped: LumpedSolver::iterative(), consistent: ConsistentSolver::new() }
    }

    pub fn kind(&self) -> SolverKind {
        self.kind
    }

    /// Forget symbolic factorizations (call when the connectivity changes).
    pub fn reset(&mut self) {
        self.lumped.reset();
        self.consistent.reset();
    }

    /// Solve the linearized system (74) for `V` and `V⃗`.
    pub fn velocity<const D: usize>(&mut self, sys: &LinearSystem<'_, D>) -> Result<Velocity<D>, FlowError> {
        let (normal, vector) = match self.kind {
            SolverKind::Lumped => {
                let v = match sys.limits {
                    Some(limits) if !matches!(sys.product, ProductWeights::HMinus1) => {
                        solve_limited(&mut self.lumped, sys, limits)?
                    }
                    _ => self.lumped.solve(sys)?,
                };
                let m = &sys.matrices.lumped_mass;
                let nn = &sys.matrices.lumped_normal;
                let vec = (0..v.len()).map(|i| nn[i] * (v[i] / m[i])).collect();
                (v, vec)
            }
            SolverKind::Consistent => self.consistent.solve(sys)?,
        };
        if let Some(vertex) = normal.iter().position(|x| !x.is_finite()) {
            return Err(FlowError::NonFiniteVelocity { vertex });
        }
        Ok(Velocity { normal, vector })
    }
}
