//! `GET /v1/jobs/{id}/checkpoints` (iteration, time and link of each) and
//! `GET /v1/jobs/{id}/checkpoints/{n}.glb` (one checkpoint as glTF).

use super::results::{frames_to_draw, glb_response};
use super::{blocking, find};
use crate::service::store::Which;
use crate::service::wire::{CheckpointEntry, CheckpointList};
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::response::{IntoResponse, Response};
use axum::Json;

/// `GET /v1/jobs/{id}/checkpoints`: iteration, time and link of every checkpoint.
pub(super) async fn list(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    let index = state.store.checkpoint_index(&id).await?;
    let checkpoints = index
        .iter()
        .map(|&(iteration, time)| CheckpointEntry {
            iteration,
            time,
            href: format!("/v1/jobs/{id}/checkpoints/{iteration}.glb"),
        })
        .collect();
    Ok(Json(CheckpointList { checkpoints }).into_response())
}

/// `GET /v1/jobs/{id}/checkpoints/{n}.glb`: encoded from the stored frame.
pub(super) async fn glb(
    State(state): State<AppState>,
    Path((id, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    let n: i64 = file
        .strip_suffix(".glb")
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| ApiError::NotFound(format!("no checkpoint file {file:?}: expected {{iteration}}.glb")))?;
    let missing = || ApiError::NotFound(format!("job {id} has no checkpoint at iteration {n}"));
    let (context, mut frames) = frames_to_draw(&state, &id, Which::At(n)).await?.ok_or_else(missing)?;
    let frame = frames.pop().ok_or_else(missing)?;
    let bytes = blocking(move || context.frame_glb(&frame)).await?;
    Ok(glb_response(bytes, &file))
}
