//! `GET /v1/jobs/{id}/results` (the manifest) and the result files: shape.json,
//! shape.glb, evolution.glb and the image results. They are built on request from
//! the stored checkpoints (on the blocking pool: glTF recomputes curvature and
//! normal velocity).

use super::{blocking, find};
use crate::export::shape_json;
use crate::flow::Checkpoint;
use crate::jobs::{
    image_result_names, parse_spec, prepare, result_state, state_glb, states_glb, PreparedJob, StateResults,
};
use crate::service::wire::{Manifest, ResultFile};
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde_json::Value;

pub(super) const GLB: &str = "model/gltf-binary";

/// The job rebuilt from its stored spec (for the problem behind the fields).
pub(super) async fn rebuild(state: &AppState, id: &str) -> Result<PreparedJob, ApiError> {
    let row = find(state, id).await?;
    let spec = parse_spec(&row.spec).map_err(|e| ApiError::Internal(format!("stored spec of {id}: {e}")))?;
    let inputs = state.store.inputs(id).await?;
    blocking(move || prepare(spec, &inputs))
        .await?
        .map_err(|e| ApiError::Internal(format!("stored spec of {}: {e}", row.id)))
}

pub(super) fn glb_response(bytes: Vec<u8>, name: &str) -> Response {
    (
        [
            (header::CONTENT_TYPE, GLB.to_string()),
            (header::CONTENT_DISPOSITION, format!("inline; filename=\"{name}\"")),
        ],
        bytes,
    )
        .into_response()
}

/// `GET /v1/jobs/{id}/results`: the result files available now.
pub(super) async fn manifest(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = find(&state, &id).await?;
    let index = state.store.checkpoint_index(&id).await?;
    let base = format!("/v1/jobs/{id}");
    let file = |name: &str, href: String, media_type| ResultFile { name: name.to_string(), href, media_type };
    let mut files = vec![
        file("energy", format!("{base}/energy"), "application/json"),
        file("energy.csv", format!("{base}/energy?format=csv"), "text/csv"),
        file("energy.svg", format!("{base}/energy.svg"), "image/svg+xml"),
    ];
    if !index.is_empty() {
        files.push(file("shape.json", format!("{base}/results/shape.json"), "application/json"));
        files.push(file("shape.glb", format!("{base}/results/shape.glb"), GLB));
        files.push(file("evolution.glb", format!("{base}/results/evolution.glb"), GLB));
        let spec: Value = serde_json::from_str(&job.spec).unwrap_or(Value::Null);
        if spec["problem"]["type"] == "segmentation" {
            let volume = spec["problem"]["image"].is_array() || is_volume(&state, &id).await?;
            for (name, media) in image_result_names(if volume { 3 } else { 2 }) {
                files.push(file(name, format!("{base}/results/{name}"), media));
            }
        }
    }
    let checkpoints = format!("{base}/checkpoints");
    Ok(Json(Manifest { id: &id, status: job.status, is_final: job.status.is_final(), files, checkpoints })
        .into_response())
}

/// `GET /v1/jobs/{id}/results/shape.json`: the latest state as its results show it
/// (a segmentation's contour refined onto the edges, with pixel coordinates).
pub(super) async fn shape(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let row = find(&state, &id).await?;
    let cp = state
        .store
        .last_checkpoint(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?;
    let spec: Value = serde_json::from_str(&row.spec).unwrap_or(Value::Null);
    if spec["problem"]["type"] != "segmentation" {
        return Ok(Json(shape_json(&cp.mesh, cp.energy, cp.iteration, None)));
    }
    let job = rebuild(&state, &id).await?;
    let doc = blocking(move || StateResults::new(&job, &result_state(&job, &cp)).shape_document()).await?;
    Ok(Json(doc))
}

/// Whether the (single) input image of a segmentation job is an NRRD volume.
async fn is_volume(state: &AppState, id: &str) -> Result<bool, ApiError> {
    Ok(state.store.input_magics(id).await?.iter().any(|b| b.starts_with(b"NRRD")))
}

/// The job, its image and what its latest state shows ([`result_state`]), for
/// image results.
async fn image_job(state: &AppState, id: &str) -> Result<(PreparedJob, Checkpoint), ApiError> {
    let job = rebuild(state, id).await?;
    if job.image.is_none() {
        return Err(ApiError::NotFound(format!("job {id} is not an image job: it has no mask")));
    }
    let cp = state
        .store
        .last_checkpoint(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?;
    blocking(move || {
        let shown = result_state(&job, &cp);
        (job, shown)
    })
    .await
}

/// `GET /v1/jobs/{id}/results/mask.png`, `overlay.png`, `labels.png` (2D),
/// `mask.nrrd`, `labels.nrrd` (3D), `objects.csv`: the segmentation of the latest
/// state ([`StateResults::image_file`]).
pub(super) async fn image_result(
    State(state): State<AppState>,
    Path((id, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let known = [2, 3].iter().any(|&d| image_result_names(d).iter().any(|(n, _)| *n == file));
    if !known {
        state.store.job(&id).await?.ok_or_else(|| ApiError::NotFound(format!("no job {id}")))?;
        return Err(ApiError::NotFound(format!(
            "no result {file:?}; GET /v1/jobs/{id}/results lists this job's files"
        )));
    }
    let (job, cp) = image_job(&state, &id).await?;
    let dimension = job.image.as_ref().map_or(0, |g| g.dimension);
    let wanted = file.clone();
    let found = blocking(move || StateResults::new(&job, &cp).image_file(&wanted)).await?;
    let Some((media, bytes)) = found else {
        return Err(ApiError::NotFound(format!("job {id} has no result {file} ({dimension}D image)")));
    };
    Ok(([(header::CONTENT_TYPE, media)], bytes).into_response())
}

/// `GET /v1/jobs/{id}/results/shape.glb`: the final (or latest) state, as its
/// results show it ([`result_state`]).
pub(super) async fn shape_glb(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = rebuild(&state, &id).await?;
    let cp = state
        .store
        .last_checkpoint(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?;
    let bytes = blocking(move || state_glb(&job, &result_state(&job, &cp))).await?;
    Ok(glb_response(bytes, "shape.glb"))
}

/// `GET /v1/jobs/{id}/results/evolution.glb`: every checkpoint, animated.
pub(super) async fn evolution_glb(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = rebuild(&state, &id).await?;
    let cps: Vec<Checkpoint> = state.store.checkpoints(&id).await?;
    let bytes = blocking(move || states_glb(&job, &cps))
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no checkpoint yet")))?;
    Ok(glb_response(bytes, "evolution.glb"))
}
