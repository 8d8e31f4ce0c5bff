//! The job spec (docs/job-spec.md). Unknown fields are rejected; every error names the
//! field by its path (`flow.tau`, `initial.parts[1].radius`).

use crate::flow::{ScalarProduct, SolverKind};
use crate::problems::GradientKind;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A spec error: the offending field's path and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct SpecError {
    pub field: String,
    pub message: String,
}

impl SpecError {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        SpecError { field: field.into(), message: message.into() }
    }
}

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
}

fn one() -> f64 {
    1.0
}

fn film_mode() -> u32 {
    1
}

fn film_resolution() -> usize {
    128
}

/// `problem`: the functional to minimize.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ProblemSpec {
    /// `J = γ|Γ| + λ|Ω|`.
    CurvatureFlow {
        #[serde(default = "one")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        gamma: f64,
        #[serde(default)]
        lambda: f64,
    },
    /// `J = γ|Γ|` under the `H^{-1}` product.
    SurfaceDiffusion {
        #[serde(default = "one")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        gamma: f64,
    },
    /// Geodesic active contours `J = ∫_Γ H + λ∫_Ω H` on an image.
    Segmentation(SegmentationSpec),
    /// Optimal shape design for the Laplace equation (2D): `J = ½∫_D (y − z_g)² + γ|Γ|`.
    ShapeDesign(ShapeDesignSpec),
    /// The epitaxially stressed film (2D, periodic in `x`): `J = ∫_Ω |∇y|² + γ|Γ|`
    /// under the `H^{-1}` product; `initial` is a `film` or `film_polyline`.
    StressedFilm(StressedFilmSpec),
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
    // a struct variant, so that unknown fields are rejected (serde ignores them on
    // unit variants)
    X {},
    /// `g ≡ value`: no stress, plain surface diffusion.
    Constant { value: f64 },
    /// `g = a + b x + c y`.
    Linear {
        #[serde(default)]
        a: f64,
        #[serde(default)]
        b: f64,
        #[serde(default)]
        c: f64,
    },
}

impl Default for FilmBoundarySpec {
    fn default() -> Self {
        FilmBoundarySpec::X {}
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
    Circle {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: f64,
    },
    /// Axis-aligned square `|x − c|_∞ ≤ size/2`.
    Square {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("exclusiveMinimum" = 0))]
        size: f64,
    },
    /// A simple polygon through the points (either orientation).
    Polygon { points: Vec<[f64; 2]> },
}

/// `problem.target`: `z_g`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum TargetSpec {
    Constant {
        value: f64,
    },
    /// `log(radius / |x − center|)` (paper §4.3.2).
    LogRadial {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: f64,
    },
    /// `a + b cos(k θ)`, θ the polar angle around `center` (paper §4.3.3).
    Polar {
        #[serde(default = "origin2")]
        center: [f64; 2],
        a: f64,
        b: f64,
        k: f64,
    },
}

/// One input file, or a stack of 2D slices.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum ImageSource {
    One(#[schemars(regex(pattern = "^input:"))] String),
    Slices(#[schemars(length(min = 1), inner(regex(pattern = "^input:")))] Vec<String>),
}

/// `problem` of `segmentation` (without its `type`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SegmentationSpec {
    /// `"input:NAME"` (PNG/JPEG/TIFF → 2D, NRRD → 3D) or a list of them (a stack
    /// of 2D slices → 3D, first slice at the bottom).
    pub image: ImageSource,
    /// Gaussian smoothing in pixels of the image the threshold and the edge
    /// indicator see; default from the image's noise level (1–4 pixels; at least
    /// 1.5 for the geodesic model).
    #[serde(default)]
    #[schemars(range(min = 0, max = 64))]
    pub sigma: Option<f64>,
    /// (Addition, Chan–Vese) Gaussian smoothing in pixels of the image the fit
    /// sees; default 0 (the fit averages the noise over regions).
    #[serde(default)]
    #[schemars(range(min = 0, max = 64))]
    pub data_sigma: Option<f64>,
    /// Weight of the region term (balloon force); default `0.3 L` (2D) or `0.15 L`
    /// (3D), `L` the number of samples along the image's longest side.
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub lambda: Option<f64>,
    /// (Addition) once the flow has converged with `lambda`, it continues with
    /// this weight until it converges again (default 0 in 2D, `lambda` in 3D).
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub lambda_final: Option<f64>,
    /// (Addition) the results show the contour moved onto the image's edges to
    /// sub-pixel accuracy; default true.
    #[serde(default)]
    pub edge_refinement: Option<bool>,
    /// (Addition, geodesic model) contrast scale `k` of the edge indicator
    /// `H = 1/(1 + |∇I_σ|²/k²)`, the image mapped to [0, 100]; default from the
    /// image's gradients, `max(p99, max/4)/20` of `|∇I_σ|` (about 1 on a clean
    /// image, lower where the objects are dim).
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 1000))]
    pub edge_contrast: Option<f64>,
    /// Threshold ε of the Newton weight β (paper §4.2.1); default `0.1 L²`.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: Option<f64>,
    /// (Addition) the functional: `chan_vese` (region-based, one mean intensity
    /// per object; the default), `geodesic` (geodesic active contours, the
    /// paper's) or `both` (their sum).
    #[serde(default)]
    pub model: Option<SegmentationModel>,
    /// (Addition, Chan–Vese) weight of the contour's length, in intensity² ×
    /// pixels (the image normalized to [0, 1]); default `max(0.05, noise/2)` with
    /// the noise's standard deviation on that scale.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1000))]
    pub mu: Option<f64>,
    /// (Addition, Chan–Vese) weight of the fit inside the objects; default 1.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1000))]
    pub lambda_in: Option<f64>,
    /// (Addition, Chan–Vese) weight of the fit outside the objects; default 1.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1000))]
    pub lambda_out: Option<f64>,
    /// (Addition, Chan–Vese) `per_object` (default: each object has its own mean
    /// intensity, so that dim and bright objects are both fitted) or `global` (one
    /// mean for all objects: the two-phase model).
    #[serde(default)]
    pub means: Option<MeansKind>,
    /// (Addition) intensity normalization: the percentiles of the image mapped to
    /// 0 and 1 (values beyond are clipped); default [0.5, 99.5].
    #[serde(default)]
    #[schemars(extend("items" = {"type": "number", "format": "double", "minimum": 0, "maximum": 100}))]
    pub percentiles: Option<[f64; 2]>,
    /// (Addition) the background model removed before thresholding and fitting:
    /// `quadratic` (default: a quadratic illumination fitted to the background) or
    /// `flat` (none).
    #[serde(default)]
    pub background: Option<BackgroundModel>,
    /// (Addition) whether the objects are `bright` or `dark`; default: the class
    /// of the threshold that covers less of the image's border.
    #[serde(default)]
    pub polarity: Option<Polarity>,
    /// (Addition) the threshold of the automatic initial shape on the normalized
    /// scale [0, 1]; default Otsu's.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1))]
    pub threshold: Option<f64>,
    /// (Addition) the threshold (normalized scale) at which dim objects that the
    /// main threshold misses entirely are found; default: the background level
    /// (the histogram's mode) plus 8 standard deviations of the smoothed noise.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1))]
    pub dim_threshold: Option<f64>,
    /// (Addition) objects of fewer pixels (voxels) are dropped from the automatic
    /// initial shape, and holes of fewer are filled; default 16 (2D), 64 (3D).
    #[serde(default)]
    #[schemars(range(min = 0, max = 1e9))]
    pub min_size: Option<f64>,
    /// (Addition) the automatic initial shape splits objects that touch, where a
    /// neck is clearly narrower than both sides (a watershed of the distance
    /// transform); they then stay separate objects. Default true.
    #[serde(default)]
    pub split_touching: Option<bool>,
    /// (Addition, Chan–Vese with per-object means) whether objects merge where
    /// their contours meet; default false: objects that start separate stay the
    /// objects they are (a trial step that would make them overlap is shortened).
    #[serde(default)]
    pub merge: Option<bool>,
}

/// `problem.model` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SegmentationModel {
    Geodesic,
    ChanVese,
    Both,
}

/// `problem.means` of Chan–Vese segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MeansKind {
    PerObject,
    Global,
}

/// `problem.background` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BackgroundModel {
    Flat,
    Quadratic,
}

/// `problem.polarity` of segmentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Polarity {
    Bright,
    Dark,
}

/// Prefix of the message of a malformed `problem.image` (see [`parse_spec`]).
const IMAGE_MESSAGE: &str = "`image` must be \"input:NAME\" or a list of them";

impl<'de> Deserialize<'de> for ImageSource {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(s) => Ok(ImageSource::One(s)),
            serde_json::Value::Array(items) if !items.is_empty() => items
                .into_iter()
                .map(|v| match v {
                    serde_json::Value::String(s) => Ok(s),
                    other => Err(serde::de::Error::custom(format!("{IMAGE_MESSAGE}, found {other} in the list"))),
                })
                .collect::<Result<_, _>>()
                .map(ImageSource::Slices),
            other => Err(serde::de::Error::custom(format!("{IMAGE_MESSAGE}, got {other}"))),
        }
    }
}

/// Default `problem.sigma` (pixels), 1.5 in 2D and 3D. The smoothing moves the
/// minimizer inside the edges by `O(σ²κ)`, which the results' edge refinement
/// (`problem.edge_refinement`) removes; more smoothing means a quieter `H` and fewer
/// iterations (two noisy balls in 64³: 31 iterations at σ = 1, 18 at σ = 1.5).
pub fn default_sigma(_d: usize) -> f64 {
    1.5
}
/// Default `problem.lambda` of segmentation for an image of `L` samples along its
/// longest side, in dimension `d`: `0.3 L` (2D) and `0.15 L` (3D). The paper's
/// λ = 30 on 100×100 images is 0.3 per pixel; keeping λ/L fixed makes the balance
/// of balloon force, edge attraction and pixel noise the same at every resolution.
/// The balloon force shifts the contour inwards by about `(λ + κ) s² / 2L` pixels
/// (`s²` the variance of the edge profile), and `κ` of a surface is twice that of a
/// curve of the same radius: volumes get the smaller factor.
pub fn default_lambda(d: usize, l: f64) -> f64 {
    if d == 2 {
        0.3 * l
    } else {
        0.15 * l
    }
}
/// Default `problem.lambda_final` of segmentation: 0 for 2D images, `lambda` (no
/// second stage) for volumes. The balloon force that carries the contour to the
/// object's edges also holds it about `λ s²/2L` pixels inside them (see
/// [`default_lambda`]): half a pixel with the 2D defaults, which costs 1 % of Dice
/// on a 128² image. Started at the edges, the flow without it moves out to where
/// `κH + ∂_ν H = 0` in a few iterations. In 3D the shift is a quarter as large
/// and the second stage measured to gain 0.1 % of Dice for 60 % more time.
pub fn default_lambda_final(d: usize, lambda: f64) -> f64 {
    if d == 2 {
        0.0
    } else {
        lambda
    }
}
/// Default `problem.epsilon` of segmentation: `0.1 L²`, the paper's ε = 0.1 per
/// squared pixel (1e3 on its 100×100 images in the unit box).
pub fn default_beta_epsilon(l: f64) -> f64 {
    0.1 * l * l
}

fn origin2() -> [f64; 2] {
    [0.0, 0.0]
}
fn origin3() -> [f64; 3] {
    [0.0, 0.0, 0.0]
}
fn curve_resolution() -> usize {
    128
}
fn sphere_resolution() -> u32 {
    4
}
fn box_resolution() -> f64 {
    8.0
}
fn torus_resolution() -> usize {
    64
}

/// `initial`: the starting shape. `resolution` means: curves, the number of
/// vertices; sphere/ellipsoid, the icosphere subdivision level; box, grid cells per
/// unit length; torus, segments around the axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum InitialSpec {
    Circle {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: f64,
        #[serde(default = "curve_resolution")]
        #[schemars(range(min = 3, max = 2_000_000))]
        resolution: usize,
    },
    Ellipse {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        semi_axes: [f64; 2],
        #[serde(default)]
        rotation: f64,
        #[serde(default = "curve_resolution")]
        #[schemars(range(min = 3, max = 2_000_000))]
        resolution: usize,
    },
    Rectangle {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        size: [f64; 2],
        #[serde(default = "curve_resolution")]
        #[schemars(range(min = 3, max = 2_000_000))]
        resolution: usize,
    },
    Polygon {
        points: Vec<[f64; 2]>,
        #[serde(default)]
        #[schemars(range(min = 3, max = 2_000_000))]
        resolution: Option<usize>,
    },
    /// A film surface (stressed film): `y = height + amplitude·cos(2π mode x / L)`
    /// over one period, `resolution` vertices.
    Film {
        #[schemars(extend("exclusiveMinimum" = 0))]
        height: f64,
        #[serde(default)]
        amplitude: f64,
        #[serde(default = "film_mode")]
        #[schemars(range(min = 1))]
        mode: u32,
        #[serde(default = "film_resolution")]
        #[schemars(range(min = 8, max = 100_000))]
        resolution: usize,
    },
    /// A film surface through the points (one period, `0 ≤ x < L`, in `+x`; it may
    /// overhang), resampled to `resolution` vertices if given.
    FilmPolyline {
        #[schemars(length(min = 3))]
        points: Vec<[f64; 2]>,
        #[serde(default)]
        #[schemars(range(min = 8, max = 100_000))]
        resolution: Option<usize>,
    },
    Union {
        parts: Vec<InitialSpec>,
    },
    Sphere {
        #[serde(default = "origin3")]
        center: [f64; 3],
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: f64,
        #[serde(default = "sphere_resolution")]
        #[schemars(range(max = 8))]
        resolution: u32,
    },
    Ellipsoid {
        #[serde(default = "origin3")]
        center: [f64; 3],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        semi_axes: [f64; 3],
        #[serde(default = "sphere_resolution")]
        #[schemars(range(max = 8))]
        resolution: u32,
    },
    Box {
        #[serde(default = "origin3")]
        center: [f64; 3],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        size: [f64; 3],
        #[serde(default = "box_resolution")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        resolution: f64,
    },
    Torus {
        #[serde(default = "origin3")]
        center: [f64; 3],
        #[schemars(extend("exclusiveMinimum" = 0))]
        major_radius: f64,
        #[schemars(extend("exclusiveMinimum" = 0))]
        minor_radius: f64,
        #[serde(default = "torus_resolution")]
        #[schemars(range(min = 3, max = 4096))]
        resolution: usize,
    },
    /// (Addition, segmentation) contours from the image itself, the default when
    /// `initial` is omitted: a threshold of the smoothed image (Otsu's unless
    /// `problem.threshold`, and `problem.dim_threshold` for dim objects), specks
    /// dropped, touching objects split, one closed curve (surface) per object and
    /// per hole (marching squares, marching tetrahedra).
    Threshold {},
    /// (Addition, segmentation) a grid of small circles, `spacing` pixels apart
    /// (default 1/8 of the image's shorter side), of radius `radius` pixels
    /// (default a quarter of the spacing).
    Seeds {
        #[serde(default)]
        #[schemars(extend("exclusiveMinimum" = 0))]
        spacing: Option<f64>,
        #[serde(default)]
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: Option<f64>,
    },
    /// (Addition, segmentation) a circle (sphere) inscribed in the image box, two
    /// pixels inside it (the default initial shape of volumes).
    Inscribed {},
    /// An uploaded mesh: `"input:NAME"` (OBJ, OFF, STL or glTF; closed curves as
    /// OBJ `l` polylines or glTF `LINE_LOOP`s in the plane z = 0).
    Mesh {
        #[schemars(regex(pattern = "^input:"))]
        file: String,
    },
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
    #[schemars(range(min = 1, max = 100_000_000))]
    pub max_iterations: Option<usize>,
    /// Stop at this time; the last step is shortened to end exactly there.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub end_time: Option<f64>,
    /// Stop with `converged` when `|J_{n+1} − J_n| ≤ tolerance·|J_n|` (a rate for
    /// physical evolutions); 0 disables; default 1e-6, but 0 when `end_time` is given
    /// (the run then goes to its end time).
    #[schemars(range(min = 0))]
    pub tolerance: Option<f64>,
    /// Halve τ until J decreases; default on, off for physical flows.
    pub backtracking: Option<bool>,
    /// ε of the geometric time-step control `τ max_T |V⃗(z_a) − V⃗(z_b)|/h_T ≤ ε`;
    /// 0 switches it off; default 0.5.
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
    /// Curves: merge and split where segments cross.
    pub topology_changes: bool,
    /// Regularization sweeps per step (default 1 for curves, 3 for surfaces).
    pub sweeps: Option<usize>,
    /// Refinement threshold for `h_S β_S`; default 1.5 × the initial mesh's largest.
    pub epsilon: Option<f64>,
    /// Smallest edge length; default ¼ of the initial mean edge.
    pub h_min: Option<f64>,
    /// Largest edge length; default 3 × the initial mean edge.
    pub h_max: Option<f64>,
    /// Components with a smaller enclosed area are dropped after a topological change.
    pub min_area: Option<f64>,
    /// Angle-width control (surfaces): split edges opposite wider angles (degrees).
    pub max_angle: f64,
    /// Surfaces: stop with `pinch_off` when a neck radius falls below `h_min/2`
    /// (default on, except for segmentation, whose creases are not necks).
    pub pinch_off: Option<bool>,
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
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec { checkpoint_every: 10 }
    }
}

/// Parse a spec from JSON text. Errors name the field path, also inside the tagged
/// objects (`initial.parts[1].center`, see [`super::spec_path`]).
pub fn parse_spec(text: &str) -> Result<JobSpec, SpecError> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| SpecError::new("(document)", format!("malformed JSON: {e}")))?;
    if let Some(e) = super::spec_path::duplicate_key(text) {
        return Err(e);
    }
    // one deserialization for a good spec (an object: serde also reads a struct from
    // an array); a bad one is searched for the field to name
    if value.is_object() {
        if let Ok(spec) = JobSpec::deserialize(&value) {
            return Ok(spec);
        }
    }
    let mut e = super::spec_path::locate(&value)
        .unwrap_or_else(|| SpecError::new("(document)", "not a valid job spec".to_string()));
    if let Some(rest) = e.message.strip_prefix(IMAGE_MESSAGE) {
        e = SpecError::new("problem.image", format!("must be \"input:NAME\" or a list of them{rest}"));
    }
    Err(e)
}
