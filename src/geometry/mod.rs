//! Geometry: meshes of closed curves (`D = 2`) and closed surfaces (`D = 3`), their
//! validated constructors, built-in shapes and measures. Topology (the element list)
//! is kept apart from positions; derived quantities are computed on request.

mod any_mesh;
mod boxes;
mod component_crossings;
pub use component_crossings::SweptSegments;
mod crossing_watch;
mod curve_loop;
pub use any_mesh::AnyMesh;
pub use boxes::{bounding_box, boxes_meet, in_box, BoxGrid, Rect};
pub use curve_loop::loop_area;
mod curve_pass;
mod curve_remesh;
mod curve_topology;
mod curves;
pub mod distance;
mod intersect;
mod measures;
mod mesh;
mod neck_cut;
mod objects;
mod patch_search;
pub use patch_search::PatchSearch;
pub mod simplex;
mod surface_gap;
pub use surface_gap::curved_sheet_gap;
mod surface_intersections;
mod surface_remesh;
mod surface_revert;
mod surface_watch;
mod surface_zip;
pub use surface_watch::{swept_surface_intersections, SurfaceWatch};
pub use surface_zip::{closest_facing_vertices, zip_sheets};
mod surfaces;
#[cfg(test)]
mod test_numbers;
mod unions;
mod validate;
mod winding;
pub use validate::degenerate_measure;

pub use crossing_watch::CrossingWatch;
pub use curve_pass::{manage_curve, manage_curve_holding, Hold};
pub use curve_remesh::{adapt_curve, regularize_curve, CurveRemeshSettings};
pub use curve_topology::{resolve_crossings, resolve_intersections};
pub use curves::{all_loops_below, circle, curves_from_loops, drop_small_loops, ellipse, polygon, rectangle};
pub use intersect::{find_periodic_intersections, find_segment_intersections, segment_pair_hit, SegmentHit};
pub use measures::{vertex_normals, MeshQuality};
pub use mesh::{components, segment_cycles, CurveMesh, Mesh, MeshError, SurfaceMesh};
pub use neck_cut::cut_neck;
pub use objects::Objects;
pub use surface_intersections::{first_surface_intersection, surface_intersections};
pub use surface_remesh::{
    adapt_surface, adapt_surface_except, edge_statistics, freeze_around, regularize_surface, surface_edges,
    SurfaceEdge, SurfaceRemeshSettings,
};
pub use surface_revert::revert_new_intersections;
pub use surfaces::{box_surface, ellipsoid, icosphere, torus};
pub use unions::{surface_union, union};
pub use winding::{mesh_winding_number, winding_number};

/// A point of `R^D`.
pub type Point<const D: usize> = nalgebra::SVector<f64, D>;
