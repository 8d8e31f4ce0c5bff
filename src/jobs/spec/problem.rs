//! `problem`: the functional to minimize, one variant per problem.

use super::defaults::{one, origin2};
use super::SegmentationSpec;
use crate::problems::GradientKind;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `problem`: the functional to minimize.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ProblemSpec {
    /// `J = γ|Γ| + λ|Ω|`.
    CurvatureFlow(CurvatureFlowSpec),
    /// `J = γ|Γ|` under the `H^{-1}` product.
    SurfaceDiffusion(SurfaceDiffusionSpec),
    /// Geodesic active contours `J = ∫_Γ H + λ∫_Ω H` on an image.
    Segmentation(SegmentationSpec),
    /// Optimal shape design for the Laplace equation (2D): `J = ½∫_D (y − z_g)² + γ|Γ|`.
    ShapeDesign(ShapeDesignSpec),
    /// The epitaxially stressed film (2D, periodic in `x`): `J = ∫_Ω |∇y|² + γ|Γ|`
    /// under the `H^{-1}` product; `initial` is a `film` or `film_polyline`.
    StressedFilm(StressedFilmSpec),
}

// The fields of each variant of `ProblemSpec`, as a struct of its own: a bad field is
// then located by deserializing its variant alone (see `spec::path`).

// `ProblemSpec::CurvatureFlow`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurvatureFlowSpec {
    #[serde(default = "one")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub gamma: f64,
    #[serde(default)]
    pub lambda: f64,
}

// `ProblemSpec::SurfaceDiffusion`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDiffusionSpec {
    #[serde(default = "one")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub gamma: f64,
}

/// `problem` of `stressed_film` (paper §1.3, §4.4.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StressedFilmSpec {
    /// Width `L` of the periodic cell `0 < x < L`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub length: f64,
    /// Surface tension `γ > 0`.
    #[serde(default = "one")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub gamma: f64,
    /// The Dirichlet data `g` on the substrate `y = 0` and the walls; default `x`.
    #[serde(default)]
    pub boundary: FilmBoundarySpec,
    /// (Addition) thickness `δ > 0` of a wetting layer: the free surface and the
    /// voids are kept at `y ≥ δ` (an obstacle, up to the per-step area correction),
    /// so the gas never reaches the substrate. Without it a surface that meets the
    /// substrate is inadmissible.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub wetting_layer: Option<f64>,
    /// (Addition) `ε ≥ 0` of a bending energy `ε/2 ∫_Γ κ²` added to `J`: a
    /// curvature regularization that gives a crack tip a radius of about `√(ε/γ)`.
    /// Needs the `h_minus_1` product and the lumped solver (the defaults).
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub bending: f64,
}

/// `problem.boundary` of `stressed_film`: `g`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum FilmBoundarySpec {
    /// `g = x` (the paper's misfit).
    // an empty struct, not a unit variant, so that unknown fields are rejected
    // (serde ignores them on unit variants)
    X(XBoundary),
    /// `g ≡ value`: no stress, plain surface diffusion.
    Constant(ConstantBoundary),
    /// `g = a + b x + c y`.
    Linear(LinearBoundary),
}

// The fields of each variant of `FilmBoundarySpec`, as a struct of its own: a bad field is
// then located by deserializing its variant alone (see `spec::path`).

// `FilmBoundarySpec::X`
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct XBoundary {}

// `FilmBoundarySpec::Constant`
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstantBoundary {
    pub value: f64,
}

// `FilmBoundarySpec::Linear`
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinearBoundary {
    #[serde(default)]
    pub a: f64,
    #[serde(default)]
    pub b: f64,
    #[serde(default)]
    pub c: f64,
}

impl Default for FilmBoundarySpec {
    fn default() -> Self {
        FilmBoundarySpec::X(XBoundary {})
    }
}

/// `problem` of `shape_design` (paper §1.2, §4.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShapeDesignSpec {
    /// The fixed outer boundary `Σ` (`y = 0` there).
    pub outer: BoundarySpec,
    /// The control region `D`: the region between two nested closed curves.
    pub control: ControlSpec,
    /// The target `z_g` on `D`.
    pub target: TargetSpec,
    /// Weight `γ ≥ 0` of the length of `Γ`.
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub gamma: f64,
    /// Vertex spacing on `Σ` and `∂D`, which also sets the bulk element size; default
    /// 1/200 of the perimeter of `Σ`.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub spacing: Option<f64>,
    /// `discrete` (default: the exact gradient of the discrete functional) or
    /// `continuous` (the paper's formula for `G`).
    #[serde(default)]
    pub gradient: GradientKind,
}

/// `problem.control`: `D` lies between `inner` and `outer`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    pub inner: BoundarySpec,
    pub outer: BoundarySpec,
}

/// A fixed closed boundary of the shape-design domain.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum BoundarySpec {
    Circle(CircleBoundary),
    /// Axis-aligned square `|x − c|_∞ ≤ size/2`.
    Square(SquareBoundary),
    /// A simple polygon through the points (either orientation).
    Polygon(PolygonBoundary),
}

// The fields of each variant of `BoundarySpec`, as a struct of its own: a bad field is
// then located by deserializing its variant alone (see `spec::path`).

// `BoundarySpec::Circle`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CircleBoundary {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
}

// `BoundarySpec::Square`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SquareBoundary {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub size: f64,
}

// `BoundarySpec::Polygon`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PolygonBoundary {
    pub points: Vec<[f64; 2]>,
}

/// `problem.target`: `z_g`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum TargetSpec {
    Constant(ConstantTarget),
    /// `log(radius / |x − center|)` (paper §4.3.2).
    LogRadial(LogRadialTarget),
    /// `a + b cos(k θ)`, θ the polar angle around `center` (paper §4.3.3).
    Polar(PolarTarget),
}

// The fields of each variant of `TargetSpec`, as a struct of its own: a bad field is
// then located by deserializing its variant alone (see `spec::path`).

// `TargetSpec::Constant`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstantTarget {
    pub value: f64,
}

// `TargetSpec::LogRadial`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LogRadialTarget {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
}

// `TargetSpec::Polar`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PolarTarget {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    pub a: f64,
    pub b: f64,
    pub k: f64,
}
