//! The result files of a job ([`result_files`]: one list for the CLI and the
//! service) and what its latest state shows ([`result_state`]).

use super::frames::{Frame, GlbContext};
use super::vtk_files::{frame_vtp, vtk_series, zip_files, EVOLUTION_VTK_ZIP};
use super::PreparedJob;
use crate::export::{
    labels_png, labels_tiff, mask, mask_png, objects, objects_csv, overlay_png, rois_zip, shape_json, ObjectRow,
};
use crate::flow::{Checkpoint, MeshData};
use crate::geometry::{loop_area, Point};
use crate::imaging::{encode_nifti_labels, encode_nifti_mask, encode_nrrd_labels, encode_nrrd_mask, Grid};
use crate::problems::refine_to_edges;
use serde_json::Value;
use std::borrow::Cow;
use std::cell::OnceCell;

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
/// each computed on request; the objects (label image and table) and the mask,
/// which several of them share, once.
pub struct StateResults<'a> {
    job: &'a PreparedJob,
    shown: &'a Checkpoint,
    objects: OnceCell<(Vec<u16>, Vec<ObjectRow>)>,
    mask: OnceCell<Vec<bool>>,
    found: OnceCell<MeshData>,
}

impl<'a> StateResults<'a> {
    pub fn new(job: &'a PreparedJob, shown: &'a Checkpoint) -> Self {
        StateResults { job, shown, objects: OnceCell::new(), mask: OnceCell::new(), found: OnceCell::new() }
    }

    fn objects(&self, image: &Grid) -> &(Vec<u16>, Vec<ObjectRow>) {
        self.objects.get_or_init(|| objects(image, self.found()))
    }

    /// The mask of a volume, which mask.nrrd and mask.nii.gz share.
    fn mask(&self, image: &Grid) -> &[bool] {
        self.mask.get_or_init(|| mask(image, self.found()))
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
    /// table of objects (`"objects"`); the run's topological surgeries
    /// (`"surgeries"`) if it had any.
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
        if !shown.surgeries.is_empty() {
            doc["surgeries"] = serde_json::to_value(&shown.surgeries).unwrap_or(Value::Null);
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
            "mask.nrrd" => encode_nrrd_mask(img, self.mask(img)),
            "labels.png" => labels_png(img, &self.objects(img).0),
            "labels.nrrd" => encode_nrrd_labels(img, &self.objects(img).0),
            "mask.nii.gz" => encode_nifti_mask(img, self.mask(img)),
            "labels.nii.gz" => encode_nifti_labels(img, &self.objects(img).0),
            "objects.csv" => objects_csv(img.dimension, &self.objects(img).1).into_bytes(),
            "labels.tif" | "labels.ome.tif" => labels_tiff(img, &self.objects(img).0),
            "rois.zip" => rois_zip(img, self.found()),
            _ => return None,
        };
        Some((media, bytes))
    }
}

/// An image job's results as arrays in the order of the image as an array
/// (2D `(row, column)` rows from the top, 3D `(plane, row, column)`; C order of `shape`).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageArrays {
    pub shape: Vec<usize>,
    pub mask: Vec<bool>,
    pub labels: Vec<u16>,
    pub objects: Vec<ObjectRow>,
}

impl StateResults<'_> {
    /// The mask, the label image and the table of objects of an image job as
    /// arrays ([`ImageArrays`]); `None` for a job without an image.
    pub fn image_arrays(&self) -> Option<ImageArrays> {
        let img = self.job.image.as_deref()?;
        let (labels, objects) = self.objects(img);
        Some(ImageArrays {
            shape: img.array_shape(),
            mask: img.to_array(self.mask(img)),
            labels: img.to_array(labels),
            objects: objects.clone(),
        })
    }
}

/// Names and media types of the image results of a 2D image or a volume: the
/// mask, the overlay (2D), the label image (volumes: both as NRRD and as NIfTI-1)
/// and the table of objects; then (additions) the label image as TIFF (2D) or
/// OME-TIFF (volumes) and the contours as an ImageJ ROI set (2D).
pub fn image_result_names(dimension: usize) -> &'static [(&'static str, &'static str)] {
    if dimension == 2 {
        &[
            ("mask.png", "image/png"),
            ("overlay.png", "image/png"),
            ("labels.png", "image/png"),
            ("objects.csv", "text/csv"),
            ("labels.tif", "image/tiff"),
            ("rois.zip", "application/zip"),
        ]
    } else {
        &[
            ("mask.nrrd", "application/octet-stream"),
            ("labels.nrrd", "application/octet-stream"),
            ("mask.nii.gz", "application/gzip"),
            ("labels.nii.gz", "application/gzip"),
            ("objects.csv", "text/csv"),
            ("labels.ome.tif", "image/tiff"),
        ]
    }
}

/// One result file: its name, media type and bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct ResultFile {
    pub name: Cow<'static, str>,
    pub media_type: Cow<'static, str>,
    pub bytes: Vec<u8>,
}

/// The result files of a run whose frames (checkpoints with their fields, the
/// last one its final state) are `frames`: shape.json, shape.glb and shape.vtp of what the
/// final state shows ([`result_state`]), evolution.glb and the VTK time series
/// (evolution_vtk.zip: evolution.pvd and its frames) of every frame, and for an
/// image job its mask, overlay, label image and table of objects
/// ([`image_result_names`]). Empty if there is no frame. The CLI writes these to
/// its output directory; the service stores them when a job ends.
pub fn result_files(job: &PreparedJob, frames: &[Frame]) -> Vec<ResultFile> {
    if frames.is_empty() {
        return Vec::new();
    }
    let context = GlbContext::of(job);
    // evolution.glb, the largest, on a second thread beside the others
    let (evolution, (mut files, image_files)) = std::thread::scope(|scope| {
        let evolution = scope.spawn(|| context.evolution_glb(frames));
        let state = state_files(job, &context, frames);
        (evolution.join().expect("evolution.glb panicked"), state)
    });
    files.extend(evolution.map(|bytes| ResultFile { name: "evolution.glb".into(), media_type: GLB.into(), bytes }));
    files.push(ResultFile {
        name: EVOLUTION_VTK_ZIP.into(),
        media_type: "application/zip".into(),
        bytes: zip_files(&vtk_series(job, frames)),
    });
    files.extend(image_files);
    files
}

/// The result files of the state the last of `frames` shows: shape.json and
/// shape.glb, and an image job's files.
fn state_files(job: &PreparedJob, context: &GlbContext, frames: &[Frame]) -> (Vec<ResultFile>, Vec<ResultFile>) {
    let last = frames.last().expect("a frame");
    let shown = result_state(job, &last.state);
    // the fields of the shown state: the last frame's, unless the contour moved
    let shown_frame = if shown == last.state { last.clone() } else { Frame::of_run(job, &shown) };
    let results = StateResults::new(job, &shown);
    let json = serde_json::to_vec_pretty(&results.shape_document()).expect("shape.json serializes");
    let shape = vec![
        ResultFile { name: "shape.json".into(), media_type: "application/json".into(), bytes: json },
        ResultFile { name: "shape.glb".into(), media_type: GLB.into(), bytes: context.frame_glb(&shown_frame) },
        ResultFile { name: "shape.vtp".into(), media_type: VTP.into(), bytes: frame_vtp(job, &shown_frame) },
    ];
    let names = job.image.as_deref().map_or(&[][..], |img| image_result_names(img.dimension));
    let images = names
        .iter()
        .filter_map(|&(name, media_type)| {
            results.image_file(name).map(|(_, bytes)| ResultFile {
                name: name.into(),
                media_type: media_type.into(),
                bytes,
            })
        })
        .collect();
    (shape, images)
}

/// The media type of glTF binary files.
pub const GLB: &str = "model/gltf-binary";

/// The media type of VTK PolyData files (XML).
pub const VTP: &str = "application/xml";
