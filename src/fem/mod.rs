//! P1 finite elements on Γ: element kernels, the sparsity pattern (built once per
//! connectivity) and the global matrices of the paper's §3.6:
//!
//! * `M_ij = ∫_Γ φ_i φ_j` (consistent mass) and its lumped form `m_i = ∫_Γ φ_i`,
//! * `A_ij = ∫_Γ ∇_Γφ_i · ∇_Γφ_j` (stiffness), `A_α` with a weight α,
//! * `M_β`, `M_g` weighted masses,
//! * `N⃗_ij = ∫_Γ φ_i φ_j ν` and its lumped form `N⃗_i = ∫_Γ φ_i ν`.

mod assemble;
pub mod element;
mod pattern;
mod recovery;

pub use assemble::{Matrices, Weight};
pub use pattern::{csc_mul, Pattern};
pub use recovery::tangential_derivative;
