//! `POST /v1/jobs/{id}/cancel`: an accepted job is dismissed at once; a running one
//! stops at its next step (on whichever node runs it); 409 for an ended job.

use super::super::find;
use crate::service::wire::JobView;
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use std::sync::atomic::Ordering;

pub(in crate::service::routes) async fn cancel(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let job = find(&state, &id).await?;
    if job.status.is_final() {
        return Err(ApiError::Conflict(format!("job {id} is already {}", job.status.as_str())));
    }
    state.store.request_cancel(&id).await?;
    // a job of this node stops at once; another node's sees the flag at its next write
    if let Some(flag) = state.registry.lock().unwrap().get(&id) {
        flag.store(true, Ordering::Relaxed);
    }
    let job = find(&state, &id).await?;
    Ok((StatusCode::ACCEPTED, Json(JobView::from(&job))).into_response())
}
