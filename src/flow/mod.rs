//! The gradient flow: scalar products, the semi-implicit step of the paper (eqs.
//! 62–65) solved through the Schur complement for the scalar normal velocity `V`,
//! geometric time-step control, backtracking and the driver loop.

mod acceptance;
mod active_set;
mod checkpoint;
mod contact;
mod driver;
mod error;
mod intersections;
mod limits;
mod linearize;
mod managed;
mod mesh_management;
mod problem;
mod report;
mod schur;
mod settings;
mod start;
mod step;
mod surface_manager;
pub mod surgery;
mod system;

pub use crate::linalg::{gmres, solve_cyclic_tridiagonal, GmresOutcome, SparseCholesky};
pub use driver::{Checkpoint, Flow, MeshData};
pub use error::FlowError;
pub use limits::{Confinement, StepLimits};
pub use linearize::VertexFields;
pub use mesh_management::{CurveManager, Managed, MeshManager, Surgery, WatchedCurveManager};
pub(crate) use problem::curvature_and_normals;
pub use problem::{
    shape_derivative, FlowDefaults, H1Weights, OwnField, Problem, ProblemError, ShapeGradient, SurfaceState,
};
pub use report::{Progress, Rejection, StepReport, StopReason, SurgeryEvent, SurgeryKind, SurgeryRecord};
pub use schur::{ConsistentSolver, LumpedSolver};
pub use settings::FlowSettings;
pub use step::{SemiImplicitStep, SolverKind, Velocity};
pub use surface_manager::SurfaceManager;
pub use system::{LinearSystem, ProductWeights, ScalarProduct};
