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
    Circle {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: f64,
        #[serde(default = "curve_resolution")]
        #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
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
        #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
        resolution: usize,
    },
    Rectangle {
        #[serde(default = "origin2")]
        center: [f64; 2],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        size: [f64; 2],
        #[serde(default = "curve_resolution")]
        #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
        resolution: usize,
    },
    Polygon {
        points: Vec<[f64; 2]>,
        #[serde(default)]
        #[schemars(range(min = CURVE_RESOLUTION.min, max = CURVE_RESOLUTION.max))]
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
        #[schemars(range(min = FILM_RESOLUTION.min, max = FILM_RESOLUTION.max))]
        resolution: usize,
    },
    /// A film surface through the points (one period, `0 ≤ x < L`, in `+x`; it may
    /// overhang), resampled to `resolution` vertices if given.
    FilmPolyline {
        #[schemars(length(min = 3))]
        points: Vec<[f64; 2]>,
        #[serde(default)]
        #[schemars(range(min = FILM_RESOLUTION.min, max = FILM_RESOLUTION.max))]
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
        #[schemars(range(max = SPHERE_LEVEL.max))]
        resolution: u32,
    },
    Ellipsoid {
        #[serde(default = "origin3")]
        center: [f64; 3],
        #[schemars(extend("items" = {"type": "number", "format": "double", "exclusiveMinimum": 0}))]
        semi_axes: [f64; 3],
        #[serde(default = "sphere_resolution")]
        #[schemars(range(max = SPHERE_LEVEL.max))]
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
        #[schemars(range(min = TORUS_RESOLUTION.min, max = TORUS_RESOLUTION.max))]
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
