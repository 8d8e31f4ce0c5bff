//! The VTK files of a run, for ParaView, PyVista and meshio: `shape.vtp` of the
//! state the results show and the time series `evolution.pvd` of every frame
//! (`evolution/frame_00000.vtp`, …), which the service stores as one zip
//! (`evolution_vtk.zip`). Image jobs' points are in the image's physical space
//! ([`to_world`]), the others' in the job's own coordinates.

use super::frames::Frame;
use super::PreparedJob;
pub use crate::export::zip_files;
use crate::export::{pvd, to_world, vtp, VtkCells, VtkPiece};
use crate::geometry::components;

/// The name of the zip of the time series among the result files.
pub const EVOLUTION_VTK_ZIP: &str = "evolution_vtk.zip";

/// The point-data name of a glTF attribute name (`_EDGE_INDICATOR` → `edge_indicator`).
fn field_name(gltf: &str) -> String {
    gltf.trim_start_matches('_').to_ascii_lowercase()
}

/// The `.vtp` of one frame: the curve's segments (a periodic curve without the
/// segments that close it around its period) or the surface's triangles, with the
/// frame's curvature, normal velocity and the problem's own field as point data
/// and each cell's component as cell data.
pub fn frame_vtp(job: &PreparedJob, frame: &Frame) -> Vec<u8> {
    let mesh = &frame.state.mesh;
    let image = job.image.as_deref();
    let points: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|p| match image {
            Some(img) => to_world(img, p),
            None => [p[0], p.get(1).copied().unwrap_or(0.0), p.get(2).copied().unwrap_or(0.0)],
        })
        .collect();
    let wraps = |e: &[usize]| {
        mesh.period.is_some_and(|period| (mesh.positions[e[0]][0] - mesh.positions[e[1]][0]).abs() > 0.5 * period)
    };
    let cells: Vec<&[usize]> = mesh.elements.iter().map(|e| e.as_slice()).filter(|e| !wraps(e)).collect();
    let n = mesh.positions.len();
    let labels = if mesh.dimension == 2 {
        let segments: Vec<[usize; 2]> = mesh.elements.iter().map(|e| [e[0], e[1]]).collect();
        components(n, &segments).0
    } else {
        let triangles: Vec<[usize; 3]> = mesh.elements.iter().map(|e| [e[0], e[1], e[2]]).collect();
        components(n, &triangles).0
    };
    let component = cells.iter().map(|c| labels.get(c[0]).map_or(0, |&l| l as i32)).collect();
    let mut point_data = Vec::new();
    if let Some(f) = &frame.fields {
        point_data.push(("curvature".to_string(), f.curvature.as_slice()));
        point_data.push(("normal_velocity".to_string(), f.normal_velocity.as_slice()));
        if let Some((name, values)) = &f.own {
            point_data.push((field_name(name), values.as_slice()));
        }
    }
    let piece = VtkPiece {
        points,
        cells,
        kind: if mesh.dimension == 2 { VtkCells::Lines } else { VtkCells::Polys },
        point_data,
        cell_data: vec![("component".to_string(), component)],
    };
    vtp(&piece)
}

/// The time series of `frames`: `evolution.pvd` first, then one
/// `evolution/frame_NNNNN.vtp` per frame, each at its flow time (names relative to
/// the directory the `.pvd` is in).
pub fn vtk_series(job: &PreparedJob, frames: &[Frame]) -> Vec<(String, Vec<u8>)> {
    let names: Vec<String> = (0..frames.len()).map(|k| format!("evolution/frame_{k:05}.vtp")).collect();
    let steps: Vec<(f64, String)> = frames.iter().zip(&names).map(|(f, n)| (f.state.time, n.clone())).collect();
    let mut files = vec![("evolution.pvd".to_string(), pvd(&steps))];
    files.extend(names.into_iter().zip(frames).map(|(name, f)| (name, frame_vtp(job, f))));
    files
}
