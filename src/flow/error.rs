//! Errors of the flow: numeric failures end a run.

/// A numeric failure of the flow. A run that hits one ends as failed; the state
/// before the failing step is still available (and checkpointed by the caller).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlowError {
    #[error("the problem returned a non-finite {what} at index {index}")]
    NonFiniteInput { what: &'static str, index: usize },
    #[error("sparse factorization of the Schur complement failed: {0}")]
    Factorization(String),
    #[error("iterative Schur solve did not converge: residual {residual:e} after {iterations} iterations")]
    NoConvergence { residual: f64, iterations: usize },
    #[error("the velocity is not finite at vertex {vertex}")]
    NonFiniteVelocity { vertex: usize },
    #[error("the energy is not finite ({value}) at iteration {iteration}")]
    NonFiniteEnergy { value: f64, iteration: usize },
    #[error("problem error: {0}")]
    Problem(String),
    #[error("invalid settings: {field}: {reason}")]
    Settings { field: &'static str, reason: String },
    #[error("checkpoint does not fit: {0}")]
    Checkpoint(String),
    /// The mesh management could not repair the shape a step left (a fold of a
    /// curve it could not resolve); the driver takes such a step back and tries a
    /// shorter one.
    #[error("mesh management: {0}")]
    Management(String),
    #[error(
        "mesh management grew the mesh to {vertices} vertices, more than the {limit} this run may have \
         (the steps are unstable at these settings: see flow.backtracking and flow.step_control)"
    )]
    MeshGrowth { vertices: usize, limit: usize },
}
