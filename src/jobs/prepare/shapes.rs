//! `initial`: the explicit starting shapes (circles to tori, polygons, unions and
//! uploaded mesh files).

use super::checks::{curve, finite, positive, surface};
use super::inputs::input;
use crate::formats::read_mesh_file;
use crate::geometry::{self, AnyMesh, Point};
use crate::jobs::spec::bounds::{CURVE_RESOLUTION, SPHERE_LEVEL, TORUS_RESOLUTION};
use crate::jobs::spec::{
    BoxShape, CircleShape, EllipseShape, EllipsoidShape, FilmPolylineShape, FilmShape, InitialSpec, InscribedShape,
    MeshShape, PolygonShape, RectangleShape, SeedsShape, SpecError, SphereShape, ThresholdShape, TorusShape,
    UnionShape,
};
use crate::limits::MAX_VERTICES;
use std::collections::HashMap;

pub(super) fn build_initial(
    field: &str,
    s: &InitialSpec,
    inputs: &HashMap<String, Vec<u8>>,
) -> Result<AnyMesh, SpecError> {
    let at = |name: &str| format!("{field}.{name}");
    let curve_res = |r: usize| CURVE_RESOLUTION.check(&at("resolution"), r);
    match s {
        InitialSpec::Circle(CircleShape { center, radius, resolution }) => {
            finite(&at("center"), center)?;
            let r = positive(&at("radius"), *radius)?;
            curve(field, geometry::circle(*center, r, curve_res(*resolution)?))
        }
        InitialSpec::Ellipse(EllipseShape { center, semi_axes, rotation, resolution }) => {
            finite(&at("center"), center)?;
            positive(&at("semi_axes[0]"), semi_axes[0])?;
            positive(&at("semi_axes[1]"), semi_axes[1])?;
            finite(&at("rotation"), &[*rotation])?;
            curve(field, geometry::ellipse(*center, *semi_axes, *rotation, curve_res(*resolution)?))
        }
        InitialSpec::Rectangle(RectangleShape { center, size, resolution }) => {
            finite(&at("center"), center)?;
            positive(&at("size[0]"), size[0])?;
            positive(&at("size[1]"), size[1])?;
            curve(field, geometry::rectangle(*center, *size, curve_res(*resolution)?.max(4)))
        }
        InitialSpec::Polygon(PolygonShape { points, resolution }) => {
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
        InitialSpec::Union(UnionShape { parts }) => {
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
                return surface(field, geometry::surface_union(&surfaces));
            }
            curve(field, geometry::union(&curves))
        }
        InitialSpec::Sphere(SphereShape { center, radius, resolution }) => {
            finite(&at("center"), center)?;
            let r = positive(&at("radius"), *radius)?;
            surface(field, geometry::icosphere(*center, r, SPHERE_LEVEL.check(&at("resolution"), *resolution)?))
        }
        InitialSpec::Ellipsoid(EllipsoidShape { center, semi_axes, resolution }) => {
            finite(&at("center"), center)?;
            for (i, a) in semi_axes.iter().enumerate() {
                positive(&format!("{field}.semi_axes[{i}]"), *a)?;
            }
            surface(
                field,
                geometry::ellipsoid(*center, *semi_axes, SPHERE_LEVEL.check(&at("resolution"), *resolution)?),
            )
        }
        InitialSpec::Box(BoxShape { center, size, resolution }) => {
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
        InitialSpec::Torus(TorusShape { center, major_radius, minor_radius, resolution }) => {
            finite(&at("center"), center)?;
            let big = positive(&at("major_radius"), *major_radius)?;
            let small = positive(&at("minor_radius"), *minor_radius)?;
            if small >= big {
                return Err(SpecError::new(at("minor_radius"), "must be smaller than major_radius"));
            }
            let n = TORUS_RESOLUTION.check(&at("resolution"), *resolution)?;
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
        InitialSpec::Film(FilmShape { .. }) | InitialSpec::FilmPolyline(FilmPolylineShape { .. }) => {
            Err(SpecError::new(at("shape"), "film shapes are for problem.type `stressed_film`"))
        }
        InitialSpec::Threshold(ThresholdShape {})
        | InitialSpec::Seeds(SeedsShape { .. })
        | InitialSpec::Inscribed(InscribedShape {}) => {
            Err(SpecError::new(at("shape"), "this shape comes from an image: it needs problem.type `segmentation`"))
        }
        InitialSpec::Mesh(MeshShape { file }) => {
            let (name, bytes) = input(&at("file"), file, inputs)?;
            read_mesh_file(name, bytes).map_err(|e| SpecError::new(at("file"), e.to_string()))
        }
    }
}
