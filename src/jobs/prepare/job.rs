//! A prepared job: the problem (one variant per application) and everything a run
//! needs, validated.

use super::SegmentationSetup;
use crate::flow::{CurveManager, FlowError, FlowSettings, Problem, SurfaceManager};
use crate::geometry::AnyMesh;
use crate::imaging::{EdgeField, Grid};
use crate::jobs::necks::NeckSplit;
use crate::jobs::spec::JobSpec;
use crate::problems::{ChanVese, CurvatureFlow, Segmentation, ShapeDesign, StressedFilm, SurfaceDiffusion};
use std::sync::Arc;

/// A concrete problem (works in 2D and 3D).
#[derive(Debug, Clone, PartialEq)]
pub enum ProblemKind {
    CurvatureFlow(CurvatureFlow),
    SurfaceDiffusion(SurfaceDiffusion),
    Segmentation(Segmentation),
    /// Region-based segmentation (Chan–Vese), possibly with the geodesic term.
    ChanVese(ChanVese),
    ShapeDesign(ShapeDesign),
    StressedFilm(StressedFilm),
}

impl PreparedJob {
    /// The problem of stage `stage` (see [`Checkpoint::stage`](crate::flow::Checkpoint)).
    pub fn stage_problem(&self, stage: usize) -> &ProblemKind {
        match (stage, &self.second_stage) {
            (1.., Some(p)) => p,
            _ => &self.problem,
        }
    }
}

impl ProblemKind {
    /// The problem as a flow on curves runs it: a run with its own state.
    pub fn curve_problem(&self) -> Box<dyn Problem<2>> {
        match self {
            ProblemKind::CurvatureFlow(p) => Box::new(*p),
            ProblemKind::SurfaceDiffusion(p) => Box::new(*p),
            ProblemKind::Segmentation(p) => Box::new(p.clone()),
            ProblemKind::ChanVese(p) => Box::new(p.start()),
            ProblemKind::ShapeDesign(p) => Box::new(p.start()),
            ProblemKind::StressedFilm(p) => Box::new(p.start()),
        }
    }

    /// The problem as a flow on surfaces runs it; shape design and the stressed
    /// film are problems on curves only (the job builder never pairs them with a
    /// surface).
    pub fn surface_problem(&self) -> Result<Box<dyn Problem<3>>, FlowError> {
        match self {
            ProblemKind::CurvatureFlow(p) => Ok(Box::new(*p)),
            ProblemKind::SurfaceDiffusion(p) => Ok(Box::new(*p)),
            ProblemKind::Segmentation(p) => Ok(Box::new(p.clone())),
            ProblemKind::ChanVese(p) => Ok(Box::new(p.start())),
            ProblemKind::ShapeDesign(_) => Err(FlowError::Problem("shape design needs a curve (2D)".into())),
            ProblemKind::StressedFilm(_) => Err(FlowError::Problem("the stressed film needs a curve (2D)".into())),
        }
    }
}

/// A validated job, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedJob {
    pub spec: JobSpec,
    pub mesh: AnyMesh,
    pub problem: ProblemKind,
    /// (Addition) the problem of a second stage, run from where the first one
    /// converged (segmentation with `lambda_final`).
    pub second_stage: Option<ProblemKind>,
    pub settings: FlowSettings,
    pub checkpoint_every: usize,
    /// Mesh management of curves, resolved from the spec and the initial mesh
    /// (`None` for surfaces, or when every switch is off).
    pub curve_manager: Option<CurveManager>,
    /// Mesh management of surfaces, likewise.
    pub surface_manager: Option<SurfaceManager>,
    /// (Addition) the surface's management while it converges on coarse edges
    /// first (`mesh.coarse_start`), before [`PreparedJob::surface_manager`]'s.
    pub coarse_manager: Option<SurfaceManager>,
    /// The decoded input image of a segmentation job (for masks and overlays).
    pub image: Option<Arc<Grid>>,
    /// (Addition) the edge field the results are refined onto: segmentation with
    /// `problem.edge_refinement` (default on); see [`result_state`](crate::jobs::result_state).
    pub edges: Option<Arc<EdgeField>>,
    /// (Addition) the settings of a segmentation, automatic or given.
    pub segmentation: Option<SegmentationSetup>,
    /// (Addition) the split of touching objects at the necks of converged
    /// contours (2D Chan–Vese segmentation with `problem.split_touching`).
    pub neck_split: Option<NeckSplit>,
}
