//! The applications, one module each, behind the [`crate::flow::Problem`] trait.

mod chan_vese;
mod curvature_flow;
mod edge_refinement;
mod segmentation;
mod shape_design;
mod stressed_film;
mod surface_diffusion;

pub use chan_vese::{ChanVese, ChanVeseRun, Territories};
pub use curvature_flow::CurvatureFlow;
pub use edge_refinement::{blur_variance, refine_to_edges, EdgeRefinement};
pub use segmentation::Segmentation;
pub use shape_design::{alpha_84, DesignRun, DesignSolution, GradientKind, ShapeDesign, Target};
pub use stressed_film::{
    cosine_film, film_mesh, polyline_film, solve_stress, BoundaryData, FilmCell, FilmRun, StressField, StressedFilm,
};
pub use surface_diffusion::SurfaceDiffusion;

/// The error of an image problem run on a mesh of the other dimension.
fn check_image_dimension<const D: usize>(image_dimension: usize) -> Result<(), crate::flow::ProblemError> {
    if image_dimension != D {
        return Err(crate::flow::ProblemError(format!(
            "a {image_dimension}D image cannot segment a {}",
            if D == 2 { "curve" } else { "surface" }
        )));
    }
    Ok(())
}
