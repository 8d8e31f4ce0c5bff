//! Reading an uploaded glTF 2.0 file (binary `.glb`, or `.gltf` JSON with its
//! buffers embedded as `data:` URIs) as the initial shape.
//!
//! The default scene (else the first, else every mesh untransformed) is walked
//! with the nodes' transforms applied. `TRIANGLES` primitives make a surface;
//! exporters split vertices at seams, so positions that are bit-identical after
//! the transform are merged, as for STL. `LINE_LOOP` primitives make closed curves
//! in the plane `z = 0` (the layout of our own `shape.glb`, so a result can start
//! a new job). Other modes, external buffers and sparse or non-float positions are
//! rejected with a message naming the input.

use super::build::{AnyMesh, MAX_VERTICES};
use super::mesh_io::{from_soup, MeshFileError};
use crate::geometry::{Mesh, Point};
use base64::Engine;
use gltf::mesh::Mode;
use nalgebra::{Matrix4, Point3};

fn content(name: &str, message: impl Into<String>) -> MeshFileError {
    MeshFileError::Content { name: name.into(), message: message.into() }
}

/// The bytes of every buffer of the document, in order.
fn buffers(name: &str, gltf: &gltf::Gltf) -> Result<Vec<Vec<u8>>, MeshFileError> {
    gltf.buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => gltf
                    .blob
                    .clone()
                    .ok_or_else(|| content(name, format!("buffer {} refers to a missing BIN chunk", b.index())))?,
                gltf::buffer::Source::Uri(uri) => {
                    let Some(encoded) = uri.strip_prefix("data:").and_then(|r| r.split_once(";base64,")).map(|(_, d)| d)
                    else {
                        return Err(content(
                            name,
                            format!(
                                "buffer {} is the external file {uri:?}; upload a .glb, or a .gltf with embedded (data:) buffers",
                                b.index()
                            ),
                        ));
                    };
                    base64::engine::general_purpose::STANDARD
                        .decode(encoded)
                        .map_err(|e| content(name, format!("buffer {}: bad base64 data URI: {e}", b.index())))?
                }
            };
            if data.len() < b.length() {
                return Err(content(name, format!("buffer {} has {} bytes, expected {}", b.index(), data.len(), b.length())));
            }
            Ok(data)
        })
        .collect()
}

/// What the primitives give: triangles (as coordinates) or closed loops.
#[derive(Default)]
struct Collected {
    soup: Vec<[Point<3>; 3]>,
    loops: Vec<Vec<Point<3>>>,
    count: usize,
}

fn collect(
    name: &str,
    mesh: gltf::Mesh,
    transform: &Matrix4<f64>,
    data: &[Vec<u8>],
    out: &mut Collected,
) -> Result<(), MeshFileError> {
    for (k, prim) in mesh.primitives().enumerate() {
        let what = format!("mesh {} primitive {k}", mesh.index());
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::LineLoop) {
            return Err(content(
                name,
                format!("{what}: mode {mode:?} is not supported (TRIANGLES for surfaces, LINE_LOOP for curves)"),
            ));
        }
        let Some(acc) = prim.get(&gltf::Semantic::Positions) else {
            return Err(content(name, format!("{what} has no POSITION attribute")));
        };
        if acc.sparse().is_some() || acc.view().is_none() {
            return Err(content(name, format!("{what}: sparse POSITION accessors are not supported")));
        }
        out.count += acc.count();
        if out.count > 3 * MAX_VERTICES {
            return Err(content(name, format!("more than {} vertex records", 3 * MAX_VERTICES)));
        }
        let reader = prim.reader(|b| data.get(b.index()).map(|d| d.as_slice()));
        let positions: Vec<Point<3>> = reader
            .read_positions()
            .ok_or_else(|| content(name, format!("{what}: POSITION must be float VEC3")))?
            .map(|p| {
                let q = transform.transform_point(&Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                Point::<3>::new(q.x, q.y, q.z)
            })
            .collect();
        let indices: Vec<usize> = match reader.read_indices() {
            Some(ix) => ix.into_u32().map(|i| i as usize).collect(),
            None => (0..positions.len()).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i >= positions.len()) {
            return Err(content(name, format!("{what}: index {bad} out of range (0..{})", positions.len())));
        }
        if !positions.iter().all(|p| p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(content(name, format!("{what}: a position is not finite")));
        }
        if mode == Mode::Triangles {
            if indices.len() % 3 != 0 {
                return Err(content(name, format!("{what}: {} indices is not a multiple of 3", indices.len())));
            }
            out.soup.extend(indices.chunks_exact(3).map(|t| [positions[t[0]], positions[t[1]], positions[t[2]]]));
        } else {
            if indices.len() < 3 {
                return Err(content(name, format!("{what}: a LINE_LOOP needs at least 3 vertices")));
            }
            out.loops.push(indices.iter().map(|&i| positions[i]).collect());
        }
    }
    Ok(())
}

fn matrix(node: &gltf::Node) -> Matrix4<f64> {
    let m = node.transform().matrix(); // column-major
    Matrix4::from_fn(|r, c| m[c][r] as f64)
}

fn walk(
    name: &str,
    node: gltf::Node,
    parent: &Matrix4<f64>,
    depth: usize,
    data: &[Vec<u8>],
    out: &mut Collected,
) -> Result<(), MeshFileError> {
    if depth > 64 {
        return Err(content(name, "the node hierarchy is deeper than 64 levels"));
    }
    let transform = parent * matrix(&node);
    if let Some(mesh) = node.mesh() {
        collect(name, mesh, &transform, data, out)?;
    }
    for child in node.children() {
        walk(name, child, &transform, depth + 1, data, out)?;
    }
    Ok(())
}

/// Read a glTF file (GLB or JSON) into a surface or a set of closed curves.
pub(super) fn read_gltf(name: &str, bytes: &[u8]) -> Result<AnyMesh, MeshFileError> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| content(name, format!("not a valid glTF file: {e}")))?;
    let data = buffers(name, &gltf)?;
    let mut out = Collected::default();
    let identity = Matrix4::identity();
    match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(scene) => {
            for node in scene.nodes() {
                walk(name, node, &identity, 0, &data, &mut out)?;
            }
        }
        None => {
            for mesh in gltf.meshes() {
                collect(name, mesh, &identity, &data, &mut out)?;
            }
        }
    }
    match (out.soup.is_empty(), out.loops.is_empty()) {
        (true, true) => Err(content(name, "the glTF file has no TRIANGLES or LINE_LOOP primitive")),
        (false, false) => Err(content(name, "the glTF file mixes triangles and line loops; upload one or the other")),
        (false, true) => from_soup(name, out.soup),
        (true, false) => curves(name, &out.loops),
    }
}

/// Closed curves from loops of points in the plane `z = 0`.
fn curves(name: &str, loops: &[Vec<Point<3>>]) -> Result<AnyMesh, MeshFileError> {
    let extent = loops.iter().flatten().fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
    if let Some(p) = loops.iter().flatten().find(|p| p.z.abs() > 1e-6 * extent.max(1e-300)) {
        return Err(content(name, format!("curve vertex ({}, {}, {}) is not in the plane z = 0", p.x, p.y, p.z)));
    }
    let mut positions = Vec::new();
    let mut elements = Vec::new();
    for l in loops {
        let first = positions.len();
        positions.extend(l.iter().map(|p| Point::<2>::new(p.x, p.y)));
        elements.extend((0..l.len()).map(|j| [first + j, first + (j + 1) % l.len()]));
    }
    if positions.len() > MAX_VERTICES {
        return Err(content(name, format!("more than {MAX_VERTICES} vertices")));
    }
    Mesh::new(positions, elements).map(AnyMesh::Curve).map_err(|error| MeshFileError::Mesh { name: name.into(), error })
}
