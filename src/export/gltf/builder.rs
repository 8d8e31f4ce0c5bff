//! The glTF document and its binary buffer as they are built: buffer views,
//! accessors with exact bounds, and the GLB container.

use serde_json::{json, Value};

pub(super) const ARRAY_BUFFER: u32 = 34962;
pub(super) const ELEMENT_ARRAY_BUFFER: u32 = 34963;
pub(super) const FLOAT: u32 = 5126;
pub(super) const UNSIGNED_INT: u32 = 5125;

#[derive(Default)]
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
    pub(super) meshes: Vec<Value>,
    /// The frame nodes and the domain's (the scene's roots).
    pub(super) nodes: Vec<Value>,
    /// Their children (filled regions), placed after them in `finish`.
    pub(super) children: Vec<Value>,
}

impl Builder {
    /// A buffer view of the bytes that `write` appends to the binary chunk (from a
    /// 4-byte boundary); returns its index.
    fn view(&mut self, target: Option<u32>, write: impl FnOnce(&mut Vec<u8>)) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        write(&mut self.bin);
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": self.bin.len() - offset});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    /// A float accessor of `kind` (`SCALAR`, `VEC3`) with exact min/max.
    pub(super) fn floats(&mut self, data: &[f32], kind: &str, target: Option<u32>) -> usize {
        let comps = if kind == "VEC3" { 3 } else { 1 };
        let count = data.len() / comps;
        let mut lo = vec![f32::INFINITY; comps];
        let mut hi = vec![f32::NEG_INFINITY; comps];
        for (i, &x) in data.iter().enumerate() {
            lo[i % comps] = lo[i % comps].min(x);
            hi[i % comps] = hi[i % comps].max(x);
        }
        let view = self.view(target, |bin| extend_le(bin, data, f32::to_le_bytes));
        let as_json = |v: &[f32]| v.iter().map(|&x| json!(x as f64)).collect::<Vec<_>>();
        self.accessors.push(json!({
            "bufferView": view, "componentType": FLOAT, "count": count, "type": kind,
            "min": as_json(&lo), "max": as_json(&hi),
        }));
        self.accessors.len() - 1
    }

    pub(super) fn indices(&mut self, data: &[u32]) -> usize {
        let view = self.view(Some(ELEMENT_ARRAY_BUFFER), |bin| extend_le(bin, data, u32::to_le_bytes));
        self.accessors
            .push(json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": data.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    pub(super) fn finish(mut self, extras: Value, animations: Vec<Value>) -> Vec<u8> {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
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
        let mut doc = json!({
            "asset": {"version": "2.0", "generator": concat!("shapeflow ", env!("CARGO_PKG_VERSION"))},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "meshes": self.meshes,
            "materials": [{
                "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
                "doubleSided": true,
            }, {
                "name": "region",
                "pbrMetallicRoughness": {"baseColorFactor": [0.55, 0.65, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9},
                "doubleSided": true,
            }, {
                "name": "domain",
                "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.2, 0.2, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9},
                "doubleSided": true,
            }, {
                "name": "control region",
                "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.8, 0.35, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9},
                "doubleSided": true,
            }],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": self.bin.len()}],
            "extras": extras,
        });
        if !animations.is_empty() {
            doc["animations"] = json!(animations);
        }
        glb(&serde_json::to_vec(&doc).expect("JSON"), &self.bin)
    }
}

/// `data` appended to `bin` as the little-endian bytes `bytes` gives each value.
fn extend_le<T: Copy>(bin: &mut Vec<u8>, data: &[T], bytes: impl Fn(T) -> [u8; 4]) {
    bin.reserve(4 * data.len());
    for &x in data {
        bin.extend_from_slice(&bytes(x));
    }
}

pub(super) fn finite(x: f64) -> f32 {
    if x.is_finite() {
        x as f32
    } else {
        0.0
    }
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let (jl, bl) = (json.len() + pad(json.len()), bin.len() + pad(bin.len()));
    let total = 12 + 8 + jl + if bl > 0 { 8 + bl } else { 0 };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(jl as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.extend(std::iter::repeat_n(b' ', pad(json.len())));
    if bl > 0 {
        out.extend_from_slice(&(bl as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out.extend(std::iter::repeat_n(0u8, pad(bin.len())));
    }
    out
}
