//! The glTF document and its binary buffer as they are built: buffer views,
//! accessors with exact bounds, and the GLB container. The arrays of the views are
//! kept as they are given and written once, into the container, when it is made.

use super::document::{materials, Accessor, Document, MeshDoc, Primitive, View};
use serde_json::{json, Value};

pub(super) const ARRAY_BUFFER: u32 = 34962;
pub(super) const ELEMENT_ARRAY_BUFFER: u32 = 34963;
pub(super) const FLOAT: u32 = 5126;
pub(super) const UNSIGNED_INT: u32 = 5125;

/// The array of one buffer view (4-byte values: every view starts on a 4-byte
/// boundary without padding).
enum Piece {
    Floats(Vec<f32>),
    Indices(Vec<u32>),
}

#[derive(Default)]
pub(super) struct Builder {
    /// The binary chunk's arrays, in order.
    pieces: Vec<Piece>,
    /// Their bytes so far.
    bin_len: usize,
    views: Vec<View>,
    accessors: Vec<Accessor>,
    meshes: Vec<MeshDoc>,
    /// The frame nodes and the domain's (the scene's roots).
    pub(super) nodes: Vec<Value>,
    /// Their children (filled regions), placed after them in `finish`.
    pub(super) children: Vec<Value>,
}

impl Builder {
    /// A buffer view of `piece`, appended to the binary chunk; returns its index.
    fn view(&mut self, target: Option<u32>, piece: Piece) -> usize {
        let bytes = 4 * match &piece {
            Piece::Floats(v) => v.len(),
            Piece::Indices(v) => v.len(),
        };
        self.views.push(View { buffer: 0, byte_offset: self.bin_len, byte_length: bytes, target });
        self.bin_len += bytes;
        self.pieces.push(piece);
        self.views.len() - 1
    }

    /// A float accessor of `kind` (`SCALAR`, `VEC3`) with exact min/max.
    pub(super) fn floats(&mut self, data: Vec<f32>, kind: &'static str, target: Option<u32>) -> usize {
        let comps = if kind == "VEC3" { 3 } else { 1 };
        let count = data.len() / comps;
        let mut lo = vec![f64::INFINITY; comps];
        let mut hi = vec![f64::NEG_INFINITY; comps];
        for (i, &x) in data.iter().enumerate() {
            lo[i % comps] = lo[i % comps].min(f64::from(x));
            hi[i % comps] = hi[i % comps].max(f64::from(x));
        }
        let view = self.view(target, Piece::Floats(data));
        self.accessors.push(Accessor {
            buffer_view: view,
            component_type: FLOAT,
            count,
            kind,
            min: Some(lo),
            max: Some(hi),
        });
        self.accessors.len() - 1
    }

    pub(super) fn indices(&mut self, data: Vec<u32>) -> usize {
        let count = data.len();
        let view = self.view(Some(ELEMENT_ARRAY_BUFFER), Piece::Indices(data));
        self.accessors.push(Accessor {
            buffer_view: view,
            component_type: UNSIGNED_INT,
            count,
            kind: "SCALAR",
            min: None,
            max: None,
        });
        self.accessors.len() - 1
    }

    /// A mesh of `primitives`; returns its index.
    pub(super) fn mesh_of(&mut self, primitives: Vec<Primitive>) -> usize {
        self.meshes.push(MeshDoc { primitives });
        self.meshes.len() - 1
    }

    pub(super) fn finish(mut self, extras: Value, animations: Vec<Value>) -> Vec<u8> {
        // the frame nodes are the scene's roots, their filled children follow them
        let roots: Vec<usize> = (0..self.nodes.len()).collect();
        let first_child = self.nodes.len();
        let mut child = first_child;
        for node in self.nodes.iter_mut() {
            if node.get("children").is_some() {
                node["children"] = json!([child]);
                child += 1;
            }
        }
        let mut nodes = self.nodes;
        nodes.append(&mut self.children);
        let doc = Document {
            asset: json!({"version": "2.0", "generator": concat!("shapeflow ", env!("CARGO_PKG_VERSION"))}),
            scene: 0,
            scenes: json!([{"nodes": roots}]),
            nodes,
            meshes: self.meshes,
            materials: materials(),
            accessors: self.accessors,
            buffer_views: self.views,
            buffers: json!([{"byteLength": self.bin_len}]),
            extras,
            animations: (!animations.is_empty()).then_some(animations),
        };
        glb(&serde_json::to_vec(&doc).expect("JSON"), self.bin_len, &self.pieces)
    }
}

/// `data` appended to `out` as the little-endian bytes `bytes` gives each value.
fn extend_le<T: Copy>(out: &mut Vec<u8>, data: &[T], bytes: impl Fn(T) -> [u8; 4]) {
    let start = out.len();
    out.resize(start + 4 * data.len(), 0);
    for (to, &x) in out[start..].chunks_exact_mut(4).zip(data) {
        to.copy_from_slice(&bytes(x));
    }
}

pub(super) fn finite(x: f64) -> f32 {
    if x.is_finite() {
        x as f32
    } else {
        0.0
    }
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk of the
/// `pieces`, `bin_len` bytes (a multiple of 4).
fn glb(json: &[u8], bin_len: usize, pieces: &[Piece]) -> Vec<u8> {
    let pad = (4 - json.len() % 4) % 4;
    let jl = json.len() + pad;
    let total = 12 + 8 + jl + if bin_len > 0 { 8 + bin_len } else { 0 };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(jl as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.extend(std::iter::repeat_n(b' ', pad));
    if bin_len > 0 {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        for piece in pieces {
            match piece {
                Piece::Floats(v) => extend_le(&mut out, v, f32::to_le_bytes),
                Piece::Indices(v) => extend_le(&mut out, v, u32::to_le_bytes),
            }
        }
    }
    debug_assert_eq!(out.len(), total);
    out
}
