//! Optimal shape design for an elliptic PDE (paper §1.2, §2.2.2, §4.3):
//!
//! ```text
//! J(Ω) = ½ ∫_D (y − z_g)² + γ|Γ|,    −Δy = 0 in Ω, y = 0 on Σ, ∂_ν y = 1 on Γ,
//! ```
//!
//! with the adjoint `−Δp = χ_D (y − z_g)`, `p = 0` on `Σ`, `∂_ν p = 0` on `Γ`.
//!
//! Signs: the paper writes `G = −∇_Γ y·∇_Γ p + κ(p + γ)` for velocities along the
//! outward normal `ν` of `Ω`, which on `Γ` points into the hole. Our curves carry their
//! own outward normal `n = −ν` (away from the hole) and their curvature `κ_Γ = −κ`,
//! and the velocity is `V_Γ = −V`; hence along `n`
//!
//! ```text
//! G_Γ = (p + γ) κ_Γ + ∇_Γ y·∇_Γ p      (g = p + γ, f = ∇_Γ y·∇_Γ p).
//! ```
//!
//! The tangential derivatives are the lumped L2 projections of the elementwise
//! difference quotients of the P1 traces onto P1 (length-weighted averages at the
//! vertices). The weighted H1 product of the paper (eq. 84) has `β = 1` and `α`
//! per edge from `g` at its ends (`p` in the paper, where `γ = 0`): 1 where `g` takes
//! negative values (there the L2 flow is backward parabolic), `h_e²` where `g` is
//! well above its oscillation, and a linear blend in between.

use crate::bulk::{DesignDomain, MeshingOptions};
use crate::geometry::Point;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

mod run;
mod target;

pub use run::DesignRun;
pub use target::Target;

/// Default `flow.tau`: the cap of the adaptive step.
pub const DEFAULT_TAU: f64 = 10.0;

/// How the shape gradient `G` is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GradientKind {
    /// The exact gradient of the discrete `J_h`, its normal
    /// part per vertex: `G_i = ∂J_h/∂X_i · N⃗_i / |N⃗_i|²`.
    #[default]
    Discrete,
    /// The paper's formula `G = (p + γ)κ + ∇_Γy·∇_Γp` with recovered tangential
    /// derivatives.
    Continuous,
}

/// State, adjoint and energy of one curve.
#[derive(Debug, Clone)]
pub struct DesignSolution {
    /// `y` and `p` at the curve's vertices.
    pub y: Vec<f64>,
    pub p: Vec<f64>,
    /// `½ ∫_D (y − z_g)²`.
    pub misfit: f64,
    /// `J = misfit + γ|Γ|`.
    pub energy: f64,
    /// `∂J_h/∂X_i` at the curve's vertices (see [`curve_sensitivity`]).
    pub sensitivity: Vec<Point<2>>,
}

/// The shape-design functional on a fixed domain: the description of the problem.
/// A run of it ([`ShapeDesign::start`]) keeps the bulk meshes that follow the curve.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeDesign {
    pub domain: Arc<DesignDomain>,
    pub target: Target,
    /// Weight `γ ≥ 0` of the length of `Γ`.
    pub gamma: f64,
    /// Topology changes on: a candidate whose curves cross is evaluated as the union
    /// it becomes (the mesh manager merges it after the step). Off: crossing is
    /// inadmissible.
    pub merge: bool,
    /// Loops below this area are dropped when crossing curves are merged.
    pub min_area: f64,
    pub meshing: MeshingOptions,
    /// How `G` is computed (default: the exact gradient of the discrete functional).
    pub gradient: GradientKind,
}

impl ShapeDesign {
    pub fn new(
        domain: Arc<DesignDomain>,
        target: Target,
        gamma: f64,
        merge: bool,
        min_area: f64,
        meshing: MeshingOptions,
    ) -> Self {
        ShapeDesign { domain, target, gamma, merge, min_area, meshing, gradient: GradientKind::Discrete }
    }

    /// A run of this problem, with no bulk mesh yet: what the flow evaluates.
    pub fn start(&self) -> DesignRun {
        DesignRun::new(self.clone())
    }
}

/// `α_e` of paper eq. (84) from the values of `g` at the ends of edge `e` and `h_e²`.
pub fn alpha_84(g0: f64, g1: f64, h2: f64) -> f64 {
    let (lo, hi) = (g0.min(g1), g0.max(g1));
    if lo < 0.0 {
        return 1.0;
    }
    let (mean, osc) = (0.5 * (hi + lo), hi - lo);
    if mean <= osc {
        // osc > 0 here (mean ≥ lo ≥ 0 and mean ≤ osc, with mean = osc = 0 only if g ≡ 0)
        if osc > 0.0 {
            1.0 - mean * (1.0 - h2) / osc
        } else {
            1.0
        }
    } else {
        h2
    }
}

#[cfg(test)]
mod tests;
