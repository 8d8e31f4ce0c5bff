//! `DELETE /v1/jobs/{id}`: a job that has ended, with its history, checkpoints,
//! inputs and files; 409 while it is accepted or running. It is gone from every
//! read at once; its rows and blobs go in the background (`retention`).

use super::super::find;
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::http::StatusCode;

pub(in crate::service::routes) async fn delete(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    let job = find(&state, &id).await?;
    if !job.status.is_final() {
        return Err(ApiError::Conflict(format!("job {id} is {}; cancel it first", job.status.as_str())));
    }
    match state.store.mark_deleted(&id).await? {
        true => Ok(StatusCode::NO_CONTENT),
        // deleted meanwhile by another request
        false => Err(ApiError::NotFound(format!("no job {id}"))),
    }
}
