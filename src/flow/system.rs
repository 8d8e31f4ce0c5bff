//! The data of one semi-implicit step: the linear system (74) of the paper on `Γ_n`.

use super::limits::StepLimits;
use crate::fem::{Matrices, Pattern, Weight};
use crate::geometry::{Mesh, Point};
use serde::{Deserialize, Serialize};

/// The scalar product `b(·,·)` that turns the shape gradient `G` into a velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ScalarProduct {
    /// `∫ V W`: `V = −G`.
    L2,
    /// `∫ α ∇V·∇W + β V W` with α, β from the settings (constants).
    H1,
    /// The weighted H1 product with α, β supplied by the problem (Newton-type for
    /// segmentation, paper eq. 84 for shape design).
    H1Newton,
    /// `H^{-1}`: `V = Δ_Γ G`, the physical law of surface diffusion.
    #[serde(rename = "h_minus_1")]
    HMinus1,
}

/// The scalar product with its weights resolved for the current mesh.
#[derive(Debug, Clone, PartialEq)]
pub enum ProductWeights {
    L2,
    H1 { alpha: Weight, beta: Weight },
    HMinus1,
}

/// Everything one linear solve needs, on `Γ_n`.
///
/// Unknowns `K⃗, K, V, V⃗` (paper eq. 74):
///
/// ```text
/// M⃗ K⃗ − τ A⃗ V⃗ = A⃗ X
/// M K − N⃗ᵀ K⃗   = 0
/// B V + M_g K   = −F            (L2/H1: B = A_α + M_β, F = M f)
/// M⃗ V⃗ − N⃗ V    = 0
/// ```
///
/// and for `H^{-1}` the third row is `M V + A (g K + f) = 0`, or with a bending
/// energy `ε/2 ∫ κ²` ([`super::Problem::bending`]) `M V + A ((g + ε M⁻¹A) K + f) = 0`.
pub struct LinearSystem<'a, const D: usize> {
    pub mesh: &'a Mesh<D>,
    pub pattern: &'a Pattern<D>,
    pub matrices: &'a Matrices<D>,
    /// `A⃗ X`, `#V × D`.
    pub ax: &'a [Point<D>],
    /// `g` at the vertices (`G = g κ + f`).
    pub g: &'a [f64],
    /// `f` at the vertices.
    pub f: &'a [f64],
    pub product: &'a ProductWeights,
    pub tau: f64,
    /// `ε` of the bending energy (0: none); `H^{-1}` on curves only.
    pub bending: f64,
    /// Limits on where the step may take each vertex, kept by the solve
    /// ([`super::Problem::step_limits`]; the lumped solver with the L2 and H1
    /// products), if any.
    pub limits: Option<&'a dyn StepLimits<D>>,
}
