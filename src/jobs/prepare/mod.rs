//! From a parsed spec to a runnable job (`prepare`): value checks naming their
//! field, the initial mesh, the problem and the flow and mesh settings. One module
//! per problem that needs more than its fields (`design`, `film`, `segment` with
//! `image_shapes`), plus the explicit initial shapes, the flow settings and the
//! mesh settings.

mod background;
mod checks;
mod design;
mod film;
mod flow_settings;
mod image_shapes;
mod inputs;
mod job;
mod mesh_settings;
mod preprocess;
mod segment;
mod shapes;

pub use job::{PreparedJob, ProblemKind};
pub use segment::{default_min_size, default_mu, default_mu_in, SegmentationSetup};

use crate::flow::{CurveManager, ScalarProduct, Surgery};
use crate::geometry::AnyMesh;
use crate::jobs::spec::{
    ColorBy, CurvatureFlowSpec, FilmPolylineShape, FilmShape, InitialSpec, InscribedShape, JobSpec, ProblemSpec,
    SeedsShape, SpecError, SurfaceDiffusionSpec, ThresholdShape,
};
use crate::problems::{CurvatureFlow, StressedFilm, SurfaceDiffusion};
use checks::{finite, positive};
use flow_settings::flow_settings;
use mesh_settings::{coarse_manager, curve_manager, surface_manager};
use shapes::build_initial;
use std::collections::HashMap;
use std::sync::Arc;

/// Validate `spec` and build the job. `inputs` maps `NAME` of `"input:NAME"` to the
/// file's bytes.
pub fn prepare(spec: JobSpec, inputs: &HashMap<String, Vec<u8>>) -> Result<PreparedJob, SpecError> {
    spec.limits.resolve()?;
    let mut image = None;
    let mut second_stage = None;
    let mut edges = None;
    let mut image_mesh = None;
    let mut segmentation = None;
    let mut neck_split = None;
    // the problems that need the initial curve are built once it is there
    let early = match &spec.problem {
        ProblemSpec::CurvatureFlow(CurvatureFlowSpec { gamma, lambda }) => {
            positive("problem.gamma", *gamma)?;
            finite("problem.lambda", &[*lambda])
                .map_err(|_| SpecError::new("problem.lambda", "must be a finite number"))?;
            Some(ProblemKind::CurvatureFlow(CurvatureFlow { gamma: *gamma, lambda: *lambda }))
        }
        ProblemSpec::SurfaceDiffusion(SurfaceDiffusionSpec { gamma }) => {
            positive("problem.gamma", *gamma)?;
            Some(ProblemKind::SurfaceDiffusion(SurfaceDiffusion { gamma: *gamma }))
        }
        ProblemSpec::Segmentation(seg) => {
            let prepared = segment::prepare_segmentation(seg, spec.initial.as_ref(), inputs)?;
            image = Some(Arc::new(prepared.grid));
            (second_stage, edges, image_mesh, segmentation, neck_split) =
                (prepared.second_stage, prepared.edges, prepared.mesh, Some(prepared.setup), prepared.neck_split);
            Some(prepared.problem)
        }
        ProblemSpec::ShapeDesign(_) | ProblemSpec::StressedFilm(_) => None,
    };
    let film_cell = match &spec.problem {
        ProblemSpec::StressedFilm(fs) => Some(film::film_cell(fs)?),
        _ => None,
    };
    let mesh = match (&spec.initial, &image, &film_cell) {
        _ if image_mesh.is_some() => image_mesh.take().expect("an image's initial shape"),
        (
            Some(
                InitialSpec::Threshold(ThresholdShape {})
                | InitialSpec::Seeds(SeedsShape { .. })
                | InitialSpec::Inscribed(InscribedShape {}),
            ),
            _,
            _,
        ) => {
            return Err(SpecError::new(
                "initial.shape",
                "this shape comes from an image: it needs problem.type `segmentation`",
            ));
        }
        (initial, _, Some(cell)) => AnyMesh::Curve(film::initial_film(cell, initial.as_ref())?),
        (Some(InitialSpec::Film(FilmShape { .. }) | InitialSpec::FilmPolyline(FilmPolylineShape { .. })), _, None) => {
            return Err(SpecError::new("initial.shape", "film shapes are for problem.type `stressed_film`"));
        }
        (Some(initial), _, None) => build_initial("initial", initial, inputs)?,
        (None, _, None) => return Err(SpecError::new("initial", "missing field `initial`")),
    };
    if let Some(grid) = &image {
        if grid.dimension != mesh.dimension() {
            return Err(SpecError::new(
                "initial",
                format!(
                    "a {}D image needs a {}",
                    grid.dimension,
                    if grid.dimension == 2 { "curve" } else { "surface" }
                ),
            ));
        }
    }
    // a surface traced from the image (not a shape the spec gives) keeps its
    // edges near the voxel size
    let traced = matches!(spec.initial, None | Some(InitialSpec::Threshold(ThresholdShape {})));
    let traced_voxel =
        image.as_ref().filter(|_| traced && matches!(mesh, AnyMesh::Surface(_))).map(|g| 1.0 / g.scale());
    let (mut curve_manager, mut surface_manager) = match &mesh {
        AnyMesh::Curve(c) => (curve_manager(&spec.mesh, c)?, None),
        AnyMesh::Surface(m) => {
            let segmentation = matches!(spec.problem, ProblemSpec::Segmentation(_));
            let pinch_off = spec.mesh.pinch_off.unwrap_or(!segmentation);
            // `pinch_off: false` with topology changes: necks are cut, and (but in
            // segmentation, whose objects are kept apart) surfaces in contact merge
            let surgery =
                (!pinch_off && spec.mesh.topology_changes).then_some(Surgery { merge: !segmentation, conserve: false });
            (None, surface_manager(&spec.mesh, m, pinch_off, surgery, traced_voxel)?)
        }
    };
    if let (Some(m), Some(setup), Some(grid), None) =
        (curve_manager.as_mut(), &segmentation, &image, spec.mesh.min_area)
    {
        // a contour that shrinks below a quarter of the smallest object kept at the
        // start is gone
        let l = grid.scale();
        m.params.min_area = m.params.min_area.max(0.25 * setup.min_size / (l * l));
    }
    let problem = match (&spec.problem, &mesh) {
        (ProblemSpec::ShapeDesign(sd), AnyMesh::Curve(c)) => {
            let min_area = curve_manager.map_or(CurveManager::defaults_for(c).min_area, |m| m.params.min_area);
            ProblemKind::ShapeDesign(design::shape_design(sd, c, spec.mesh.topology_changes, min_area)?)
        }
        (ProblemSpec::StressedFilm(fs), AnyMesh::Curve(c)) => {
            // voids below (1.5 h)² are dropped: slivers cut off at a crack tip have
            // a handful of vertices and move too fast to be followed
            let h = c.boundary_measure() / c.num_elements() as f64;
            let min_area = match spec.mesh.min_area {
                Some(a) => positive("mesh.min_area", a)?,
                None => 2.25 * h * h,
            };
            if let Some(m) = curve_manager.as_mut() {
                m.params.min_area = min_area;
            }
            let cell = film_cell.expect("film cell");
            let meshing = StressedFilm::meshing_for(h);
            let wetting = match fs.wetting_layer {
                Some(d) => {
                    let d = positive("problem.wetting_layer", d)?;
                    if c.positions().iter().any(|p| p.y <= d) {
                        return Err(SpecError::new(
                            "problem.wetting_layer",
                            "the initial surface must lie above the wetting layer",
                        ));
                    }
                    Some(d)
                }
                None => None,
            };
            if !(fs.bending.is_finite() && fs.bending >= 0.0) {
                return Err(SpecError::new(
                    "problem.bending",
                    format!("must be a nonnegative number, got {}", fs.bending),
                ));
            }
            ProblemKind::StressedFilm(
                StressedFilm::new(cell, fs.gamma, meshing, spec.mesh.topology_changes, min_area)
                    .with_wetting_layer(wetting)
                    .with_bending(fs.bending),
            )
        }
        (ProblemSpec::ShapeDesign(_), AnyMesh::Surface(_)) => {
            return Err(SpecError::new("initial", "shape design is two-dimensional: it needs a curve"));
        }
        (ProblemSpec::StressedFilm(_), AnyMesh::Surface(_)) => {
            return Err(SpecError::new("initial", "the stressed film is two-dimensional: it needs a curve"));
        }
        _ => early.expect("every other problem is built from its fields"),
    };
    let settings = flow_settings(&spec.flow, &problem)?;
    if let Some(s) = surface_manager.as_mut().and_then(|m| m.surgery.as_mut()) {
        s.conserve = settings.scalar_product == ScalarProduct::HMinus1 || settings.conservation.is_some();
    }
    let coarse_manager = coarse_manager(&spec.mesh, surface_manager.as_ref(), traced_voxel, &settings);
    if let Some(m) = curve_manager.as_mut() {
        m.params.keep_area = settings.scalar_product == ScalarProduct::HMinus1;
        // a pocket of Ω closed off by Γ would have no Dirichlet boundary
        m.params.fill_pockets = matches!(problem, ProblemKind::ShapeDesign(_));
        m.params.keep_apart = matches!(&problem, ProblemKind::ChanVese(p) if p.separate);
    }
    let has_own_field = matches!(spec.problem, ProblemSpec::Segmentation(_) | ProblemSpec::StressedFilm(_));
    if spec.output.color_by == ColorBy::ProblemField && !has_own_field {
        let kind = serde_json::to_value(&spec.problem).map(|v| v["type"].to_string()).unwrap_or_default();
        return Err(SpecError::new(
            "output.color_by",
            format!(
                "the problem {} has no field of its own to colour (segmentation and stressed_film have); \
                 use curvature or normal_velocity",
                kind
            ),
        ));
    }
    let checkpoint_every = match spec.output.checkpoint_every {
        0 => return Err(SpecError::new("output.checkpoint_every", "must be at least 1, got 0")),
        n => n,
    };
    Ok(PreparedJob {
        spec,
        mesh,
        problem,
        second_stage,
        settings,
        checkpoint_every,
        curve_manager,
        surface_manager,
        coarse_manager,
        image,
        edges,
        segmentation,
        neck_split,
    })
}
