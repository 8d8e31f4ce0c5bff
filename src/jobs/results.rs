//! glTF results of a job from its checkpoints: each state with its per-vertex
//! curvature and normal velocity (recomputed from the job's problem on that state).

use super::run::vertex_fields;
use super::spec::ColorBy;
use super::{PreparedJob, ProblemKind};
use crate::bulk::Polygon;
use crate::export::{
    evolution_glb, labels_png, mask_nrrd, mask_png, objects, objects_csv, overlay_png, shape_glb, shape_json,
    ColorField, DomainOutline, GltfFrame, ObjectRow,
};
use crate::flow::{Checkpoint, MeshData, VertexFields};
use crate::geometry::{loop_area, Point};
use crate::imaging::{encode_nrrd_labels, Grid};
use crate::problems::refine_to_edges;
use serde_json::{json, Value};
use std::cell::OnceCell;

pub use crate::limits::MAX_FRAMES;

/// The state a job's results show (shape.json, shape.glb, the mask and the overlay):
/// for a segmentation with `problem.edge_refinement` (default on), `state` with its
/// contour moved onto the image's edges to sub-pixel accuracy
/// ([`refine_to_edges`]); otherwise `state` itself. Checkpoints and evolution.glb
/// keep the flow's own states, and a run resumes from those.
pub fn result_state(job: &PreparedJob, state: &Checkpoint) -> Checkpoint {
    let Some(field) = job.edges.as_deref() else { return state.clone() };
    let mesh = match (state.mesh.dimension, field.dimension()) {
        (2, 2) => state.mesh.to_mesh::<2>().ok().and_then(|m| {
            let refined = refine_to_edges(field, &m).0;
            // a move that would make the curve cross itself is not taken
            (refined.crossings().len() <= m.crossings().len()).then(|| MeshData::from(&refined))
        }),
        (3, 3) => state.mesh.to_mesh::<3>().ok().map(|m| MeshData::from(&refine_to_edges(field, &m).0)),
        _ => None,
    };
    match mesh {
        Some(mesh) => Checkpoint { mesh, ..state.clone() },
        None => state.clone(),
    }
}

/// The result documents and files of one state `shown` (see [`result_state`]),
/// each computed on request; the objects (label image and table), which several
/// of them share, once.
pub struct StateResults<'a> {
    job: &'a PreparedJob,
    shown: &'a Checkpoint,
    objects: OnceCell<(Vec<u16>, Vec<ObjectRow>)>,
    found: OnceCell<MeshData>,
}

impl<'a> StateResults<'a> {
    pub fn new(job: &'a PreparedJob, shown: &'a Checkpoint) -> Self {
        StateResults { job, shown, objects: OnceCell::new(), found: OnceCell::new() }
    }

    fn objects(&self, image: &Grid) -> &(Vec<u16>, Vec<ObjectRow>) {
        self.objects.get_or_init(|| objects(image, self.found()))
    }

    /// The shape the mask, the labels and the objects show: the shown state without
    /// the contours below the mesh management's `min_area`, which the flow removes
    /// (a run that stops with `vanished` has only such contours, and an empty mask).
    fn found(&self) -> &MeshData {
        self.found.get_or_init(|| {
            let mesh = &self.shown.mesh;
            let min_area = match self.job.curve_manager {
                Some(m) if m.topology_changes => m.params.min_area,
                _ => return mesh.clone(),
            };
            match mesh.to_mesh_unvalidated::<2>() {
                Some(m) if m.period().is_none() => {
                    let kept: Vec<Vec<Point<2>>> = m
                        .cycles()
                        .into_iter()
                        .map(|c| c.iter().map(|&v| m.positions()[v]).collect::<Vec<_>>())
                        .filter(|l| loop_area(l).abs() >= min_area)
                        .collect();
                    let (mut positions, mut elements) = (Vec::new(), Vec::new());
                    for l in kept {
                        let base = positions.len();
                        positions.extend(l.iter().map(|p| vec![p[0], p[1]]));
                        elements.extend((0..l.len()).map(|k| vec![base + k, base + (k + 1) % l.len()]));
                    }
                    MeshData { dimension: 2, positions, elements, period: None }
                }
                _ => mesh.clone(),
            }
        })
    }

    /// shape.json: the shape, and for image jobs the pixel coordinates, the
    /// settings of the segmentation (`"segmentation"`, automatic or given) and the
    /// table of objects (`"objects"`).
    pub fn shape_document(&self) -> Value {
        let (job, shown) = (self.job, self.shown);
        let image = job.image.as_deref();
        let mut doc = shape_json(&shown.mesh, shown.energy, shown.iteration, image);
        if let Some(setup) = &job.segmentation {
            doc["segmentation"] = serde_json::to_value(setup).unwrap_or(Value::Null);
        }
        if let Some(img) = image {
            doc["objects"] = serde_json::to_value(&self.objects(img).1).unwrap_or(Value::Null);
        }
        doc
    }

    /// The image result `name` ([`image_result_names`]) and its media type; `None`
    /// if the job has no such file.
    pub fn image_file(&self, name: &str) -> Option<(&'static str, Vec<u8>)> {
        let img = self.job.image.as_deref()?;
        let media = image_result_names(img.dimension).iter().find(|(n, _)| *n == name)?.1;
        let bytes = match name {
            "mask.png" => mask_png(img, self.found()),
            "overlay.png" => overlay_png(img, &self.shown.mesh),
            "mask.nrrd" => mask_nrrd(img, self.found()),
            "labels.png" => labels_png(img, &self.objects(img).0),
            "labels.nrrd" => encode_nrrd_labels(img.dims, &self.objects(img).0),
            "objects.csv" => objects_csv(img.dimension, &self.objects(img).1).into_bytes(),
            _ => return None,
        };
        Some((media, bytes))
    }
}

/// Names and media types of the image results of a 2D image or a volume: the
/// mask, the overlay (2D), the label image and the table of objects.
pub fn image_result_names(dimension: usize) -> &'static [(&'static str, &'static str)] {
    if dimension == 2 {
        &[
            ("mask.png", "image/png"),
            ("overlay.png", "image/png"),
            ("labels.png", "image/png"),
            ("objects.csv", "text/csv"),
        ]
    } else {
        &[
            ("mask.nrrd", "application/octet-stream"),
            ("labels.nrrd", "application/octet-stream"),
            ("objects.csv", "text/csv"),
        ]
    }
}

/// The job's metadata for the glTF `extras`.
pub fn job_extras(job: &PreparedJob) -> Value {
    let spec = serde_json::to_value(&job.spec).unwrap_or(Value::Null);
    json!({"generator": "shapeflow", "problem": spec["problem"]["type"], "spec": spec})
}

/// Curvature, normal velocity and the problem's own field of `state`; zeros (and
/// no own field) where they cannot be computed (e.g. the last state of a failed
/// run), so that the geometry is still shown.
fn fields(job: &PreparedJob, state: &Checkpoint) -> VertexFields {
    let n = state.mesh.positions.len();
    match vertex_fields(job, state) {
        Ok(f) if f.curvature.len() == n && f.normal_velocity.len() == n => f,
        _ => VertexFields { curvature: vec![0.0; n], normal_velocity: vec![0.0; n], own: None },
    }
}

/// One state to draw, with its fields.
fn frame<'a>(job: &PreparedJob, state: &'a Checkpoint, fields: &'a VertexFields) -> GltfFrame<'a> {
    GltfFrame {
        mesh: &state.mesh,
        curvature: &fields.curvature,
        normal_velocity: &fields.normal_velocity,
        own: fields.own.as_ref().map(|f| (f.name, f.values.as_slice())),
        iteration: state.iteration,
        time: state.time,
        energy: state.energy,
        color_by: color_field(job),
    }
}

/// The field the job's glTF results colour (`output.color_by`).
fn color_field(job: &PreparedJob) -> ColorField {
    match job.spec.output.color_by {
        ColorBy::Curvature => ColorField::Curvature,
        ColorBy::NormalVelocity => ColorField::NormalVelocity,
        ColorBy::ProblemField => ColorField::ProblemField,
    }
}

/// The fixed domain (`Σ` and `D`) of a shape-design job.
fn domain_outline(job: &PreparedJob) -> Option<DomainOutline> {
    let ProblemKind::ShapeDesign(p) = &job.problem else { return None };
    let points = |q: &Polygon| q.points().iter().map(|x| [x[0], x[1]]).collect::<Vec<_>>();
    let [inner, outer] = p.domain.control();
    Some(DomainOutline { outer: points(p.domain.outer()), control: [points(inner), points(outer)] })
}

/// shape.glb / checkpoints/{n}.glb of one state.
pub fn state_glb(job: &PreparedJob, state: &Checkpoint) -> Vec<u8> {
    let fields = fields(job, state);
    shape_glb(&frame(job, state, &fields), domain_outline(job).as_ref(), job_extras(job))
}

/// evolution.glb of the checkpoints (in iteration order). `None` if there are none.
pub fn states_glb(job: &PreparedJob, states: &[Checkpoint]) -> Option<Vec<u8>> {
    if states.is_empty() {
        return None;
    }
    let picked: Vec<&Checkpoint> = if states.len() <= MAX_FRAMES {
        states.iter().collect()
    } else {
        let last = states.len() - 1;
        (0..MAX_FRAMES).map(|k| &states[k * last / (MAX_FRAMES - 1)]).collect()
    };
    let fields: Vec<VertexFields> = picked.iter().map(|s| fields(job, s)).collect();
    let frames: Vec<GltfFrame<'_>> = picked.iter().zip(&fields).map(|(s, f)| frame(job, s, f)).collect();
    let mut extras = job_extras(job);
    extras["frames"] = json!(frames.len());
    extras["seconds_per_frame"] = json!(crate::export::FRAME_SECONDS);
    // the animation's length, for importers that set a scene's frame range (the
    // last frame is held for one more frame time)
    extras["animation_seconds"] = json!(frames.len() as f64 * crate::export::FRAME_SECONDS as f64);
    Some(evolution_glb(&frames, domain_outline(job).as_ref(), extras))
}
