//! The nodes and meshes of a glTF result: a state's curves or surface with its
//! per-vertex attributes, the filled region and ribbons of 2D curves, and the
//! fixed domain of a shape-design job.

use super::builder::{finite, Builder, ARRAY_BUFFER};
use super::document::Primitive;
use super::{frame_extras, GltfFrame};
use crate::export::colors::ColorScale;
use crate::export::domain_node::{domain_primitives, DomainOutline, Part, DOMAIN_NODE};
use crate::export::fill::{bounding_diagonal, Filled, RIBBON_WIDTH};
use crate::flow::MeshData;
use crate::geometry::{segment_cycles, vertex_normals, Point};
use serde_json::json;
use std::borrow::Cow;

/// Materials of the shape-design domain (indices into the document's materials).
const DOMAIN_MATERIAL: usize = 2;
const CONTROL_MATERIAL: usize = 3;

/// Placeholder child index, replaced in [`Builder::finish`].
const FILLED_CHILD: usize = usize::MAX;

impl Builder {
    /// Attributes of the vertices `order` of `frame`, each moved by `dx[k]` in `x`
    /// (periodic curves; empty for none).
    pub(super) fn attributes(
        &mut self,
        frame: &GltfFrame<'_>,
        order: &[usize],
        dx: &[f64],
        scale: &ColorScale,
    ) -> Vec<(Cow<'static, str>, usize)> {
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
        let mut a = Vec::with_capacity(6);
        a.push(("POSITION".into(), self.floats(pos, "VEC3", Some(ARRAY_BUFFER))));
        a.push(("_CURVATURE".into(), self.floats(kappa, "SCALAR", Some(ARRAY_BUFFER))));
        a.push(("_NORMAL_VELOCITY".into(), self.floats(vel, "SCALAR", Some(ARRAY_BUFFER))));
        if let Some((name, values)) = frame.own {
            let own: Vec<f32> = order.iter().map(|&v| finite(values[v])).collect();
            a.push((name.to_string().into(), self.floats(own, "SCALAR", Some(ARRAY_BUFFER))));
        }
        a.push(("COLOR_0".into(), self.floats(color, "VEC3", Some(ARRAY_BUFFER))));
        a
    }

    /// A mesh for `frame`; returns its index.
    pub(super) fn mesh(&mut self, frame: &GltfFrame<'_>, scale: &ColorScale) -> usize {
        let m = frame.mesh;
        let mut primitives = Vec::new();
        if m.dimension == 2 {
            for mut cycle in segment_cycles(m.positions.len(), m.elements.iter().map(|e| (e[0], e[1]))) {
                let Some(period) = m.period else {
                    let attributes = self.attributes(frame, &cycle, &[], scale);
                    primitives.push(Primitive { attributes, indices: None, mode: 2, material: 0 });
                    continue;
                };
                let (dx, winds) = crate::export::lift_component(m, &mut cycle, period);
                let attributes = self.attributes(frame, &cycle, &dx, scale);
                let mode = if winds { 3 } else { 2 };
                primitives.push(Primitive { attributes, indices: None, mode, material: 0 });
            }
        } else {
            let order: Vec<usize> = (0..m.positions.len()).collect();
            let mut attributes = self.attributes(frame, &order, &[], scale);
            let normals = surface_normals(m);
            attributes.push(("NORMAL".into(), self.floats(normals, "VEC3", Some(ARRAY_BUFFER))));
            let idx: Vec<u32> = m.elements.iter().flat_map(|t| t.iter().map(|&v| v as u32)).collect();
            let indices = self.indices(idx);
            primitives.push(Primitive { attributes, indices: Some(indices), mode: 4, material: 0 });
        }
        self.mesh_of(primitives)
    }

    /// The mesh of `filled` (the region and ribbons of `frame`'s curves, see the
    /// module documentation), the ribbons coloured by `scale`; returns its index.
    pub(super) fn filled(&mut self, frame: &GltfFrame<'_>, scale: &ColorScale, filled: &Filled) -> usize {
        let mut primitives = Vec::new();
        if !filled.region.is_empty() {
            let pos: Vec<f32> = filled.points.iter().flat_map(|p| [p[0] as f32, p[1] as f32, 0.0]).collect();
            let normals: Vec<f32> = filled.points.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
            let idx: Vec<u32> = filled.region.iter().flat_map(|t| t.map(|v| v as u32)).collect();
            let position = self.floats(pos, "VEC3", Some(ARRAY_BUFFER));
            let normal = self.floats(normals, "VEC3", Some(ARRAY_BUFFER));
            let indices = self.indices(idx);
            let attributes = vec![("POSITION".into(), position), ("NORMAL".into(), normal)];
            primitives.push(Primitive { attributes, indices: Some(indices), mode: 4, material: 1 });
        }
        // the ribbons, a little above the region so that both show
        let z = (0.5 * filled.width) as f32;
        let pos: Vec<f32> = filled.ribbon_points.iter().flat_map(|p| [p[0] as f32, p[1] as f32, z]).collect();
        let field = frame.colored().0;
        let color: Vec<f32> = filled.ribbon_source.iter().flat_map(|&v| scale.color(field[v])).collect();
        let normals: Vec<f32> = filled.ribbon_points.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
        let idx: Vec<u32> = filled.ribbon_triangles.iter().flatten().copied().collect();
        let position = self.floats(pos, "VEC3", Some(ARRAY_BUFFER));
        let normal = self.floats(normals, "VEC3", Some(ARRAY_BUFFER));
        let colors = self.floats(color, "VEC3", Some(ARRAY_BUFFER));
        let indices = self.indices(idx);
        let attributes = vec![("POSITION".into(), position), ("NORMAL".into(), normal), ("COLOR_0".into(), colors)];
        primitives.push(Primitive { attributes, indices: Some(indices), mode: 4, material: 0 });
        self.mesh_of(primitives)
    }

    /// The node of a shape-design domain (docs/results.md); returns its index.
    pub(super) fn domain_node(&mut self, domain: &DomainOutline) -> usize {
        let width = RIBBON_WIDTH * bounding_diagonal(&domain.outer);
        let mut primitives = Vec::new();
        for p in domain_primitives(domain, width) {
            let pos: Vec<f32> = p.points.iter().flat_map(|q| [q[0] as f32, q[1] as f32, p.z as f32]).collect();
            let position = self.floats(pos, "VEC3", Some(ARRAY_BUFFER));
            let material = if p.part == Part::Control { CONTROL_MATERIAL } else { DOMAIN_MATERIAL };
            if p.part == Part::Loop {
                primitives.push(Primitive {
                    attributes: vec![("POSITION".into(), position)],
                    indices: None,
                    mode: 2,
                    material,
                });
                continue;
            }
            let normals: Vec<f32> = p.points.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).collect();
            let normal = self.floats(normals, "VEC3", Some(ARRAY_BUFFER));
            let idx: Vec<u32> = p.triangles.iter().flatten().copied().collect();
            let indices = self.indices(idx);
            let attributes = vec![("POSITION".into(), position), ("NORMAL".into(), normal)];
            primitives.push(Primitive { attributes, indices: Some(indices), mode: 4, material });
        }
        let mesh = self.mesh_of(primitives);
        self.nodes.push(json!({"mesh": mesh, "name": DOMAIN_NODE, "extras": {"shapeflow": "display"}}));
        self.nodes.len() - 1
    }

    /// The node of `frame` (its lines or surface), with `filled` (the region and the
    /// ribbons of its curves, [`Filled::of`]) as a child; returns the node's index.
    pub(super) fn frame_node(&mut self, frame: &GltfFrame<'_>, filled: Option<&Filled>) -> usize {
        let (field, name) = frame.colored();
        let scale = ColorScale::of(field, name);
        let mesh = self.mesh(frame, &scale);
        let name = format!("iteration {}", frame.iteration);
        let mut extras = frame_extras(frame);
        extras["colors"] = scale.extras();
        let mut node = json!({"mesh": mesh, "name": name, "extras": extras});
        if let Some(filled) = filled.map(|f| self.filled(frame, &scale, f)) {
            self.children
                .push(json!({"mesh": filled, "name": format!("{name} (filled)"), "extras": {"shapeflow": "display"}}));
            node["children"] = json!([FILLED_CHILD]);
        }
        self.nodes.push(node);
        self.nodes.len() - 1
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
