//! The epitaxially stressed film (paper §1.3, §2.2.3, §4.4.2): a film
//! `Ω = {0 < x < L, 0 < y < h(x)}` on a substrate, whose free surface `Γ` is a curve
//! on the cylinder `R/LZ × R` (periodic in `x`, see
//! [`crate::geometry::Mesh::new_periodic`]), possibly with closed inclusions (voids)
//! inside the film. The bulk field solves
//!
//! ```text
//! −Δy = 0 in Ω,   ∂_ν y = 0 on Γ,   y = g on the bottom and the lateral walls,
//! ```
//!
//! and the surface moves by the `H^{-1}` gradient flow of `J = ∫_Ω |∇y|² + γ|Γ|`,
//! i.e. `V = Δ_Γ(γκ + |∇y|²)` along the outward normal `ν` of `Ω`.
//!
//! Files: `cell` (the periodic cell, its boundary data and initial films), `mesh`
//! (the film's triangulation), `field` (the bulk field, a
//! [`crate::bulk::DirichletLaplace`] solve), `run` (the problem as the flow runs it,
//! with the last field kept).
//!
//! Conventions: the gas (above the film and inside the voids) is the interior of
//! the curve mesh. The film surface therefore runs in `+x` and the voids
//! counter-clockwise, and the mesh normal points into the film, against the
//! outward normal `ν` of `Ω`. Hence the curve's normal is `n = −ν`, its curvature
//! `κ_Γ = −κ` and its velocity `V_Γ = −V`; along `n`, `G_Γ = γκ_Γ − |∇y|²` (`g = γ`,
//! `f = −|∇y|²`). Since `∂_ν y = 0` on `Γ`, `|∇y|² = (∂_s y)²`, and `∂_s y` is
//! recovered from the P1 trace of `y` on `Γ` ([`crate::fem::tangential_derivative`],
//! second order); the gradients of the triangles at `Γ` are only first-order
//! accurate there, and the exact gradient of the discrete energy (with the bulk
//! vertices held) carries an `O(1)` mesh-distortion bias that shifts the growth rate
//! of the linear instability (measured; not used). With `g` constant the field is
//! constant and the flow is plain surface diffusion of the periodic curve (no bulk
//! mesh is built).
//!
//! Optionally (an addition, `problem.bending`) `J` gains a bending energy
//! `ε/2 ∫_Γ κ²`, whose gradient `ε(−Δ_Γκ − κ³/2)` gives the groove's tip a radius of
//! about `√(ε/γ)` instead of a segment; `−εΔ_Γκ` is implicit in the step
//! ([`crate::flow::Problem::bending`]), `−εκ³/2` is added to `f`.

use crate::bulk::MeshingOptions;

mod cell;
mod field;
mod mesh;
mod run;

pub use cell::{cosine_film, polyline_film, BoundaryData, FilmCell};
pub use field::{solve_stress, StressField};
pub use mesh::film_mesh;
pub use run::FilmRun;

/// Default `flow.tau` (the film's rates are `γk⁴` for wavenumbers `k`).
pub const DEFAULT_TAU: f64 = 1e-5;
/// Default `flow.tau_min`: just after a void closes off, the corners where the
/// walls met move at up to `~10⁷` and need steps near `h⁴/γ` (measured down to
/// 2e-12 at 128 vertices) until surface diffusion has rounded them.
pub const DEFAULT_TAU_MIN: f64 = 1e-15;
/// Default `flow.conservation`: the film's area kept per step.
pub const DEFAULT_CONSERVATION: f64 = 1e-6;

/// The stressed film in its cell: the description of the problem. A run of it
/// ([`StressedFilm::start`]) keeps the last film mesh and field.
#[derive(Debug, Clone, PartialEq)]
pub struct StressedFilm {
    pub cell: FilmCell,
    /// Surface tension `γ > 0`.
    pub gamma: f64,
    pub meshing: MeshingOptions,
    /// Topology changes on: crossing candidates are reconnected (voids pinch off).
    pub merge: bool,
    /// Loops below this area are dropped when curves are reconnected.
    pub min_area: f64,
    /// Thickness `δ` of a wetting layer: every vertex of a trial step is put at
    /// `y ≥ δ` (the driver's per-step area correction then offsets it by ~1e-4).
    pub wetting_layer: Option<f64>,
    /// `ε ≥ 0` of an added bending energy `ε/2 ∫_Γ κ²` (an addition): a curvature
    /// regularization of the crack tip; see [`crate::flow::Problem::bending`].
    pub bending: f64,
}

impl StressedFilm {
    pub fn new(cell: FilmCell, gamma: f64, meshing: MeshingOptions, merge: bool, min_area: f64) -> Self {
        StressedFilm { cell, gamma, meshing, merge, min_area, wetting_layer: None, bending: 0.0 }
    }

    /// With a wetting layer of thickness `δ` (an obstacle `y ≥ δ` for the surface).
    pub fn with_wetting_layer(mut self, delta: Option<f64>) -> Self {
        self.wetting_layer = delta;
        self
    }

    /// With a bending energy `ε/2 ∫_Γ κ²` added to `J`.
    pub fn with_bending(mut self, eps: f64) -> Self {
        self.bending = eps;
        self
    }

    /// Meshing options for a curve of mean segment length `h`: 28°, triangle areas
    /// at most `h²` (the field's perturbation decays over `1/k` below the surface;
    /// with areas up to `(4h)²` the growth rate of the instability was 1.5 % lower at
    /// 128 vertices).
    pub fn meshing_for(h: f64) -> MeshingOptions {
        MeshingOptions { min_angle_deg: 28.0, max_area: h * h, min_area: 0.0025 * h * h }
    }

    /// A run of this problem, with no field yet: what the flow evaluates.
    pub fn start(&self) -> FilmRun {
        FilmRun::new(self.clone())
    }
}
