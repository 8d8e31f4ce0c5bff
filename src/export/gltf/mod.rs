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

mod builder;
mod document;
mod nodes;

use super::domain_node::DomainOutline;
use super::fill::Filled;
use crate::flow::MeshData;
use builder::Builder;
use serde_json::{json, Value};
use std::borrow::Cow;

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
    /// [`Filled::of`] `mesh`, if it was computed ahead (a service's writer does it
    /// for each checkpoint while the run goes on); computed here otherwise.
    pub fill: Option<&'a Option<Filled>>,
}

impl<'a> GltfFrame<'a> {
    /// The region and ribbons of the frame's curves, as computed ahead or now.
    fn filled(&self) -> Cow<'a, Option<Filled>> {
        match self.fill {
            Some(f) => Cow::Borrowed(f),
            None => Cow::Owned(Filled::of(self.mesh)),
        }
    }

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

/// [`GltfFrame::filled`] of every frame, on as many threads as there are cores.
fn filled_all<'a>(frames: &[GltfFrame<'a>]) -> Vec<Cow<'a, Option<Filled>>> {
    let threads = crate::cores().clamp(1, frames.len().max(1));
    let chunk = frames.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let parts: Vec<_> = frames
            .chunks(chunk)
            .map(|c| s.spawn(move || c.iter().map(GltfFrame::filled).collect::<Vec<_>>()))
            .collect();
        parts.into_iter().flat_map(|p| p.join().expect("a triangulation thread panicked")).collect()
    })
}

fn frame_extras(f: &GltfFrame<'_>) -> Value {
    let energy = if f.energy.is_finite() { json!(f.energy) } else { Value::Null };
    json!({"iteration": f.iteration, "time": f.time, "energy": energy})
}

/// One state as a .glb (shape.glb, checkpoints/{n}.glb), with the fixed domain of a
/// shape-design job if given.
pub fn shape_glb(frame: &GltfFrame<'_>, domain: Option<&DomainOutline>, extras: Value) -> Vec<u8> {
    let mut b = Builder::default();
    b.frame_node(frame, frame.filled().as_ref().as_ref());
    if let Some(d) = domain {
        b.domain_node(d);
    }
    b.finish(extras, Vec::new())
}

/// Every checkpoint as an animated .glb (evolution.glb), with the fixed domain of a
/// shape-design job if given (not animated). `frames` must not be empty.
pub fn evolution_glb(frames: &[GltfFrame<'_>], domain: Option<&DomainOutline>, extras: Value) -> Vec<u8> {
    let mut b = Builder::default();
    for (k, (f, filled)) in frames.iter().zip(filled_all(frames)).enumerate() {
        let node = b.frame_node(f, filled.as_ref().as_ref());
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
    let input = b.floats(times, "SCALAR", None);
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    for node in 0..n {
        let scales: Vec<f32> = (0..=n)
            .flat_map(|key| {
                let on = key.min(n - 1) == node;
                [on as u8 as f32; 3]
            })
            .collect();
        let output = b.floats(scales, "VEC3", None);
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
                fill: None,
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
            fill: None,
        };
        let g = evolution_glb(&[f, f, f], None, json!({"problem": "x"}));
        let jl = u32::from_le_bytes(g[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&g[20..20 + jl]).unwrap();
        assert_eq!(doc["nodes"].as_array().unwrap().len(), 3);
        assert_eq!(doc["animations"][0]["channels"].as_array().unwrap().len(), 3);
    }
}
