//! The Schur solvers of the semi-implicit step: the scalar normal velocity `V`
//! from the Schur complement of the step's block system. `lumped` (default: lumped
//! masses, an explicit sparse complement, direct solves; `lumped_iterative`: its
//! conjugate-gradient and GMRES solves), `h_minus_1` (its `H⁻¹`
//! case: a two-ring complement applied matrix-free, GMRES) and `consistent` (the
//! paper's path: consistent masses, matrix-free complement, GMRES).

mod consistent;
mod h_minus_1;
mod lumped;
mod lumped_iterative;

pub use consistent::ConsistentSolver;
#[cfg(test)]
pub(crate) use lumped::assemble_l2_h1;
pub use lumped::LumpedSolver;
