//! Frames: a stored state with the per-vertex fields its glTF shows, computed once
//! when the state is stored ([`Frame::of`]), and what else a glTF file of the job
//! needs ([`GlbContext`]). With both, any glb of the job (a checkpoint, the
//! evolution) is encoded without preparing the job again or solving anything.

use super::run::{run_vertex_fields, vertex_fields};
use super::spec::ColorBy;
use super::{PreparedJob, ProblemKind};
use crate::bulk::Polygon;
use crate::export::{evolution_glb, shape_glb, ColorField, DomainOutline, Filled, GltfFrame};
use crate::flow::{Checkpoint, FlowError, MeshData, VertexFields};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::sync::Arc;

pub use crate::limits::{MAX_EVOLUTION_BYTES, MAX_FRAMES};

/// The per-vertex fields of a frame, as stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameFields {
    pub curvature: Vec<f64>,
    pub normal_velocity: Vec<f64>,
    /// The problem's own field: its glTF attribute name and values.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub own: Option<(String, Vec<f64>)>,
}

impl From<VertexFields> for FrameFields {
    fn from(f: VertexFields) -> Self {
        FrameFields {
            curvature: f.curvature,
            normal_velocity: f.normal_velocity,
            own: f.own.map(|o| (o.name.to_string(), o.values)),
        }
    }
}

/// A state of a run and its fields. Serialized as the checkpoint's JSON with a
/// `fields` member, so that a stored checkpoint without fields reads as a frame
/// whose fields are unknown.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    #[serde(flatten)]
    pub state: Checkpoint,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields: Option<FrameFields>,
    /// What draws the state's curves in renderers that draw no lines, if it was
    /// computed ahead ([`Frame::with_fill`]); not stored.
    #[serde(skip)]
    pub fill: Option<Arc<Option<Filled>>>,
}

impl Frame {
    /// `state` with its curvature, normal velocity and own field (one linear
    /// solve of the job's problem); zeros where they cannot be computed (e.g. the
    /// last state of a failed run), so that the geometry is still shown.
    pub fn of(job: &PreparedJob, state: &Checkpoint) -> Frame {
        Frame::with_fields(state, vertex_fields(job, state))
    }

    /// [`Frame::of`] a state that this process's run produced (its mesh is not
    /// validated again, [`run_vertex_fields`]).
    pub fn of_run(job: &PreparedJob, state: &Checkpoint) -> Frame {
        Frame::with_fields(state, run_vertex_fields(job, state))
    }

    fn with_fields(state: &Checkpoint, fields: Result<VertexFields, FlowError>) -> Frame {
        let n = state.mesh.positions.len();
        let fields = match fields {
            Ok(f) if f.curvature.len() == n && f.normal_velocity.len() == n => f,
            _ => VertexFields { curvature: vec![0.0; n], normal_velocity: vec![0.0; n], own: None },
        };
        Frame { state: state.clone(), fields: Some(fields.into()), fill: None }
    }

    /// The frame with its drawing computed now (the triangles of a 2D state's
    /// region and the ribbons along its curves, [`Filled::of`]), so that the glb files made of it
    /// later need not: a worker computes it for each checkpoint while the run
    /// goes on, and not all of them at the end.
    pub fn with_fill(mut self) -> Frame {
        self.fill = Some(Arc::new(Filled::of(&self.state.mesh)));
        self
    }

    /// What the glTF encoder draws: the state with its fields (zeros if unknown).
    fn gltf<'a>(&'a self, zeros: &'a [f64], color_by: ColorBy) -> GltfFrame<'a> {
        let (curvature, normal_velocity, own) = match &self.fields {
            Some(f) if f.curvature.len() == zeros.len() && f.normal_velocity.len() == zeros.len() => {
                (f.curvature.as_slice(), f.normal_velocity.as_slice(), f.own.as_ref())
            }
            _ => (zeros, zeros, None),
        };
        GltfFrame {
            mesh: &self.state.mesh,
            curvature,
            normal_velocity,
            own: own.filter(|o| o.1.len() == zeros.len()).map(|(name, v)| (name.as_str(), v.as_slice())),
            iteration: self.state.iteration,
            time: self.state.time,
            energy: self.state.energy,
            color_by: match color_by {
                ColorBy::Curvature => ColorField::Curvature,
                ColorBy::NormalVelocity => ColorField::NormalVelocity,
                ColorBy::ProblemField => ColorField::ProblemField,
            },
            fill: self.fill.as_deref(),
        }
    }
}

/// What the glTF files of a job share: the metadata in `extras`, the field
/// `COLOR_0` shows and the fixed domain of a shape-design job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GlbContext {
    pub extras: Value,
    pub color_by: ColorBy,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<DomainOutline>,
}

impl GlbContext {
    pub fn of(job: &PreparedJob) -> GlbContext {
        GlbContext { extras: job_extras(job), color_by: job.spec.output.color_by, domain: domain_outline(job) }
    }

    /// shape.glb / checkpoints/{n}.glb of one frame.
    pub fn frame_glb(&self, frame: &Frame) -> Vec<u8> {
        let zeros = vec![0.0; frame.state.mesh.positions.len()];
        shape_glb(&frame.gltf(&zeros, self.color_by), self.domain.as_ref(), self.extras.clone())
    }

    /// evolution.glb of the frames (in iteration order; at most [`MAX_FRAMES`],
    /// and as many as fit in about [`MAX_EVOLUTION_BYTES`], evenly picked with the
    /// first and last kept). `None` if there are none.
    pub fn evolution_glb(&self, frames: &[Frame]) -> Option<Vec<u8>> {
        if frames.is_empty() {
            return None;
        }
        let sizes: Vec<usize> = frames.iter().map(|f| glb_bytes(&f.state.mesh)).collect();
        let picked: Vec<&Frame> = evolution_picks(&sizes).into_iter().map(|k| &frames[k]).collect();
        let zeros: Vec<Vec<f64>> = picked.iter().map(|f| vec![0.0; f.state.mesh.positions.len()]).collect();
        let drawn: Vec<GltfFrame<'_>> = picked.iter().zip(&zeros).map(|(f, z)| f.gltf(z, self.color_by)).collect();
        let mut extras = self.extras.clone();
        extras["frames"] = json!(drawn.len());
        extras["seconds_per_frame"] = json!(crate::export::FRAME_SECONDS);
        // the animation's length, for importers that set a scene's frame range (the
        // last frame is held for one more frame time)
        extras["animation_seconds"] = json!(drawn.len() as f64 * crate::export::FRAME_SECONDS as f64);
        Some(evolution_glb(&drawn, self.domain.as_ref(), extras))
    }
}

/// The frames evolution.glb shows, of frames of about `sizes` bytes each: all, or
/// as many as [`MAX_FRAMES`] and [`MAX_EVOLUTION_BYTES`] (for frames of the largest
/// size) allow, at least two, evenly picked with the first and last.
fn evolution_picks(sizes: &[usize]) -> Vec<usize> {
    let largest = sizes.iter().copied().max().unwrap_or(1).max(1);
    let fit = (MAX_EVOLUTION_BYTES / largest).clamp(2, MAX_FRAMES);
    let n = sizes.len();
    if n <= fit {
        return (0..n).collect();
    }
    (0..fit).map(|k| k * (n - 1) / (fit - 1)).collect()
}

/// How many frames the size of `frame` evolution.glb shows at most
/// ([`MAX_FRAMES`], and as many as fit in [`MAX_EVOLUTION_BYTES`]; at least two).
pub fn evolution_frames_of(frame: &MeshData) -> usize {
    (MAX_EVOLUTION_BYTES / glb_bytes(frame)).clamp(2, MAX_FRAMES)
}

/// About the bytes a state takes in a glb file: per vertex, a curve's line
/// attributes, filled region and ribbon (measured 186–188 bytes on segmentations
/// of 6,400 and 104,000 vertices), a surface's attributes, normals and triangles
/// (72 bytes measured).
pub(super) fn glb_bytes(mesh: &MeshData) -> usize {
    let per_vertex = if mesh.dimension == 2 { 190 } else { 72 };
    per_vertex * mesh.positions.len() + 1024
}

/// The job's metadata for the glTF `extras`.
pub fn job_extras(job: &PreparedJob) -> Value {
    let spec = serde_json::to_value(&job.spec).unwrap_or(Value::Null);
    json!({"generator": "shapeflow", "problem": spec["problem"]["type"], "spec": spec})
}

/// The fixed domain (`Σ` and `D`) of a shape-design job.
fn domain_outline(job: &PreparedJob) -> Option<DomainOutline> {
    let ProblemKind::ShapeDesign(p) = &job.problem else { return None };
    let points = |q: &Polygon| q.points().iter().map(|x| [x[0], x[1]]).collect::<Vec<_>>();
    let [inner, outer] = p.domain.control();
    Some(DomainOutline { outer: points(p.domain.outer()), control: [points(inner), points(outer)] })
}

/// Makes the frames of a run's checkpoints as they come ([`Frame::of`]), each
/// with its drawing ([`Frame::with_fill`]) while the frames so far fit in
/// evolution.glb's size ([`MAX_EVOLUTION_BYTES`]): beyond it only some of them are
/// drawn, when the result files are made, and the drawings of all would hold
/// memory for nothing (on a 2048² segmentation of 1,650 nuclei, 0.8 GB).
#[derive(Debug)]
pub struct FrameMaker {
    /// The estimated glb bytes of the frames so far, and the most drawn ahead.
    bytes: usize,
    budget: usize,
}

impl Default for FrameMaker {
    fn default() -> Self {
        FrameMaker { bytes: 0, budget: MAX_EVOLUTION_BYTES }
    }
}

impl FrameMaker {
    /// The frame of `state`, a state of this process's run, drawn if the frames so far fit.
    pub fn make(&mut self, job: &PreparedJob, state: &Checkpoint) -> Frame {
        let frame = Frame::of_run(job, state);
        self.bytes += glb_bytes(&frame.state.mesh);
        if self.bytes <= self.budget {
            frame.with_fill()
        } else {
            frame
        }
    }
}

/// shape.glb / checkpoints/{n}.glb of one state of `job` (its fields computed).
pub fn state_glb(job: &PreparedJob, state: &Checkpoint) -> Vec<u8> {
    GlbContext::of(job).frame_glb(&Frame::of(job, state))
}

/// evolution.glb of the states of `job` (their fields computed). `None` if there
/// are none.
pub fn states_glb(job: &PreparedJob, states: &[Checkpoint]) -> Option<Vec<u8>> {
    let frames: Vec<Frame> = states.iter().map(|s| Frame::of(job, s)).collect();
    GlbContext::of(job).evolution_glb(&frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jobs::{parse_spec, prepare, run_prepared, run_with_frames};
    use std::sync::atomic::AtomicBool;

    /// A curvature flow of a 48-gon with a checkpoint every 5 of its 20 steps, and
    /// its checkpoints.
    fn short_run() -> (PreparedJob, Vec<Checkpoint>) {
        let spec = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 48},
          "flow": {"tau": 1e-3, "end_time": 0.02, "tolerance": 0}, "output": {"checkpoint_every": 5}}"#;
        let job = prepare(parse_spec(spec).unwrap(), &Default::default()).unwrap();
        let mut kept = Vec::new();
        run_prepared(&job, None, &AtomicBool::new(false), &mut kept).unwrap();
        (job, kept)
    }

    /// The glb files of frames whose drawing was computed ahead (as a worker does)
    /// are those computed from the frames alone, byte for byte.
    #[test]
    fn a_fill_computed_ahead_draws_the_same() {
        let (job, kept) = short_run();
        let now: Vec<Frame> = kept.iter().map(|c| Frame::of(&job, c)).collect();
        let ahead: Vec<Frame> = now.iter().cloned().map(Frame::with_fill).collect();
        assert!(now.len() > 2 && ahead.iter().all(|f| matches!(f.fill.as_deref(), Some(Some(_)))));
        let context = GlbContext::of(&job);
        assert_eq!(context.evolution_glb(&ahead), context.evolution_glb(&now));
        assert_eq!(context.frame_glb(&ahead[1]), context.frame_glb(&now[1]));
        // made on a second thread during the run: the same frames, in order, and
        // the events passed on
        let mut heard = Vec::new();
        let (result, during) = run_with_frames(&job, None, &AtomicBool::new(false), &mut heard);
        assert_eq!(result.unwrap().last, *kept.last().unwrap());
        assert_eq!(heard, kept);
        assert_eq!(during.iter().map(|f| &f.state).collect::<Vec<_>>(), kept.iter().collect::<Vec<_>>());
        assert_eq!(context.evolution_glb(&during), context.evolution_glb(&now));
    }

    /// Frames beyond the size that evolution.glb holds are not drawn ahead, and
    /// the glb files of frames drawn ahead or not are the same.
    #[test]
    fn frames_are_drawn_ahead_while_they_fit() {
        let (job, kept) = short_run();
        let one = glb_bytes(&kept[0].mesh);
        let mut maker = FrameMaker { bytes: 0, budget: 2 * one + one / 2 };
        let made: Vec<Frame> = kept.iter().map(|c| maker.make(&job, c)).collect();
        let drawn: Vec<bool> = made.iter().map(|f| f.fill.is_some()).collect();
        assert_eq!(drawn[..3], [true, true, false]);
        assert!(drawn[3..].iter().all(|d| !d));
        let all: Vec<Frame> = kept.iter().map(|c| Frame::of(&job, c).with_fill()).collect();
        let context = GlbContext::of(&job);
        assert_eq!(context.evolution_glb(&made), context.evolution_glb(&all));
    }

    /// evolution.glb keeps every frame while they fit, else fewer, evenly spread,
    /// the first and last always.
    #[test]
    fn large_frames_are_subsampled_to_the_size_limit() {
        let mb = 1024 * 1024;
        assert_eq!(evolution_picks(&[mb; 12]), (0..12).collect::<Vec<_>>());
        // 64 MiB hold three frames of 20 MiB
        assert_eq!(evolution_picks(&[20 * mb; 20]), vec![0, 9, 19]);
        // one large frame sets the count for all
        let mut sizes = vec![mb; 30];
        sizes[29] = 16 * mb;
        assert_eq!(evolution_picks(&sizes), vec![0, 9, 19, 29]);
        // never fewer than the first and last, never more than MAX_FRAMES
        assert_eq!(evolution_picks(&[200 * mb; 5]), vec![0, 4]);
        let many = evolution_picks(&[1000; 2000]);
        assert_eq!((many.len(), many[0], many[MAX_FRAMES - 1]), (MAX_FRAMES, 0, 1999));
        assert_eq!(evolution_picks(&[mb]), vec![0]);
    }
}
