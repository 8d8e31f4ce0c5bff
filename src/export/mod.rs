//! Result formats (pure functions to strings/bytes): shape.json (docs/user-guide.md), the
//! energy history as CSV and as an SVG plot; masks and overlays of image jobs; glTF (.glb) shapes and evolutions;
//! VTK PolyData (.vtp) and time series (.pvd).

mod colors;
mod domain_node;
mod energy_csv;
mod energy_svg;
mod fill;
mod gltf;
mod image_results;
mod label_files;
mod objects;
mod shape_json;
mod vtk;
mod zip_files;

pub use domain_node::{DomainOutline, DOMAIN_NODE};
pub use energy_csv::energy_csv;
pub use energy_svg::energy_svg;
pub use fill::{region_triangles, ribbon, Filled};
pub use gltf::{evolution_glb, shape_glb, ColorField, GltfFrame, FRAME_SECONDS};
pub use image_results::{mask, mask_png, overlay_png, to_array_coordinates, to_pixel, to_world};
pub use label_files::{labels_tiff, rois_zip};
pub use objects::{labels_png, object_elements, objects, objects_csv, ObjectRow};
pub use shape_json::shape_json;
pub use vtk::{pvd, vtp, VtkCells, VtkPiece};
pub use zip_files::zip_files;

use crate::flow::MeshData;

/// A component `cycle` of a periodic curve (period `period` in `x`) lifted for
/// drawing: rotated to start at the vertex nearest `x ≡ 0`, and the `x` offset of
/// every vertex so that the component runs continuously from there. A component winding around the period is open:
/// its first vertex is appended again one period further (then `true`).
pub(crate) fn lift_component(m: &MeshData, cycle: &mut Vec<usize>, period: f64) -> (Vec<f64>, bool) {
    let x = |v: usize| m.positions[v][0];
    // start at the vertex nearest the left wall (for winding components the strip
    // then spans about 0 ≤ x ≤ L)
    let first =
        (0..cycle.len()).min_by(|&a, &b| x(cycle[a]).rem_euclid(period).total_cmp(&x(cycle[b]).rem_euclid(period)));
    cycle.rotate_left(first.unwrap_or(0));
    let mut dx = vec![x(cycle[0]).rem_euclid(period) - x(cycle[0])];
    for k in 1..cycle.len() {
        let prev = x(cycle[k - 1]) + dx[k - 1];
        dx.push(period * ((prev - x(cycle[k])) / period).round());
    }
    let last = x(cycle[cycle.len() - 1]) + dx[cycle.len() - 1];
    let closing = period * ((last - x(cycle[0])) / period).round();
    let winds = (closing - dx[0]).abs() > 0.5 * period;
    if winds {
        dx.push(closing);
        cycle.push(cycle[0]);
    }
    (dx, winds)
}
