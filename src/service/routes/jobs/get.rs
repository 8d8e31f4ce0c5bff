//! `GET /v1/jobs/{id}`: status and progress of a job.

use super::super::find;
use crate::service::wire::JobView;
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::response::{IntoResponse, Response};
use axum::Json;

pub(in crate::service::routes) async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let job = find(&state, &id).await?;
    Ok(Json(JobView::from(&job)).into_response())
}
