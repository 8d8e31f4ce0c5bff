//! `GET /v1/jobs/{id}/energy` (JSON, or `?format=csv`) and `GET
//! /v1/jobs/{id}/energy.svg`: the energy history.

use super::{find, query};
use crate::export::{energy_csv, energy_svg};
use crate::service::wire::History;
use crate::service::{ApiError, AppState};
use axum::extract::rejection::QueryRejection;
use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FormatQuery {
    format: Option<String>,
}

pub(super) async fn history(
    State(state): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<FormatQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let q = query(q)?;
    find(&state, &id).await?;
    let rows = state.store.history(&id).await?;
    match q.format.as_deref() {
        Some("csv") => Ok(([(header::CONTENT_TYPE, "text/csv")], energy_csv(&rows)).into_response()),
        None | Some("json") => Ok(Json(History { history: rows }).into_response()),
        Some(other) => Err(ApiError::InvalidParameter {
            parameter: "format".into(),
            detail: format!("unknown format {other:?} (json or csv)"),
        }),
    }
}

pub(super) async fn plot(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    let rows = state.store.history(&id).await?;
    Ok(([(header::CONTENT_TYPE, "image/svg+xml")], energy_svg(&rows, &format!("job {id}"))).into_response())
}
