//! Reading an uploaded glTF 2.0 file (binary `.glb`, or `.gltf` JSON with its
//! buffers embedded as `data:` URIs) as the initial shape.
//!
//! The default scene (else the first, else every mesh untransformed) is walked
//! with the nodes' transforms applied. `TRIANGLES` primitives make a surface;
//! exporters split vertices at seams, so positions that are bit-identical after
//! the transform are merged, as for STL. `LINE_LOOP` primitives make closed curves
//! in the plane `z = 0` (the layout of our own `shape.glb`, so a result can start
//! a new job). Other modes, external buffers, sparse accessors, positions that are
//! not float `VEC3`, indices that are not unsigned integers, strides or ranges that
//! leave their buffer view, and node graphs that are not trees are rejected with a
//! message naming the input. The gltf crate parses and validates the JSON; the
//! accessors are read here, bounds-checked, under a budget of vertex records that
//! counts every instance of a mesh.

use super::soup::{from_soup, MeshFileError};
use crate::geometry::{AnyMesh, Mesh, Point};
use crate::limits::MAX_VERTICES;
use base64::Engine;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use nalgebra::{Matrix4, Point3};
use std::borrow::Cow;

/// Most position and index records read, over every instance of every mesh.
const MAX_RECORDS: usize = 3 * MAX_VERTICES;

fn content(name: &str, message: impl Into<String>) -> MeshFileError {
    MeshFileError::Content { name: name.into(), message: message.into() }
}

/// The bytes of every buffer of the document, in order (the BIN chunk borrowed).
fn buffers<'a>(name: &str, gltf: &'a gltf::Gltf) -> Result<Vec<Cow<'a, [u8]>>, MeshFileError> {
    gltf.buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => Cow::Borrowed(
                    gltf.blob
                        .as_deref()
                        .ok_or_else(|| content(name, format!("buffer {} refers to a missing BIN chunk", b.index())))?,
                ),
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
                    Cow::Owned(
                        base64::engine::general_purpose::STANDARD
                            .decode(encoded)
                            .map_err(|e| content(name, format!("buffer {}: bad base64 data URI: {e}", b.index())))?,
                    )
                }
            };
            if data.len() < b.length() {
                return Err(content(name, format!("buffer {} has {} bytes, expected {}", b.index(), data.len(), b.length())));
            }
            Ok(data)
        })
        .collect()
}

/// The records of an accessor: `count` slices of `size` bytes, checked to lie in
/// its buffer view and buffer.
fn records<'d>(
    name: &str,
    what: &str,
    acc: &gltf::Accessor,
    size: usize,
    data: &'d [Cow<[u8]>],
) -> Result<impl Iterator<Item = &'d [u8]>, MeshFileError> {
    let fail = |m: String| content(name, format!("{what}: accessor {}: {m}", acc.index()));
    if acc.sparse().is_some() {
        return Err(fail("sparse accessors are not supported".into()));
    }
    let view = acc.view().ok_or_else(|| fail("it has no buffer view".into()))?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(fail(format!("byte stride {stride} is smaller than an element ({size} bytes)")));
    }
    let buffer = data.get(view.buffer().index()).ok_or_else(|| fail("its buffer is missing".into()))?;
    let view_end = view.offset().checked_add(view.length()).filter(|&e| e <= buffer.len());
    let start = view.offset().checked_add(acc.offset());
    let end = match acc.count().checked_sub(1) {
        None => start,
        Some(last) => start.and_then(|s| last.checked_mul(stride)?.checked_add(size)?.checked_add(s)),
    };
    let (Some(view_end), Some(start), Some(end)) = (view_end, start, end) else {
        return Err(fail("its range overflows".into()));
    };
    if end > view_end {
        return Err(fail(format!("its {} elements run past the end of buffer view {}", acc.count(), view.index())));
    }
    Ok((0..acc.count()).map(move |i| &buffer[start + i * stride..start + i * stride + size]))
}

/// What the primitives give: triangles (as coordinates) or closed loops.
#[derive(Default)]
struct Collected {
    soup: Vec<[Point<3>; 3]>,
    loops: Vec<Vec<Point<3>>>,
    /// Position and index records read so far.
    records: usize,
}

impl Collected {
    fn spend(&mut self, name: &str, n: usize) -> Result<(), MeshFileError> {
        self.records = self.records.saturating_add(n);
        if self.records > MAX_RECORDS {
            return Err(content(name, format!("more than {MAX_RECORDS} position and index records")));
        }
        Ok(())
    }
}

fn collect(
    name: &str,
    mesh: gltf::Mesh,
    transform: &Matrix4<f64>,
    data: &[Cow<[u8]>],
    out: &mut Collected,
) -> Result<(), MeshFileError> {
    for (k, prim) in mesh.primitives().enumerate() {
        out.spend(name, 1)?;
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
        if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 || acc.normalized() {
            return Err(content(name, format!("{what}: POSITION must be a float VEC3 accessor")));
        }
        out.spend(name, acc.count())?;
        let positions = records(name, &what, &acc, 12, data)?
            .map(|r| {
                let c = |j: usize| f32::from_le_bytes([r[j], r[j + 1], r[j + 2], r[j + 3]]) as f64;
                let q = transform.transform_point(&Point3::new(c(0), c(4), c(8)));
                Point::<3>::new(q.x, q.y, q.z)
            })
            .collect::<Vec<_>>();
        let indices: Vec<usize> = match prim.indices() {
            Some(ix) => {
                let size = match (ix.data_type(), ix.dimensions()) {
                    (DataType::U8, Dimensions::Scalar) => 1,
                    (DataType::U16, Dimensions::Scalar) => 2,
                    (DataType::U32, Dimensions::Scalar) => 4,
                    _ => return Err(content(name, format!("{what}: indices must be unsigned integer scalars"))),
                };
                out.spend(name, ix.count())?;
                records(name, &what, &ix, size, data)?
                    .map(|r| match r.len() {
                        1 => r[0] as usize,
                        2 => u16::from_le_bytes([r[0], r[1]]) as usize,
                        _ => u32::from_le_bytes([r[0], r[1], r[2], r[3]]) as usize,
                    })
                    .collect()
            }
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

/// Visits the scene's nodes and their descendants, each at most once (glTF's nodes
/// form trees, so a node met twice is an error, not a reason to loop), with an
/// explicit stack (a chain of 100k nodes must not overflow the thread's).
fn walk(
    name: &str,
    scene: gltf::Scene,
    nodes: usize,
    data: &[Cow<[u8]>],
    out: &mut Collected,
) -> Result<(), MeshFileError> {
    let mut seen = vec![false; nodes];
    let mut stack: Vec<(gltf::Node, Matrix4<f64>)> = scene.nodes().map(|n| (n, Matrix4::identity())).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            let i = node.index();
            return Err(content(name, format!("node {i} is reached twice: the node hierarchy must be a tree")));
        }
        out.spend(name, 1)?;
        let transform = parent * matrix(&node);
        if let Some(mesh) = node.mesh().filter(|_| !display_only(&node)) {
            collect(name, mesh, &transform, data, out)?;
        }
        stack.extend(node.children().map(|c| (c, transform)));
    }
    Ok(())
}

/// Whether `node` is marked as drawing only (`"extras": {"shapeflow": "display"}`:
/// the filled region and ribbons that shapeflow adds to 2D results); its mesh is
/// not part of the shape.
fn display_only(node: &gltf::Node) -> bool {
    node.extras()
        .as_ref()
        .is_some_and(|e| serde_json::from_str::<serde_json::Value>(e.get()).is_ok_and(|v| v["shapeflow"] == "display"))
}

/// Most bytes of a glTF JSON outside its strings (a mesh's document is a few
/// kilobytes; the data lives in buffers or in base64 strings).
const MAX_STRUCTURE: usize = 1 << 20;

/// Cheap checks of the JSON before the gltf crate parses and validates it, whose
/// memory and time grow with the number of objects and, per primitive, with the
/// length of the accessors' `min`/`max`.
fn precheck(name: &str, bytes: &[u8]) -> Result<(), MeshFileError> {
    let glb;
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        // the crate subtracts the header's size from the declared length unchecked
        let declared = bytes.get(8..12).map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]));
        if declared.is_none_or(|l| l < 12) {
            return Err(content(name, "not a valid glTF binary (.glb) file: its header is cut short"));
        }
        glb = gltf::binary::Glb::from_slice(bytes)
            .map_err(|e| content(name, format!("not a valid glTF binary (.glb) file: {e}")))?;
        &glb.json
    } else {
        bytes
    };
    let (mut in_string, mut escaped, mut structure) = (false, false, 0usize);
    for &b in json {
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_string = false,
                _ => {}
            }
        } else {
            structure += 1;
            in_string = b == b'"';
        }
    }
    if structure > MAX_STRUCTURE {
        return Err(content(name, format!("the glTF JSON has more than {MAX_STRUCTURE} bytes outside its strings")));
    }
    let doc: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| content(name, format!("not a valid glTF file: {e}")))?;
    let long_bounds = doc["accessors"].as_array().into_iter().flatten().position(|a| {
        ["min", "max"].iter().any(|k| a.get(*k).and_then(|v| v.as_array()).is_some_and(|v| v.len() > 16))
    });
    if let Some(i) = long_bounds {
        return Err(content(name, format!("accessor {i}: `min`/`max` have more than 16 entries")));
    }
    Ok(())
}

/// The start of a long message (gltf lists every validation error).
fn shortened(message: String) -> String {
    const MAX: usize = 400;
    match message.char_indices().nth(MAX) {
        Some((cut, _)) => format!("{} … ({} more bytes)", &message[..cut], message.len() - cut),
        None => message,
    }
}

/// Read a glTF file (GLB or JSON) into a surface or a set of closed curves.
pub(super) fn read_gltf(name: &str, bytes: &[u8]) -> Result<AnyMesh, MeshFileError> {
    precheck(name, bytes)?;
    // the crate's validation indexes some arrays before checking the indices
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::from_slice(bytes))
        .map_err(|_| content(name, "not a valid glTF file: an index in it is out of range"))?;
    let gltf = parsed.map_err(|e| content(name, shortened(format!("not a valid glTF file: {e}"))))?;
    let data = buffers(name, &gltf)?;
    let mut out = Collected::default();
    match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(scene) => walk(name, scene, gltf.nodes().len(), &data, &mut out)?,
        None => {
            for mesh in gltf.meshes() {
                collect(name, mesh, &Matrix4::identity(), &data, &mut out)?;
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
