//! Building a shape-design problem from its spec: the boundary polygons of `Σ` and
//! `∂D` at the requested spacing, the target, the bulk meshing options, and the
//! admissibility of the initial curve.

use super::checks::{finite, positive};
use crate::bulk::{BulkError, DesignDomain, MeshingOptions, Polygon};
use crate::geometry::{self, CurveMesh, Point};
use crate::jobs::spec::{
    BoundarySpec, CircleBoundary, ConstantTarget, LogRadialTarget, PolarTarget, PolygonBoundary, ShapeDesignSpec,
    SpecError, SquareBoundary, TargetSpec,
};
use crate::problems::{ShapeDesign, Target};
use std::sync::Arc;

/// Most vertices a fixed boundary may have.
use crate::limits::MAX_BOUNDARY_VERTICES;

fn count(field: &str, length: f64, h: f64) -> Result<usize, SpecError> {
    let n = (length / h).ceil();
    if n > MAX_BOUNDARY_VERTICES as f64 {
        return Err(SpecError::new(
            field,
            format!("needs {n:.0} vertices at this spacing, more than {MAX_BOUNDARY_VERTICES}"),
        ));
    }
    Ok(n as usize)
}

/// The perimeter of a boundary spec (for the default spacing).
fn perimeter(b: &BoundarySpec) -> f64 {
    match b {
        BoundarySpec::Circle(CircleBoundary { radius, .. }) => std::f64::consts::TAU * radius,
        BoundarySpec::Square(SquareBoundary { size, .. }) => 4.0 * size,
        BoundarySpec::Polygon(PolygonBoundary { points }) => {
            let n = points.len();
            (0..n).map(|i| (Point::<2>::from(points[(i + 1) % n]) - Point::<2>::from(points[i])).norm()).sum()
        }
    }
}

/// The polygon of a boundary spec with vertices about `h` apart (at least 16 on a
/// circle; squares and polygons keep their corners).
fn polygon(field: &str, b: &BoundarySpec, h: f64) -> Result<Polygon, SpecError> {
    let curve = match b {
        BoundarySpec::Circle(CircleBoundary { center, radius }) => {
            finite(&format!("{field}.center"), center)?;
            let r = positive(&format!("{field}.radius"), *radius)?;
            geometry::circle(*center, r, count(field, perimeter(b), h)?.max(16))
        }
        BoundarySpec::Square(SquareBoundary { center, size }) => {
            finite(&format!("{field}.center"), center)?;
            let s = positive(&format!("{field}.size"), *size)?;
            geometry::rectangle(*center, [s, s], count(field, perimeter(b), h)?.max(4))
        }
        BoundarySpec::Polygon(PolygonBoundary { points }) => {
            if points.len() < 3 {
                return Err(SpecError::new(
                    format!("{field}.points"),
                    format!("needs at least 3 points, got {}", points.len()),
                ));
            }
            for (i, p) in points.iter().enumerate() {
                finite(&format!("{field}.points[{i}]"), p)?;
            }
            let pts: Vec<Point<2>> = points.iter().map(|p| Point::<2>::from(*p)).collect();
            geometry::polygon(&pts, Some(count(field, perimeter(b), h)?))
        }
    };
    Polygon::from_curve(field, curve).map_err(|e| match e {
        BulkError::Domain { message, .. } => SpecError::new(field, message),
        other => SpecError::new(field, other.to_string()),
    })
}

fn bulk_error(e: BulkError) -> SpecError {
    match e {
        BulkError::Domain { what, message } => SpecError::new(format!("problem.{what}"), message),
        other => SpecError::new("problem", other.to_string()),
    }
}

fn target(spec: &TargetSpec, domain: &DesignDomain) -> Result<Target, SpecError> {
    let centre_outside_d = |c: &[f64; 2]| -> Result<Point<2>, SpecError> {
        finite("problem.target.center", c)?;
        let p = Point::<2>::from(*c);
        if domain.in_control(p) {
            return Err(SpecError::new(
                "problem.target.center",
                "must not lie in the control region (z_g is singular there)",
            ));
        }
        Ok(p)
    };
    Ok(match spec {
        TargetSpec::Constant(ConstantTarget { value }) => {
            finite("problem.target.value", &[*value])
                .map_err(|_| SpecError::new("problem.target.value", "must be a finite number"))?;
            Target::Constant(*value)
        }
        TargetSpec::LogRadial(LogRadialTarget { center, radius }) => {
            let center = centre_outside_d(center)?;
            Target::LogRadial { center, radius: positive("problem.target.radius", *radius)? }
        }
        TargetSpec::Polar(PolarTarget { center, a, b, k }) => {
            let center = centre_outside_d(center)?;
            for (name, v) in [("a", a), ("b", b), ("k", k)] {
                if !v.is_finite() {
                    return Err(SpecError::new(format!("problem.target.{name}"), "must be a finite number"));
                }
            }
            Target::Polar { center, a: *a, b: *b, k: *k }
        }
    })
}

/// The shape-design problem of a spec, for the initial curve `initial`, with merging
/// of crossing curves when `merge` (topology changes on) and loops below `min_area`
/// dropped. The initial curve must be admissible.
pub fn shape_design(
    spec: &ShapeDesignSpec,
    initial: &CurveMesh,
    merge: bool,
    min_area: f64,
) -> Result<ShapeDesign, SpecError> {
    let gamma = spec.gamma;
    if !(gamma.is_finite() && gamma >= 0.0) {
        return Err(SpecError::new("problem.gamma", format!("must be a nonnegative number, got {gamma}")));
    }
    let h = match spec.spacing {
        Some(h) => positive("problem.spacing", h)?,
        None => perimeter(&spec.outer) / 200.0,
    };
    if !(h.is_finite() && h > 0.0) {
        // name the bad radius or size when there is one
        match &spec.outer {
            BoundarySpec::Circle(CircleBoundary { radius, .. }) => positive("problem.outer.radius", *radius)?,
            BoundarySpec::Square(SquareBoundary { size, .. }) => positive("problem.outer.size", *size)?,
            BoundarySpec::Polygon(PolygonBoundary { .. }) => 0.0,
        };
        return Err(SpecError::new("problem.outer", "has no length, or one too large to sample"));
    }
    let outer = polygon("problem.outer", &spec.outer, h)?;
    let inner_d = polygon("problem.control.inner", &spec.control.inner, h)?;
    let outer_d = polygon("problem.control.outer", &spec.control.outer, h)?;
    let domain = DesignDomain::new(outer, inner_d, outer_d).map_err(bulk_error)?;
    let target = target(&spec.target, &domain)?;
    let mean_edge = initial.boundary_measure() / initial.num_elements() as f64;
    let meshing = MeshingOptions::for_domain(&domain, mean_edge);
    let mut problem = ShapeDesign::new(Arc::new(domain), target, gamma, merge, min_area, meshing);
    problem.gradient = spec.gradient;
    match problem.start().solve(initial) {
        Ok(_) => Ok(problem),
        Err(BulkError::Inadmissible(m)) => {
            Err(SpecError::new("initial", format!("not admissible for shape design: {m}")))
        }
        Err(e) => Err(SpecError::new("problem", e.to_string())),
    }
}
