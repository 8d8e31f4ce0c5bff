//! From a parsed spec to a runnable job: value checks (each naming its field), the
//! initial mesh, the problem and the flow settings.

use super::segment::SegmentationSetup;
use super::spec::{ImageSource, InitialSpec, JobSpec, ProblemSpec, SpecError};
use crate::flow::{CurveManager, FlowSettings, Problem, ScalarProduct, SolverKind, SurfaceManager};
use crate::formats::read_mesh_file;
use crate::geometry::{self, CurveMesh, Mesh, MeshError, Point, SurfaceMesh};
use crate::imaging::{
    decode_image, decode_nifti, decode_slices, decode_tiff_stack, decode_volume, is_nifti, is_tiff, tiff_pages,
    EdgeField, Grid, ImageLimits,
};
use crate::problems::{ChanVese, CurvatureFlow, Segmentation, ShapeDesign, StressedFilm, SurfaceDiffusion};
use std::collections::HashMap;
use std::sync::Arc;

pub use crate::limits::MAX_VERTICES;

pub use crate::geometry::AnyMesh;

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
    pub fn as_dyn<const D: usize>(&self) -> &dyn Problem<D> {
        match self {
            ProblemKind::CurvatureFlow(p) => p,
            ProblemKind::SurfaceDiffusion(p) => p,
            ProblemKind::Segmentation(p) => p,
            ProblemKind::ChanVese(p) => p,
            ProblemKind::ShapeDesign(p) => p,
            ProblemKind::StressedFilm(p) => p,
        }
    }
    fn physical(&self) -> bool {
        matches!(self, ProblemKind::SurfaceDiffusion(_) | ProblemKind::StressedFilm(_))
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
    /// The decoded input image of a segmentation job (for masks and overlays).
    pub image: Option<Arc<Grid>>,
    /// (Addition) the edge field the results are refined onto: segmentation with
    /// `problem.edge_refinement` (default on); see [`result_state`](super::result_state).
    pub edges: Option<Arc<EdgeField>>,
    /// (Addition) the settings of a segmentation, automatic or given.
    pub segmentation: Option<SegmentationSetup>,
}

pub(super) fn positive(field: &str, v: f64) -> Result<f64, SpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SpecError::new(field, format!("must be a positive number, got {v}")))
    }
}

pub(super) fn finite(field: &str, v: &[f64]) -> Result<(), SpecError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(SpecError::new(format!("{field}[{i}]"), "must be a finite number")),
        None => Ok(()),
    }
}

pub(super) fn in_range<T: PartialOrd + std::fmt::Display + Copy>(
    field: &str,
    v: T,
    lo: T,
    hi: T,
) -> Result<T, SpecError> {
    if v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(SpecError::new(field, format!("must be between {lo} and {hi}, got {v}")))
    }
}

fn mesh_err(field: &str, e: MeshError) -> SpecError {
    SpecError::new(field, format!("invalid shape: {e}"))
}

/// Validate `spec` and build the job. `inputs` maps `NAME` of `"input:NAME"` to the
/// file's bytes.
pub fn prepare(spec: JobSpec, inputs: &HashMap<String, Vec<u8>>) -> Result<PreparedJob, SpecError> {
    let mut image = None;
    let mut second_stage = None;
    let mut edges = None;
    let mut image_mesh = None;
    let mut segmentation = None;
    let early = match &spec.problem {
        ProblemSpec::CurvatureFlow { gamma, lambda } => {
            positive("problem.gamma", *gamma)?;
            finite("problem.lambda", &[*lambda])
                .map_err(|_| SpecError::new("problem.lambda", "must be a finite number"))?;
            ProblemKind::CurvatureFlow(CurvatureFlow { gamma: *gamma, lambda: *lambda })
        }
        ProblemSpec::SurfaceDiffusion { gamma } => {
            positive("problem.gamma", *gamma)?;
            ProblemKind::SurfaceDiffusion(SurfaceDiffusion { gamma: *gamma })
        }
        ProblemSpec::Segmentation(seg) => {
            let prepared = super::segment::prepare_segmentation(seg, spec.initial.as_ref(), inputs)?;
            image = Some(Arc::new(prepared.grid));
            (second_stage, edges, image_mesh, segmentation) =
                (prepared.second_stage, prepared.edges, prepared.mesh, Some(prepared.setup));
            prepared.problem
        }
        // needs the initial curve: built below
        ProblemSpec::ShapeDesign(_) | ProblemSpec::StressedFilm(_) => {
            ProblemKind::CurvatureFlow(CurvatureFlow { gamma: 1.0, lambda: 0.0 })
        }
    };
    let film_cell = match &spec.problem {
        ProblemSpec::StressedFilm(fs) => Some(super::film::film_cell(fs)?),
        _ => None,
    };
    let mesh = match (&spec.initial, &image, &film_cell) {
        _ if image_mesh.is_some() => image_mesh.take().expect("an image's initial shape"),
        (Some(InitialSpec::Threshold {} | InitialSpec::Seeds { .. } | InitialSpec::Inscribed {}), _, _) => {
            return Err(SpecError::new(
                "initial.shape",
                "this shape comes from an image: it needs problem.type `segmentation`",
            ));
        }
        (initial, _, Some(cell)) => AnyMesh::Curve(super::film::initial_film(cell, initial.as_ref())?),
        (Some(InitialSpec::Film { .. } | InitialSpec::FilmPolyline { .. }), _, None) => {
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
    let (mut curve_manager, surface_manager) = match &mesh {
        AnyMesh::Curve(c) => (curve_manager(&spec.mesh, c)?, None),
        AnyMesh::Surface(m) => {
            let pinch_off = spec
                .mesh
                .pinch_off
                .unwrap_or(!matches!(early, ProblemKind::Segmentation(_) | ProblemKind::ChanVese(_)));
            (None, surface_manager(&spec.mesh, m, pinch_off)?)
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
            ProblemKind::ShapeDesign(super::design::shape_design(sd, c, spec.mesh.topology_changes, min_area)?)
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
        _ => early,
    };
    let f = &spec.flow;
    let default_product = match &problem {
        ProblemKind::CurvatureFlow(p) => Problem::<2>::default_scalar_product(p),
        ProblemKind::SurfaceDiffusion(p) => Problem::<2>::default_scalar_product(p),
        ProblemKind::Segmentation(p) => Problem::<2>::default_scalar_product(p),
        ProblemKind::ChanVese(p) => Problem::<2>::default_scalar_product(p),
        ProblemKind::ShapeDesign(p) => Problem::<2>::default_scalar_product(p),
        ProblemKind::StressedFilm(p) => Problem::<2>::default_scalar_product(p),
    };
    let scalar_product = f.scalar_product.unwrap_or(default_product);
    if let ProblemKind::StressedFilm(p) = &problem {
        if p.bending > 0.0 && scalar_product != ScalarProduct::HMinus1 {
            return Err(SpecError::new("problem.bending", "needs flow.scalar_product h_minus_1"));
        }
        if p.bending > 0.0 && f.solver.unwrap_or_default() != SolverKind::Lumped {
            return Err(SpecError::new("problem.bending", "needs flow.solver lumped"));
        }
    }
    if let Some(m) = curve_manager.as_mut() {
        m.params.keep_area = scalar_product == ScalarProduct::HMinus1;
        // a pocket of Ω closed off by Γ would have no Dirichlet boundary
        m.params.fill_pockets = matches!(problem, ProblemKind::ShapeDesign(_));
        m.params.keep_apart = matches!(&problem, ProblemKind::ChanVese(p) if p.separate);
    }
    let d = FlowSettings::default();
    let default_tau = match (&problem, scalar_product) {
        // the Newton-type product scales V like a Newton step (τ = 1); far from edges
        // β is clipped at ε and V = -G/ε, so a larger cap lets the step control decide
        (ProblemKind::Segmentation(_), ScalarProduct::H1Newton) => SEGMENTATION_NEWTON_TAU,
        (ProblemKind::Segmentation(_), _) => SEGMENTATION_L2_TAU,
        (ProblemKind::ChanVese(p), _) => CHAN_VESE_TAU_PIXELS / p.intensity.scale(),
        // the step control and backtracking pick the step; τ only caps it
        (ProblemKind::ShapeDesign(_), _) => SHAPE_DESIGN_TAU,
        (ProblemKind::StressedFilm(_), _) => STRESSED_FILM_TAU,
        _ => d.tau,
    };
    let tau = positive("flow.tau", f.tau.unwrap_or(default_tau))?;
    let default_tau_min = match &problem {
        ProblemKind::StressedFilm(_) => STRESSED_FILM_TAU_MIN,
        _ => d.tau_min,
    };
    let tau_min = positive("flow.tau_min", f.tau_min.unwrap_or(default_tau_min.min(tau)))?;
    if tau_min > tau {
        return Err(SpecError::new("flow.tau_min", format!("must not exceed flow.tau ({tau})")));
    }
    // a run given an end time runs to it unless the spec also asks for a tolerance
    let default_tolerance = if f.end_time.is_some() { 0.0 } else { d.tolerance };
    let tolerance = f.tolerance.unwrap_or(default_tolerance);
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(SpecError::new("flow.tolerance", format!("must be a nonnegative number, got {tolerance}")));
    }
    let end_time = f.end_time.map(|t| positive("flow.end_time", t)).transpose()?;
    let step_control = match f.step_control {
        None => d.step_control,
        Some(e) if e == 0.0 => None,
        Some(e) => Some(positive("flow.step_control", e)?),
    };
    let conservation = match (f.conservation, &problem) {
        (None, ProblemKind::StressedFilm(_)) => Some(STRESSED_FILM_CONSERVATION),
        (None, _) => None,
        (Some(c), _) if c == 0.0 => None,
        (Some(c), _) => Some(positive("flow.conservation", c)?),
    };
    let alpha = f.alpha.unwrap_or(d.alpha);
    if !(alpha.is_finite() && alpha >= 0.0) {
        return Err(SpecError::new("flow.alpha", format!("must be a nonnegative number, got {alpha}")));
    }
    let beta = positive("flow.beta", f.beta.unwrap_or(d.beta))?;
    let max_iterations = in_range("flow.max_iterations", f.max_iterations.unwrap_or(d.max_iterations), 1, 100_000_000)?;
    let settings = FlowSettings {
        scalar_product,
        solver: f.solver.unwrap_or_default(),
        tau,
        tau_min,
        max_iterations,
        end_time,
        tolerance,
        backtracking: f.backtracking.unwrap_or(!problem.physical()),
        step_control,
        alpha,
        beta,
        conservation,
        tolerance_per_time: problem.physical(),
    };
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
        image,
        edges,
        segmentation,
    })
}

/// Default `flow.tau` of the stressed film (its rates are `γk⁴` for wavenumbers `k`).
pub const STRESSED_FILM_TAU: f64 = 1e-5;
/// Default `flow.tau_min` of the stressed film: just after a void closes off, the
/// corners where the walls met move at up to `~10⁷` and need steps near `h⁴/γ`
/// (measured down to 2e-12 at 128 vertices) until surface diffusion has rounded them.
pub const STRESSED_FILM_TAU_MIN: f64 = 1e-15;
/// Default `flow.conservation` of the stressed film.
pub const STRESSED_FILM_CONSERVATION: f64 = 1e-6;

/// Default `flow.tau` of segmentation with the Newton-type H1 product.
pub const SEGMENTATION_NEWTON_TAU: f64 = 10.0;

/// Default `flow.tau` (the cap of the adaptive step) of shape design.
pub const SHAPE_DESIGN_TAU: f64 = 10.0;

/// Default `flow.tau` of Chan–Vese segmentation, times `L`: the data term's speed
/// is at most `max(λ_in, λ_out)` (normalized intensities), so a step moves the
/// contour at most about this many pixels; the step control and backtracking
/// shorten it where needed.
pub const CHAN_VESE_TAU_PIXELS: f64 = 8.0;

/// Default `flow.tau` of segmentation with the L2 (and plain H1) product.
pub const SEGMENTATION_L2_TAU: f64 = 1e-3;

fn input<'a>(field: &str, name: &str, inputs: &'a HashMap<String, Vec<u8>>) -> Result<(&'a str, &'a [u8]), SpecError> {
    let key = name
        .strip_prefix("input:")
        .ok_or_else(|| SpecError::new(field, format!("must name an uploaded input as \"input:NAME\", got {name:?}")))?;
    inputs
        .get_key_value(key)
        .map(|(k, v)| (k.as_str(), v.as_slice()))
        .ok_or_else(|| SpecError::new(field, format!("no input named {key:?} was supplied")))
}

/// Decode the image of a segmentation job: 2D raster, NRRD volume or slice stack.
pub(super) fn load_image(source: &ImageSource, inputs: &HashMap<String, Vec<u8>>) -> Result<Grid, SpecError> {
    let limits = ImageLimits::default();
    match source {
        ImageSource::One(name) => {
            let (key, bytes) = input("problem.image", name, inputs)?;
            let grid = if bytes.starts_with(b"NRRD") {
                decode_volume(key, bytes, &limits)
            } else if is_nifti(bytes) {
                decode_nifti(key, bytes, &limits)
            } else if is_tiff(bytes) && tiff_pages(bytes, 2) > 1 {
                decode_tiff_stack(key, bytes, &limits)
            } else {
                decode_image(key, bytes, &limits)
            };
            grid.map_err(|e| SpecError::new("problem.image", e.to_string()))
        }
        ImageSource::Slices(names) => {
            let slices = names
                .iter()
                .enumerate()
                .map(|(k, n)| input(&format!("problem.image[{k}]"), n, inputs))
                .collect::<Result<Vec<_>, _>>()?;
            decode_slices(&slices, &limits).map_err(|e| SpecError::new("problem.image", e.to_string()))
        }
    }
}

/// `(ε, h_min, h_max)`: the spec's values where given, else the defaults; checked.
fn sizes(m: &super::spec::MeshSpec, defaults: (f64, f64, f64)) -> Result<(f64, f64, f64), SpecError> {
    let epsilon = m.epsilon.map_or(Ok(defaults.0), |e| positive("mesh.epsilon", e))?;
    let h_min = m.h_min.map_or(Ok(defaults.1), |h| positive("mesh.h_min", h))?;
    let h_max = m.h_max.map_or(Ok(defaults.2), |h| positive("mesh.h_max", h))?;
    if h_min * 2.0 > h_max {
        return Err(SpecError::new("mesh.h_max", format!("must be at least twice mesh.h_min ({h_min})")));
    }
    Ok((epsilon, h_min, h_max))
}

fn surface_manager(
    m: &super::spec::MeshSpec,
    initial: &SurfaceMesh,
    pinch_off: bool,
) -> Result<Option<SurfaceManager>, SpecError> {
    if !(m.regularize || m.adapt || pinch_off) {
        return Ok(None);
    }
    let (mut params, _) = SurfaceManager::defaults_for(initial);
    (params.epsilon, params.h_min, params.h_max) = sizes(m, (params.epsilon, params.h_min, params.h_max))?;
    params.max_angle_deg = in_range("mesh.max_angle", m.max_angle, 90.0, 179.0)?;
    let sweeps = in_range("mesh.sweeps", m.sweeps.unwrap_or(3), 0, 1000)?;
    let pinch_curvature = pinch_off.then_some(2.0 / params.h_min);
    Ok(Some(SurfaceManager { regularize: m.regularize, sweeps, adapt: m.adapt, params, pinch_curvature }))
}

fn curve_manager(m: &super::spec::MeshSpec, initial: &CurveMesh) -> Result<Option<CurveManager>, SpecError> {
    if !(m.regularize || m.adapt || m.topology_changes) {
        return Ok(None);
    }
    let mut params = CurveManager::defaults_for(initial);
    (params.epsilon, params.h_min, params.h_max) = sizes(m, (params.epsilon, params.h_min, params.h_max))?;
    if let Some(a) = m.min_area {
        params.min_area = positive("mesh.min_area", a)?;
    }
    let sweeps = in_range("mesh.sweeps", m.sweeps.unwrap_or(1), 0, 1000)?;
    Ok(Some(CurveManager {
        regularize: m.regularize,
        sweeps,
        adapt: m.adapt,
        topology_changes: m.topology_changes,
        params,
    }))
}

pub(super) fn curve(field: &str, m: Result<CurveMesh, MeshError>) -> Result<AnyMesh, SpecError> {
    m.map(AnyMesh::Curve).map_err(|e| mesh_err(field, e))
}

pub(super) fn surface(field: &str, m: Result<SurfaceMesh, MeshError>) -> Result<AnyMesh, SpecError> {
    m.map(AnyMesh::Surface).map_err(|e| mesh_err(field, e))
}

fn build_initial(field: &str, s: &InitialSpec, inputs: &HashMap<String, Vec<u8>>) -> Result<AnyMesh, SpecError> {
    let at = |name: &str| format!("{field}.{name}");
    let curve_res = |r: usize| in_range(&at("resolution"), r, 3, MAX_VERTICES);
    match s {
        InitialSpec::Circle { center, radius, resolution } => {
            finite(&at("center"), center)?;
            let r = positive(&at("radius"), *radius)?;
            curve(field, geometry::circle(*center, r, curve_res(*resolution)?))
        }
        InitialSpec::Ellipse { center, semi_axes, rotation, resolution } => {
            finite(&at("center"), center)?;
            positive(&at("semi_axes[0]"), semi_axes[0])?;
            positive(&at("semi_axes[1]"), semi_axes[1])?;
            finite(&at("rotation"), &[*rotation])?;
            curve(field, geometry::ellipse(*center, *semi_axes, *rotation, curve_res(*resolution)?))
        }
        InitialSpec::Rectangle { center, size, resolution } => {
            finite(&at("center"), center)?;
            positive(&at("size[0]"), size[0])?;
            positive(&at("size[1]"), size[1])?;
            curve(field, geometry::rectangle(*center, *size, curve_res(*resolution)?.max(4)))
        }
        InitialSpec::Polygon { points, resolution } => {
            if points.len() < 3 {
                return Err(SpecError::new(at("points"), format!("needs at least 3 points, got {}", points.len())));
            }
            for (i, p) in points.iter().enumerate() {
                finite(&format!("{field}.points[{i}]"), p)?;
            }
            let res = resolution.map(curve_res).transpose()?;
            let pts: Vec<Point<2>> = points.iter().map(|p| Point::<2>::new(p[0], p[1])).collect();
            curve(field, geometry::polygon(&pts, res))
        }
        InitialSpec::Union { parts } => {
            if parts.is_empty() {
                return Err(SpecError::new(at("parts"), "needs at least one part"));
            }
            let mut curves = Vec::new();
            let mut surfaces = Vec::new();
            let mut vertices = 0;
            for (i, part) in parts.iter().enumerate() {
                let at_part = format!("{field}.parts[{i}]");
                match build_initial(&at_part, part, inputs)? {
                    AnyMesh::Curve(c) => {
                        vertices += c.num_vertices();
                        curves.push(c);
                    }
                    AnyMesh::Surface(s) => {
                        vertices += s.num_vertices();
                        surfaces.push(s);
                    }
                }
                // each part is within the limit; so must all of them be together
                if vertices > MAX_VERTICES {
                    return Err(SpecError::new(
                        at_part,
                        format!("the parts up to this one have more than {MAX_VERTICES} vertices in all"),
                    ));
                }
            }
            if !surfaces.is_empty() && !curves.is_empty() {
                return Err(SpecError::new(at("parts"), "mixes curves (2D) and surfaces (3D)"));
            }
            if !surfaces.is_empty() {
                return surface(field, surface_union(&surfaces));
            }
            curve(field, geometry::union(&curves))
        }
        InitialSpec::Sphere { center, radius, resolution } => {
            finite(&at("center"), center)?;
            let r = positive(&at("radius"), *radius)?;
            surface(field, geometry::icosphere(*center, r, in_range(&at("resolution"), *resolution, 0, 8)?))
        }
        InitialSpec::Ellipsoid { center, semi_axes, resolution } => {
            finite(&at("center"), center)?;
            for (i, a) in semi_axes.iter().enumerate() {
                positive(&format!("{field}.semi_axes[{i}]"), *a)?;
            }
            surface(field, geometry::ellipsoid(*center, *semi_axes, in_range(&at("resolution"), *resolution, 0, 8)?))
        }
        InitialSpec::Box { center, size, resolution } => {
            finite(&at("center"), center)?;
            for (i, a) in size.iter().enumerate() {
                positive(&format!("{field}.size[{i}]"), *a)?;
            }
            let div = positive(&at("resolution"), *resolution)?;
            // the vertices of the faces' grids (`box_surface`): those of the (n+1)³
            // lattice box less its interior, counted in f64 against overflow
            let n: Vec<f64> = size.iter().map(|s| (s * div).round().max(1.0)).collect();
            let vertices = (n[0] + 1.0) * (n[1] + 1.0) * (n[2] + 1.0) - (n[0] - 1.0) * (n[1] - 1.0) * (n[2] - 1.0);
            if vertices.is_nan() || vertices > MAX_VERTICES as f64 {
                return Err(SpecError::new(
                    at("resolution"),
                    format!("gives {vertices:.0} vertices, more than {MAX_VERTICES}"),
                ));
            }
            surface(field, geometry::box_surface(*center, *size, div))
        }
        InitialSpec::Torus { center, major_radius, minor_radius, resolution } => {
            finite(&at("center"), center)?;
            let big = positive(&at("major_radius"), *major_radius)?;
            let small = positive(&at("minor_radius"), *minor_radius)?;
            if small >= big {
                return Err(SpecError::new(at("minor_radius"), "must be smaller than major_radius"));
            }
            let n = in_range(&at("resolution"), *resolution, 3, 4096)?;
            let n_minor = ((n as f64 * small / big).round() as usize).max(8);
            if n * n_minor > MAX_VERTICES {
                return Err(SpecError::new(
                    at("resolution"),
                    format!(
                        "gives {} vertices ({n} around the axis, {n_minor} around the tube), more than {MAX_VERTICES}",
                        n * n_minor
                    ),
                ));
            }
            surface(field, geometry::torus(*center, big, small, n, n_minor))
        }
        InitialSpec::Film { .. } | InitialSpec::FilmPolyline { .. } => {
            Err(SpecError::new(at("shape"), "film shapes are for problem.type `stressed_film`"))
        }
        InitialSpec::Threshold {} | InitialSpec::Seeds { .. } | InitialSpec::Inscribed {} => {
            Err(SpecError::new(at("shape"), "this shape comes from an image: it needs problem.type `segmentation`"))
        }
        InitialSpec::Mesh { file } => {
            let (name, bytes) = input(&at("file"), file, inputs)?;
            read_mesh_file(name, bytes).map_err(|e| SpecError::new(at("file"), e.to_string()))
        }
    }
}

pub(super) fn surface_union(parts: &[SurfaceMesh]) -> Result<SurfaceMesh, MeshError> {
    let mut positions = Vec::new();
    let mut elements = Vec::new();
    for p in parts {
        let base = positions.len();
        positions.extend_from_slice(p.positions());
        elements.extend(p.elements().iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }
    Mesh::new(positions, elements)
}
