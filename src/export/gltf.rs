//! glTF 2.0 binary (.glb) results, laid out as docs/results.md describes:
//!
//! - curves: one `LINE_LOOP` primitive per component (z = 0), vertices in the
//!   component's order (counter-clockwise for outer boundaries), and for closed
//!   and periodic curves a child node `… (filled)` (extras `{"shapeflow": "display"}`: the mesh
//!   readers skip it) whose mesh draws the enclosed region as
//!   triangles (holes respected, material `region`) and each curve as a ribbon of
//!   triangles with the vertex colours, so that renderers that draw no lines
//!   (Blender) or only hairlines show the shape; on periodic curves
//!   (the stressed film) a component winding around the period is a `LINE_STRIP`
//!   over one period, its first vertex repeated at the end shifted by the period;
//! - surfaces: one indexed `TRIANGLES` primitive with unit vertex `NORMAL`s;
//! - per vertex: `_CURVATURE` (the discrete κ), `_NORMAL_VELOCITY` (V of the next
//!   step) and `COLOR_0`, the curvature through a blue–white–red map, white at its
//!   median and saturated at the 98th percentile of the deviations from it (at
//!   least 5 % of the median), recorded in the node's `extras.colors`;
//! - job metadata in the root `extras`, the frame's iteration/time/energy in the
//!   node's `extras`;
//! - evolution: one node per checkpoint, switched by a `STEP`-interpolated `scale`
//!   animation (0.2 s per checkpoint, the first frame visible without animation, a
//!   trailing hold key so that the last frame is shown).

use super::colors::ColorScale;
use super::domain_node::{bounding_diagonal, domain_primitives, DomainOutline, Part, DOMAIN_NODE};
use crate::flow::MeshData;
use crate::geometry::{segment_cycles, vertex_normals, Point};
use serde_json::{json, Value};

/// The per-vertex field that `COLOR_0` shows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ColorField {
    /// The discrete curvature `κ` (`_CURVATURE`).
    #[default]
    Curvature,
    /// The normal velocity `V` of the next step (`_NORMAL_VELOCITY`).
    NormalVelocity,
    /// The problem's own field ([`GltfFrame::own`]; the curvature if it has none).
    ProblemField,
}

/// One state to draw.
#[derive(Debug, Clone, Copy)]
pub struct GltfFrame<'a> {
    pub mesh: &'a MeshData,
    /// Per vertex of `mesh`.
    pub curvature: &'a [f64],
    /// Per vertex of `mesh`.
    pub normal_velocity: &'a [f64],
    pub iteration: usize,
    pub time: f64,
    pub energy: f64,
    /// The problem's own field, if it has one: its attribute name and its values
    /// per vertex of `mesh`.
    pub own: Option<(&'a str, &'a [f64])>,
    /// The field `COLOR_0` shows.
    pub color_by: ColorField,
}

impl<'a> GltfFrame<'a> {
    /// The values of the coloured field and its attribute's name.
    fn colored(&self) -> (&'a [f64], &'a str) {
        match (self.color_by, self.own) {
            (ColorField::NormalVelocity, _) => (self.normal_velocity, "_NORMAL_VELOCITY"),
            (ColorField::ProblemField, Some((name, values))) => (values, name),
            _ => (self.curvature, "_CURVATURE"),
        }
    }
}

/// Seconds per checkpoint in evolution.glb.
pub const FRAME_SECONDS: f32 = 0.2;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    /// The frame nodes and the domain's (the scene's roots).
    nodes: Vec<Value>,
    /// Their children (filled regions), placed after them in `finish`.
    children: Vec<Value>,
}

/// Width of the curve ribbons, relative to the diagonal of the curves' bounding box.
const RIBBON_WIDTH: f64 = 0.004;

/// Materials of the shape-design domain (indices into the document's materials).
const DOMAIN_MATERIAL: usize = 2;
const CONTROL_MATERIAL: usize = 3;

/// Placeholder child index, replaced in [`Builder::finish`].
const FILLED_CHILD: usize = usize::MAX;

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// A float accessor of `kind` (`SCALAR`, `VEC3`) with exact min/max.
    fn floats(&mut self, data: &[f32], kind: &str, target: Option<u32>) -> usize {
        let comps = if kind == "VEC3" { 3 } else { 1 };
        let count = data.len() / comps;
        let mut lo = vec![f32::INFINITY; comps];
        let mut hi = vec![f32::NEG_INFINITY; comps];
        for (i, &x) in data.iter().enumerate() {
            lo[i % comps] = lo[i % comps].min(x);
            hi[i % comps] = hi[i % comps].max(x);
        }
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let as_json = |v: &[f32]| v.iter().map(|&x| json!(x as f64)).collect::<Vec<_>>();
        self.accessors.push(json!({
            "bufferView": view, "componentType": FLOAT, "count": count, "type": kind,
            "min": as_json(&lo), "max": as_json(&hi),
        }));
        self.accessors.len() - 1
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors
            .push(json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": data.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// Attributes of the vertices `order` of `frame`, each moved by `dx[k]` in `x`
    /// (periodic curves; empty for none).
    fn attributes(
        &mut self,
        frame: &GltfFrame<'_>,
        order: &[usize],
        dx: &[f64],
        scale: &ColorScale,
    ) -> serde_json::Map<String, Value> {
        let m = frame.mesh;
        let pos: Vec<f32> = order
            .iter()
            .enumerate()
            .flat_map(|(k, &v)| {
                let shift = dx.get(k).copied().unwrap_or(0.0);
                (0..3).map(move |c| {
                    let x = m.positions[v].get(c).copied().unwrap_or(0.0);
                    (if c == 0 { x + shift } else { x }) as f32
                })
            })
            .collect();
        let kappa: Vec<f32> = order.iter().map(|&v| finite(frame.curvature[v])).collect();
        let vel: Vec<f32> = order.iter().map(|&v| finite(frame.normal_velocity[v])).collect();
        let field = frame.colored().0;
        let color: Vec<f32> = order.iter().flat_map(|&v| scale.color(field[v])).collect();
        let mut a = serde_json::Map::new();
        a.insert("POSITION".into(), json!(self.floats(&pos, "VEC3", Some(ARRAY_BUFFER))));
        a.insert("_CURVATURE".into(), json!(self.floats(&kappa, "SCALAR", Some(ARRAY_BUFFER))));
        a.insert("_NORMAL_VELOCITY".into(), json!(self.floats(&vel, "SCALAR", Some(ARRAY_BUFFER))));
        if let Some((name, values)) = frame.own {
            let own: Vec<f32> = order.iter().map(|&v| finite(values[v])).collect();
            a.insert(name.into(), json!(self.floats(&own, "SCALAR", Some(ARRAY_BUFFER))));
        }
        a.insert("COLOR_0".into(), json!(self.floats(&color, "VEC3", Some(ARRAY_BUFFER))));
        a
    }

    /// A mesh for `frame`; returns its index.
    fn mesh(&mut self, frame: &GltfFrame<'_>, scale: &ColorScale) -> usize {
        let m = frame.mesh;
        let mut primitives = Vec::new();
        if m.dimension == 2 {
            for mut cycle in segment_cycles(m.positions.len(), m.elements.iter().map(|e| (e[0], e[1]))) {
                let Some(period) = m.period else {
                    let attributes = self.attributes(frame, &cycle, &[], scale);
                    primitives.push(json!({"attributes": attributes, "mode": 2, "material": 0}));
                    continue;
                };
                let (dx, winds) = super::lift_component(m, &mut cycle, period);
                let attributes = self.attributes(frame, &cycle, &dx, scale);
                primitives.push(json!({"attributes": attributes, "mode": if winds { 3 } else { 2 }, "material": 0}));
            }
        } else {
            let order: Vec<usize> = (0..m.positions.len()).collect();
            let mut attributes = self.attributes(frame, &order, &[], scale);
            let normals = surface_normals(m);
            attributes.insert("NORMAL".into(), json!(self.floats(&normals, "VEC3", Some(ARRAY_BUFFER))));
            let idx: Vec<u32> = m.elements.iter().flat_map(|t| t.iter().map(|&v| v as u32)).collect();
            let indices = self.indices(&idx);
            primitives.push(json!({"attributes": attributes, "indices": indices, "mode": 4, "material": 0}));
        }
        self.meshes.push(json!({"primitives": primitives}));
        self.meshes.len() - 1
    }

    /// For curves (2D): a mesh of the enclosed region and of a ribbon along each
    /// curve (see the module documentation); `None` for surfaces, or when the
    /// curves cross (no region to fill). Periodic curves (the stressed film) are
    /// drawn over one period, lifted as their `LINE_STRIP`s are: the region is the
    /// film between its surface and the substrate `y = 0`, voids left open.
    fn filled(&mut self, frame: &GltfFrame<'_>, scale: &ColorScale) -> Option<usize> {
        let m = frame.mesh;
        if m.dimension != 2 || m.elements.is_empty() {
            return None;
        }
        let drawing = super::fill::Drawing::of(m);
        let region = super::fill::region_triangles(&drawing.points, &drawing.region)?;
        let width = RIBBON_WIDTH * bounding_diagonal(&drawing.points);
        let mut primitives = Vec::new();
        if !region.is_empty() {
            let pos: Vec<f32> = drawing.points.iter().flat_map(|p| [p[0] as f32, p[1] as f32, 0.0]).collect();
            let normals: Vec<f32> = drawing.points.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
            let idx: Vec<u32> = region.iter().flat_map(|t| t.map(|v| v as u32)).collect();
            let position = self.floats(&pos, "VEC3", Some(ARRAY_BUFFER));
            let normal = self.floats(&normals, "VEC3", Some(ARRAY_BUFFER));
            let indices = self.indices(&idx);
            primitives.push(json!({
                "attributes": {"POSITION": position, "NORMAL": normal}, "indices": indices, "mode": 4, "material": 1,
            }));
        }
        // the ribbons, a little above the region so that both show
        let (mut pos, mut color, mut idx) = (Vec::new(), Vec::new(), Vec::new());
        for (l, closed) in &drawing.curves {
            let (v, t) = super::fill::ribbon(&drawing.points, l, width, *closed);
            let base = (pos.len() / 3) as u32;
            pos.extend(v.iter().flat_map(|p| [p[0] as f32, p[1] as f32, (0.5 * width) as f32]));
            color.extend(
                l.iter()
                    .flat_map(|&i| {
                        let c = scale.color(frame.colored().0[drawing.source[i]]);
                        [c, c]
                    })
                    .flatten(),
            );
            idx.extend(t.iter().flat_map(|t| t.map(|i| i + base)));
        }
        let normals: Vec<f32> = (0..pos.len() / 3).flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
        let position = self.floats(&pos, "VEC3", Some(ARRAY_BUFFER));
        let normal = self.floats(&normals, "VEC3", Some(ARRAY_BUFFER));
        let colors = self.floats(&color, "VEC3", Some(ARRAY_BUFFER));
        let indices = self.indices(&idx);
        primitives.push(json!({
            "attributes": {"POSITION": position, "NORMAL": normal, "COLOR_0": colors},
            "indices": indices, "mode": 4, "material": 0,
        }));
        self.meshes.push(json!({"primitives": primitives}));
        Some(self.meshes.len() - 1)
    }

    /// The node of a shape-design domain (docs/results.md); returns its index.
    fn domain_node(&mut self, domain: &DomainOutline) -> usize {
        let width = RIBBON_WIDTH * bounding_diagonal(&domain.outer);
        let mut primitives = Vec::new();
        for p in domain_primitives(domain, width) {
            let pos: Vec<f32> = p.points.iter().flat_map(|q| [q[0] as f32, q[1] as f32, p.z as f32]).collect();
            let position = self.floats(&pos, "VEC3", Some(ARRAY_BUFFER));
            let material = if p.part == Part::Control { CONTROL_MATERIAL } else { DOMAIN_MATERIAL };
            if p.part == Part::Loop {
                primitives.push(json!({"attributes": {"POSITION": position}, "mode": 2, "material": material}));
                continue;
            }
            let normals: Vec<f32> = p.points.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
            let normal = self.floats(&normals, "VEC3", Some(ARRAY_BUFFER));
            let idx: Vec<u32> = p.triangles.iter().flatten().copied().collect();
            let indices = self.indices(&idx);
            primitives.push(json!({
                "attributes": {"POSITION": position, "NORMAL": normal}, "indices": indices, "mode": 4, "material": material,
            }));
        }
        self.meshes.push(json!({"primitives": primitives}));
        let mesh = self.meshes.len() - 1;
        self.nodes.push(json!({"mesh": mesh, "name": DOMAIN_NODE, "extras": {"shapeflow": "display"}}));
        self.nodes.len() - 1
    }

    /// The node of `frame` (its lines or surface), with the filled region and the
    /// ribbons of closed curves as a child; returns the node's index.
    fn frame_node(&mut self, frame: &GltfFrame<'_>) -> usize {
        let (field, name) = frame.colored();
        let scale = ColorScale::of(field, name);
        let mesh = self.mesh(frame, &scale);
        let name = format!("iteration {}", frame.iteration);
        let mut extras = frame_extras(frame);
        extras["colors"] = scale.extras();
        let mut node = json!({"mesh": mesh, "name": name, "extras": extras});
        if let Some(filled) = self.filled(frame, &scale) {
            self.children
                .push(json!({"mesh": filled, "name": format!("{name} (filled)"), "extras": {"shapeflow": "display"}}));
            node["children"] = json!([FILLED_CHILD]);
        }
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    fn finish(mut self, extras: Value, animations: Vec<Value>) -> Vec<u8> {
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

fn finite(x: f64) -> f32 {
    if x.is_finite() {
        x as f32
    } else {
        0.0
    }
}

/// Unit area-weighted vertex normals of a triangle surface ([`vertex_normals`]), as
/// f32; `+z` where a vertex has none.
fn surface_normals(m: &MeshData) -> Vec<f32> {
    let points: Vec<Point<3>> = m.positions.iter().map(|p| Point::<3>::new(p[0], p[1], p[2])).collect();
    let triangles: Vec<[usize; 3]> = m.elements.iter().map(|t| [t[0], t[1], t[2]]).collect();
    vertex_normals(&points, &triangles)
        .iter()
        .flat_map(|n| if n.norm() > 0.0 { [n.x as f32, n.y as f32, n.z as f32] } else { [0.0, 0.0, 1.0] })
        .collect()
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

fn frame_extras(f: &GltfFrame<'_>) -> Value {
    let energy = if f.energy.is_finite() { json!(f.energy) } else { Value::Null };
    json!({"iteration": f.iteration, "time": f.time, "energy": energy})
}

/// One state as a .glb (shape.glb, checkpoints/{n}.glb), with the fixed domain of a
/// shape-design job if given.
pub fn shape_glb(frame: &GltfFrame<'_>, domain: Option<&DomainOutline>, extras: Value) -> Vec<u8> {
    let mut b = Builder::default();
    b.frame_node(frame);
    if let Some(d) = domain {
        b.domain_node(d);
    }
    b.finish(extras, Vec::new())
}

/// Every checkpoint as an animated .glb (evolution.glb), with the fixed domain of a
/// shape-design job if given (not animated). `frames` must not be empty.
pub fn evolution_glb(frames: &[GltfFrame<'_>], domain: Option<&DomainOutline>, extras: Value) -> Vec<u8> {
    let mut b = Builder::default();
    for (k, f) in frames.iter().enumerate() {
        let node = b.frame_node(f);
        if k > 0 {
            b.nodes[node]["scale"] = json!([0.0, 0.0, 0.0]);
        }
    }
    if let Some(d) = domain {
        b.domain_node(d);
    }
    let n = frames.len();
    if n < 2 {
        return b.finish(extras, Vec::new());
    }
    // keys at k·Δt for k = 0..n-1, plus a trailing hold key at n·Δt
    let times: Vec<f32> = (0..=n).map(|k| k as f32 * FRAME_SECONDS).collect();
    let input = b.floats(&times, "SCALAR", None);
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    for node in 0..n {
        let scales: Vec<f32> = (0..=n)
            .flat_map(|key| {
                let on = key.min(n - 1) == node;
                [on as u8 as f32; 3]
            })
            .collect();
        let output = b.floats(&scales, "VEC3", None);
        samplers.push(json!({"input": input, "output": output, "interpolation": "STEP"}));
        channels.push(json!({"sampler": node, "target": {"node": node, "path": "scale"}}));
    }
    let animation = json!({"name": "evolution", "samplers": samplers, "channels": channels});
    b.finish(extras, vec![animation])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere};

    #[test]
    fn container_is_aligned_and_sized() {
        let c = MeshData::from(&circle([0.0, 0.0], 1.0, 16).unwrap());
        let k = vec![1.0; 16];
        let g = shape_glb(
            &GltfFrame {
                mesh: &c,
                curvature: &k,
                normal_velocity: &k,
                iteration: 3,
                time: 0.1,
                energy: 2.0,
                own: None,
                color_by: ColorField::Curvature,
            },
            None,
            json!({}),
        );
        assert_eq!(&g[0..4], b"glTF");
        assert_eq!(u32::from_le_bytes(g[8..12].try_into().unwrap()) as usize, g.len());
        assert_eq!(g.len() % 4, 0);
        let jl = u32::from_le_bytes(g[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&g[20..20 + jl]).unwrap();
        assert_eq!(doc["meshes"][0]["primitives"][0]["mode"], 2);
        let s = MeshData::from(&icosphere([0.0; 3], 1.0, 1).unwrap());
        let k = vec![2.0; s.positions.len()];
        let f = GltfFrame {
            mesh: &s,
            curvature: &k,
            normal_velocity: &k,
            iteration: 0,
            time: 0.0,
            energy: 1.0,
            own: None,
            color_by: ColorField::Curvature,
        };
        let g = evolution_glb(&[f, f, f], None, json!({"problem": "x"}));
        let jl = u32::from_le_bytes(g[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&g[20..20 + jl]).unwrap();
        assert_eq!(doc["nodes"].as_array().unwrap().len(), 3);
        assert_eq!(doc["animations"][0]["channels"].as_array().unwrap().len(), 3);
    }
}
