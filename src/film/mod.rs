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
//! and the surface moves by the `H^{-1}` gradient flow of `J = ∫_Ω |∇y|² + γ|Γ|`.
//!
//! Conventions: the gas (above the film and inside the voids) is the interior of
//! the curve mesh. The film surface therefore runs in `+x` and the voids
//! counter-clockwise, and the mesh normal points into the film, against the
//! outward normal `ν` of `Ω`.

mod cell;
mod field;
mod mesh;

pub use cell::{cosine_film, polyline_film, BoundaryData, FilmCell};
pub use field::{solve_stress, StressField};
pub use mesh::FilmMesh;
