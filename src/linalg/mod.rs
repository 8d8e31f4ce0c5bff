//! The general linear-algebra solvers the layers above share: a stateful sparse
//! Cholesky factorization (symbolic once per pattern, over faer), the `O(n)` solve
//! of cyclic tridiagonal systems (closed curves), restarted GMRES with right
//! preconditioning, and conjugate gradients with a diagonal preconditioner.
//! Nothing here knows about meshes or flows.

mod cholesky;
mod cyclic;
mod gmres;
mod pcg;

pub use cholesky::SparseCholesky;
pub use cyclic::solve_cyclic_tridiagonal;
pub(crate) use cyclic::{cyclic_solve, cyclic_solve_checked, CyclicComponent};
pub use gmres::{gmres, GmresOutcome};
pub use pcg::pcg;
