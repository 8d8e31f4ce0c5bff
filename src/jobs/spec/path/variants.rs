//! The struct of every variant of the spec's tagged enums, by the enum's name in the
//! schema and the variant's tag.

use super::{error_of, Step};
use crate::jobs::spec::*;
use serde_json::Value;

/// The error of `fields` (a tagged object without its tag) as the struct of
/// variant `tag` of `definition`: `Some(None)` if it has none, `None` if the pair
/// names no variant.
#[allow(clippy::type_complexity)]
pub(super) fn error(definition: &str, tag: &str, fields: &Value) -> Option<Option<(Vec<Step>, String)>> {
    Some(match (definition, tag) {
        ("ProblemSpec", "curvature_flow") => error_of::<CurvatureFlowSpec>(fields),
        ("ProblemSpec", "surface_diffusion") => error_of::<SurfaceDiffusionSpec>(fields),
        ("ProblemSpec", "segmentation") => error_of::<SegmentationSpec>(fields),
        ("ProblemSpec", "shape_design") => error_of::<ShapeDesignSpec>(fields),
        ("ProblemSpec", "stressed_film") => error_of::<StressedFilmSpec>(fields),
        ("InitialSpec", "circle") => error_of::<CircleShape>(fields),
        ("InitialSpec", "ellipse") => error_of::<EllipseShape>(fields),
        ("InitialSpec", "rectangle") => error_of::<RectangleShape>(fields),
        ("InitialSpec", "polygon") => error_of::<PolygonShape>(fields),
        ("InitialSpec", "film") => error_of::<FilmShape>(fields),
        ("InitialSpec", "film_polyline") => error_of::<FilmPolylineShape>(fields),
        ("InitialSpec", "union") => error_of::<UnionShape>(fields),
        ("InitialSpec", "sphere") => error_of::<SphereShape>(fields),
        ("InitialSpec", "ellipsoid") => error_of::<EllipsoidShape>(fields),
        ("InitialSpec", "box") => error_of::<BoxShape>(fields),
        ("InitialSpec", "torus") => error_of::<TorusShape>(fields),
        ("InitialSpec", "threshold") => error_of::<ThresholdShape>(fields),
        ("InitialSpec", "seeds") => error_of::<SeedsShape>(fields),
        ("InitialSpec", "inscribed") => error_of::<InscribedShape>(fields),
        ("InitialSpec", "mesh") => error_of::<MeshShape>(fields),
        ("BoundarySpec", "circle") => error_of::<CircleBoundary>(fields),
        ("BoundarySpec", "square") => error_of::<SquareBoundary>(fields),
        ("BoundarySpec", "polygon") => error_of::<PolygonBoundary>(fields),
        ("TargetSpec", "constant") => error_of::<ConstantTarget>(fields),
        ("TargetSpec", "log_radial") => error_of::<LogRadialTarget>(fields),
        ("TargetSpec", "polar") => error_of::<PolarTarget>(fields),
        ("FilmBoundarySpec", "x") => error_of::<XBoundary>(fields),
        ("FilmBoundarySpec", "constant") => error_of::<ConstantBoundary>(fields),
        ("FilmBoundarySpec", "linear") => error_of::<LinearBoundary>(fields),
        _ => return None,
    })
}
