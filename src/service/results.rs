//! Result files of a job: the manifest, shape.glb, evolution.glb and the
//! checkpoints (list and one .glb each). glTF is built on request from the stored
//! checkpoints (on the blocking pool: it recomputes curvature and normal velocity).

use super::{find, ApiError, AppState};
use crate::flow::Checkpoint;
use crate::jobs::{parse_spec, prepare, state_glb, states_glb, PreparedJob};
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde_json::{json, Value};
use std::collections::HashMap;

const GLB: &str = "model/gltf-binary";

/// The job rebuilt from its stored spec (for the problem behind the fields).
async fn rebuild(state: &AppState, id: &str) -> Result<PreparedJob, ApiError> {
    let row = find(state, id).await?;
    let spec = parse_spec(&row.spec).map_err(|e| ApiError::Internal(format!("stored spec of {id}: {e}")))?;
    prepare(spec, &HashMap::new()).map_err(|e| ApiError::Internal(format!("stored spec of {id}: {e}")))
}

fn glb_response(bytes: Vec<u8>, name: &str) -> Response {
    (
        [
            (header::CONTENT_TYPE, GLB.to_string()),
            (header::CONTENT_DISPOSITION, format!("inline; filename=\"{name}\"")),
        ],
        bytes,
    )
        .into_response()
}

async fn blocking<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f).await.map_err(|e| ApiError::Internal(e.to_string()))
}

/// `GET /v1/jobs/{id}/results`: the result files available now.
pub(super) async fn manifest(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let job = find(&state, &id).await?;
    let index = state.store.checkpoint_index(&id).await?;
    let base = format!("/v1/jobs/{id}");
    let mut files = vec![
        json!({"name": "energy", "href": format!("{base}/energy"), "type": "application/json"}),
        json!({"name": "energy.csv", "href": format!("{base}/energy?format=csv"), "type": "text/csv"}),
        json!({"name": "energy.svg", "href": format!("{base}/energy.svg"), "type": "image/svg+xml"}),
    ];
    if !index.is_empty() {
        files.push(
            json!({"name": "shape.json", "href": format!("{base}/results/shape.json"), "type": "application/json"}),
        );
        files.push(json!({"name": "shape.glb", "href": format!("{base}/results/shape.glb"), "type": GLB}));
        files.push(json!({"name": "evolution.glb", "href": format!("{base}/results/evolution.glb"), "type": GLB}));
    }
    Ok(Json(json!({
        "id": id,
        "status": job.status,
        "final": matches!(job.status.as_str(), "successful" | "failed" | "dismissed"),
        "files": files,
        "checkpoints": format!("{base}/checkpoints"),
    })))
}

/// `GET /v1/jobs/{id}/results/shape.glb`: the final (or latest) state.
pub(super) async fn shape_glb(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = rebuild(&state, &id).await?;
    let cp = state
        .store
        .last_checkpoint(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?;
    let bytes = blocking(move || state_glb(&job, &cp)).await?;
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

/// `GET /v1/jobs/{id}/checkpoints`: iteration, time and link of every checkpoint.
pub(super) async fn checkpoint_list(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<Value>, ApiError> {
    find(&state, &id).await?;
    let index = state.store.checkpoint_index(&id).await?;
    let list: Vec<Value> = index
        .iter()
        .map(|(it, t)| json!({"iteration": it, "time": t, "href": format!("/v1/jobs/{id}/checkpoints/{it}.glb")}))
        .collect();
    Ok(Json(json!({ "checkpoints": list })))
}

/// `GET /v1/jobs/{id}/checkpoints/{n}.glb`.
pub(super) async fn checkpoint_glb(
    State(state): State<AppState>,
    Path((id, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let job = rebuild(&state, &id).await?;
    let n: i64 = file
        .strip_suffix(".glb")
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| ApiError::NotFound(format!("no checkpoint file {file:?}: expected {{iteration}}.glb")))?;
    let cp = state
        .store
        .checkpoint_at(&id, n)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no checkpoint at iteration {n}")))?;
    let bytes = blocking(move || state_glb(&job, &cp)).await?;
    Ok(glb_response(bytes, &file))
}
