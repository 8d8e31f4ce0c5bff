//! The glTF document's typed parts: buffer views, accessors, meshes and their
//! primitives, and the document itself (an evolution of many curves has
//! thousands of accessors, which as JSON values cost more to build and write than
//! the arrays they describe).

use serde::Serialize;
use serde_json::{json, Value};
use std::borrow::Cow;

/// A buffer view of the document.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct View {
    pub buffer: usize,
    pub byte_offset: usize,
    pub byte_length: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<u32>,
}

/// An accessor of the document.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Accessor {
    pub buffer_view: usize,
    pub component_type: u32,
    pub count: usize,
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Exact bounds of a float accessor (its values as f64).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<Vec<f64>>,
}

/// A primitive of a mesh: its attributes (name, accessor) in order.
#[derive(Serialize)]
pub(super) struct Primitive {
    #[serde(serialize_with = "as_map")]
    pub attributes: Vec<(Cow<'static, str>, usize)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indices: Option<usize>,
    pub mode: u32,
    pub material: usize,
}

/// A mesh of the document.
#[derive(Serialize)]
pub(super) struct MeshDoc {
    pub primitives: Vec<Primitive>,
}

fn as_map<S: serde::Serializer>(pairs: &[(Cow<'static, str>, usize)], s: S) -> Result<S::Ok, S::Error> {
    s.collect_map(pairs.iter().map(|(k, v)| (k, v)))
}

/// The glTF document, in the order glTF's own examples write it.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Document {
    pub asset: Value,
    pub scene: usize,
    pub scenes: Value,
    pub nodes: Vec<Value>,
    pub meshes: Vec<MeshDoc>,
    pub materials: Value,
    pub accessors: Vec<Accessor>,
    pub buffer_views: Vec<View>,
    pub buffers: Value,
    pub extras: Value,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub animations: Option<Vec<Value>>,
}

/// The materials: the curves' and surfaces' (vertex colours), the filled region's,
/// a shape-design domain's and its control region's.
pub(super) fn materials() -> Value {
    json!([{
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
    }])
}
