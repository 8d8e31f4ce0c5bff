//! The job spec (docs/job-spec.md): the types users write, parsed with serde.
//! Unknown fields are rejected; every error names the field by its path
//! (`flow.tau`, `initial.parts[1].radius`). One file per part: the problem
//! (`problem`, `segmentation`), the starting shape (`initial`), the flow, mesh and
//! output sections here, the error type (`error`), and parsing with the error's
//! location (`parse`, `path`).

pub mod bounds;
mod defaults;
mod error;
mod initial;
mod limits;
mod parse;
mod path;
mod problem;
mod segmentation;
mod unique_keys;

pub use error::SpecError;
pub use initial::{
    BoxShape, CircleShape, EllipseShape, EllipsoidShape, FilmPolylineShape, FilmShape, InitialSpec, InscribedShape,
    MeshShape, PolygonShape, RectangleShape, SeedsShape, SphereShape, ThresholdShape, TorusShape, UnionShape,
};
pub use limits::{format_size, parse_size, Limits, LimitsSpec, Size};
pub use parse::parse_spec;
pub use problem::{
    BoundarySpec, CircleBoundary, ConstantBoundary, ConstantTarget, ControlSpec, CurvatureFlowSpec, FilmBoundarySpec,
    LinearBoundary, LogRadialTarget, PolarTarget, PolygonBoundary, ProblemSpec, ShapeDesignSpec, SquareBoundary,
    StressedFilmSpec, SurfaceDiffusionSpec, TargetSpec, XBoundary,
};
pub use segmentation::{
    default_beta_epsilon, default_lambda, default_lambda_final, default_sigma, BackgroundModel, ImageSource, MeansKind,
    Polarity, SegmentationModel, SegmentationSpec,
};

use crate::flow::{ScalarProduct, SolverKind};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A shapeflow job: the functional, the starting shape and the settings of the flow,
/// its mesh management and its output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
// the rules that tie `initial` to `problem.type`, as `prepare` applies them: only
// segmentation may leave `initial` out, and film shapes are for the stressed film
// and only for it
#[schemars(extend("allOf" = [
    {
        "if": {"type": "object", "properties": {"problem": {"type": "object", "properties": {"type": {"const": "segmentation"}}}}},
        "else": {"type": "object", "required": ["initial"], "properties": {"initial": {"type": "object"}}}
    },
    {
        "if": {"type": "object", "properties": {"problem": {"type": "object", "properties": {"type": {"const": "stressed_film"}}}}},
        "then": {"type": "object", "required": ["initial"], "properties": {"initial": {
            "type": "object", "properties": {"shape": {"enum": ["film", "film_polyline"]}}
        }}},
        "else": {"type": "object", "properties": {"initial": {"anyOf": [
            {"type": "null"},
            {"type": "object", "properties": {"shape": {"not": {"enum": ["film", "film_polyline"]}}}}
        ]}}}
    }
]))]
pub struct JobSpec {
    pub problem: ProblemSpec,
    /// Required, except for segmentation (default: `threshold`).
    #[serde(default)]
    pub initial: Option<InitialSpec>,
    #[serde(default)]
    pub flow: FlowSpec,
    #[serde(default)]
    pub mesh: MeshSpec,
    #[serde(default)]
    pub output: OutputSpec,
    /// (Addition) what the job may use in the service (docs/isolation.md).
    #[serde(default, skip_serializing_if = "LimitsSpec::is_empty")]
    pub limits: LimitsSpec,
}

/// `flow`: time stepping and the descent direction. Every field is optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FlowSpec {
    /// `l2`, `h1`, `h1_newton` or `h_minus_1`; default: the problem's own.
    pub scalar_product: Option<ScalarProduct>,
    /// `lumped` (default) or `consistent`.
    pub solver: Option<SolverKind>,
    /// Nominal time step; default 1e-3, but 10 for `shape_design` and for `segmentation`
    /// with `h1_newton`, 1e-5 for `stressed_film`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub tau: Option<f64>,
    /// The run stops with `tau_min` when a step would need a smaller τ; default 1e-10
    /// (`stressed_film` 1e-15), or `tau` when that is smaller.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub tau_min: Option<f64>,
    /// Default 1000.
    #[schemars(range(min = bounds::MAX_ITERATIONS.min, max = bounds::MAX_ITERATIONS.max))]
    pub max_iterations: Option<usize>,
    /// Stop at this time; the last step is shortened to end exactly there.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub end_time: Option<f64>,
    /// Stop with `converged` when `|J_{n+1} − J_n| ≤ tolerance·|J_n|` (a rate for
    /// physical evolutions; for the others judged on steps of the flow's own
    /// length, not on one cut short by a tangled trial or still growing back after
    /// one, and only when the judged step before it was as small; also when over
    /// six such steps the recorded energy ended within `tolerance·|J|` of where it
    /// began); 0 disables; default 1e-6 (1e-5 for segmentation's `chan_vese` and
    /// `both` models), but 0 when `end_time` is given (the run then goes to its end
    /// time).
    #[schemars(range(min = 0))]
    pub tolerance: Option<f64>,
    /// Halve τ until J decreases; default on, off for physical flows.
    pub backtracking: Option<bool>,
    /// ε of the geometric time-step control `τ max_T |V⃗(z_a) − V⃗(z_b)|/h_T ≤ ε`
    /// (`τV⃗` the step's displacements after the problem's constraints); 0 switches
    /// it off; default 0.5.
    #[schemars(range(min = 0))]
    pub step_control: Option<f64>,
    /// α of the plain `h1` product; default 0.01.
    #[schemars(range(min = 0))]
    pub alpha: Option<f64>,
    /// β of the plain `h1` product; default 1.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub beta: Option<f64>,
    /// Largest relative change of the enclosed area/volume per step (`H^{-1}`
    /// flows; 0 switches it off); default 1e-6 for `stressed_film`, off otherwise.
    #[schemars(range(min = 0))]
    pub conservation: Option<f64>,
}

/// `mesh`: mesh management (paper §4.1). Switches default on; the sizes default to
/// values derived from the initial mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MeshSpec {
    /// Area/volume-preserving tangential redistribution after every step.
    pub regularize: bool,
    /// Refine where `h_S β_S > epsilon`, coarsen where it is below `epsilon/8`, keep
    /// edge lengths in `[h_min, h_max]`.
    pub adapt: bool,
    /// Curves: merge and split where segments cross. Surfaces, with `pinch_off:
    /// false`: surgery (necks cut, surfaces in contact merged but in
    /// segmentation; docs/problems/surface-evolution.md).
    pub topology_changes: bool,
    /// Regularization sweeps per step (default 1 for curves, 3 for surfaces).
    #[schemars(range(min = bounds::SWEEPS.min, max = bounds::SWEEPS.max))]
    pub sweeps: Option<usize>,
    /// Refinement threshold for `h_S β_S`; default 1.5 × the initial mesh's largest.
    pub epsilon: Option<f64>,
    /// Smallest edge length; default ¼ of the initial mean edge (a surface traced
    /// from the image: at least ½ voxel).
    pub h_min: Option<f64>,
    /// Largest edge length; default 3 × the initial mean edge (a surface traced from
    /// the image: at most one voxel).
    pub h_max: Option<f64>,
    /// Components with a smaller enclosed area are dropped after a topological change.
    pub min_area: Option<f64>,
    /// Angle-width control (surfaces): split edges opposite wider angles (degrees).
    #[schemars(range(min = bounds::MAX_ANGLE.min, max = bounds::MAX_ANGLE.max))]
    pub max_angle: f64,
    /// Surfaces: stop with `pinch_off` when a neck radius falls below `h_min/2`
    /// (default on, except for segmentation, whose creases are not necks). Off,
    /// with `topology_changes`: the neck is cut and the run goes on.
    pub pinch_off: Option<bool>,
    /// A surface traced from the image, with neither `h_min` nor `h_max` given,
    /// first converges with its edges between ¾ voxel and two voxels (at ten
    /// times `flow.tolerance`), then goes on at the default sizes (half a voxel to
    /// one) to convergence. Off: the default sizes from the start.
    pub coarse_start: bool,
}

impl Default for MeshSpec {
    fn default() -> Self {
        MeshSpec {
            regularize: true,
            adapt: true,
            topology_changes: true,
            sweeps: None,
            epsilon: None,
            h_min: None,
            h_max: None,
            min_area: None,
            max_angle: 120.0,
            pinch_off: None,
            coarse_start: true,
        }
    }
}

/// `output`: what is kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Keep a checkpoint every this many iterations (and at the end); at least 1.
    #[schemars(range(min = 1))]
    pub checkpoint_every: usize,
    /// (Addition) the per-vertex field the glTF results colour: `curvature` (the
    /// default), `normal_velocity` (`V` of the next step) or `problem_field` (the
    /// problem's own: segmentation's edge indicator `H`, or the image `I` for the
    /// model `chan_vese`; the stressed film's elastic energy density `|∇y|²`).
    pub color_by: ColorBy,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec { checkpoint_every: 10, color_by: ColorBy::Curvature }
    }
}

/// `output.color_by`: the field the glTF results colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ColorBy {
    #[default]
    Curvature,
    NormalVelocity,
    ProblemField,
}
