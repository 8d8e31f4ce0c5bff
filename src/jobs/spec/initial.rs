//! `initial`: the starting shape.

use super::bounds::{CURVE_RESOLUTION, FILM_RESOLUTION, SPHERE_LEVEL, TORUS_RESOLUTION};
use super::defaults::{
    box_resolution, curve_resolution, film_mode, film_resolution, origin2, origin3, sphere_resolution, torus_resolution,
};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `initial`: the starting shape. `resolution` means: curves, the number of
/// vertices; sphere/ellipsoid, the icosphere subdivision level; box, grid cells per
/// unit length; torus, segments around the axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum InitialSpec {
    Circle(CircleShape),
    Ellipse(EllipseShape),
    Rectangle(RectangleShape),
    Polygon(PolygonShape),
    /// A film surface (stressed film): `y = height + amplitude·cos(2π mode x / L)`
    /// over one period, `resolution` vertices.
    Film(FilmShape),
    /// A film surface through the points (one period, `0 ≤ x < L`, in `+x`; it may
    /// overhang), resampled to `resolution` vertices if given.
    FilmPolyline(FilmPolylineShape),
    Union(UnionShape),
    Sphere(SphereShape),
    Ellipsoid(EllipsoidShape),
    Box(BoxShape),
    Torus(TorusShape),
    /// (Addition, segmentation) contours from the image itself, the default when
    /// `initial` is omitted: a threshold of the smoothed image (Otsu's unless
    /// `problem.threshold`, and `problem.dim_threshold` for dim objects), specks
    /// dropped, touching objects split, one closed curve (surface) per object and
    /// per hole (marching squares, marching tetrahedra); the inscribed circle
    /// (sphere) if it finds no object.
    Threshold(ThresholdShape),
    /// (Addition, segmentation) a grid of small circles, `spacing` pixels apart
    /// (default 1/8 of the image's shorter side), of radius `radius` pixels
    /// (default a quarter of the spacing).
    Seeds(SeedsShape),
    /// (Addition, segmentation) a circle (sphere) inscribed in the image box, two
    /// pixels inside it (the default initial shape of volumes).
    Inscribed(InscribedShape),
    /// An uploaded mesh: `"input:NAME"` (OBJ, OFF, STL or glTF; closed curves as
    /// OBJ `l` polylines or glTF `LINE_LOOP`s in the plane z = 0).
    Mesh(MeshShape),
}

// The fields of each variant of `InitialSpec`, as a struct of its own: a bad field is
// then located by deserializing its variant alone (see `spec::path`).

// `InitialSpec::Circle`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CircleShape {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
    #[serde(default = "curve_resolution")]
    #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
    pub resolution: usize,
}

// `InitialSpec::Ellipse`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EllipseShape {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
    pub semi_axes: [f64; 2],
    #[serde(default)]
    pub rotation: f64,
    #[serde(default = "curve_resolution")]
    #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
    pub resolution: usize,
}

// `InitialSpec::Rectangle`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RectangleShape {
    #[serde(default = "origin2")]
    pub center: [f64; 2],
    #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
    pub size: [f64; 2],
    #[serde(default = "curve_resolution")]
    #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
    pub resolution: usize,
}

// `InitialSpec::Polygon`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PolygonShape {
    pub points: Vec<[f64; 2]>,
    #[serde(default)]
    #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
    pub resolution: Option<usize>,
}

// `InitialSpec::Film`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FilmShape {
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub height: f64,
    #[serde(default)]
    pub amplitude: f64,
    #[serde(default = "film_mode")]
    #[schemars(range(min = 1))]
    pub mode: u32,
    #[serde(default = "film_resolution")]
    #[schemars(range(min = FILM_RESOLUTION.min, max = FILM_RESOLUTION.max))]
    pub resolution: usize,
}

// `InitialSpec::FilmPolyline`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FilmPolylineShape {
    #[schemars(length(min = 3))]
    pub points: Vec<[f64; 2]>,
    #[serde(default)]
    #[schemars(range(min = FILM_RESOLUTION.min, max = FILM_RESOLUTION.max))]
    pub resolution: Option<usize>,
}

// `InitialSpec::Union`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UnionShape {
    pub parts: Vec<InitialSpec>,
}

// `InitialSpec::Sphere`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereShape {
    #[serde(default = "origin3")]
    pub center: [f64; 3],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: f64,
    #[serde(default = "sphere_resolution")]
    #[schemars(range(max = SPHERE_LEVEL.max))]
    pub resolution: u32,
}

// `InitialSpec::Ellipsoid`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EllipsoidShape {
    #[serde(default = "origin3")]
    pub center: [f64; 3],
    #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
    pub semi_axes: [f64; 3],
    #[serde(default = "sphere_resolution")]
    #[schemars(range(max = SPHERE_LEVEL.max))]
    pub resolution: u32,
}

// `InitialSpec::Box`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxShape {
    #[serde(default = "origin3")]
    pub center: [f64; 3],
    #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
    pub size: [f64; 3],
    #[serde(default = "box_resolution")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub resolution: f64,
}

// `InitialSpec::Torus`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TorusShape {
    #[serde(default = "origin3")]
    pub center: [f64; 3],
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub major_radius: f64,
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub minor_radius: f64,
    #[serde(default = "torus_resolution")]
    #[schemars(range(min = TORUS_RESOLUTION.min, max = TORUS_RESOLUTION.max))]
    pub resolution: usize,
}

// `InitialSpec::Threshold`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThresholdShape {}

// `InitialSpec::Seeds`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SeedsShape {
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub spacing: Option<f64>,
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: Option<f64>,
}

// `InitialSpec::Inscribed`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InscribedShape {}

// `InitialSpec::Mesh`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshShape {
    #[schemars(regex(pattern = "^input:"))]
    pub file: String,
}
