//! The gradient flow: scalar products, the semi-implicit step of the paper (eqs.
//! 62–65) solved through the Schur complement for the scalar normal velocity `V`,
//! geometric time-step control, backtracking and the driver loop.

mod checkpoint;
mod consistent;
mod cyclic;
mod driver;
mod error;
mod gmres;
mod h_minus_1;
mod lumped;
mod mesh_management;
mod problem;
mod step;
mod system;

pub use crate::fem::SparseCholesky;
pub use consistent::ConsistentSolver;
pub use cyclic::solve_cyclic_tridiagonal;
pub use driver::{Checkpoint, Flow, FlowSettings, MeshData, Progress, Rejection, StepReport, StopReason};
pub use error::FlowError;
pub use gmres::{gmres, GmresOutcome};
pub use lumped::LumpedSolver;
pub use mesh_management::{CurveManager, Managed, MeshManager, SurfaceManager, WatchedCurveManager};
pub(crate) use problem::curvature_and_normals;
pub use problem::{shape_derivative, H1Weights, Problem, ProblemError, ShapeGradient, SurfaceState};
pub use step::{SemiImplicitStep, SolverKind, Velocity};
pub use system::{LinearSystem, ProductWeights, ScalarProduct};
