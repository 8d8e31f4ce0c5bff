//! `GET /v1/jobs?status=&limit=&page_token=`: newest first, `limit` (1–1000,
//! default 100) per page; `next_page_token` is present when more jobs follow.

use super::super::query;
use crate::service::keys::Caller;
use crate::service::store::JobStatus;
use crate::service::wire::{JobList, JobView};
use crate::service::{ApiError, AppState};
use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::response::{IntoResponse, Response};
use axum::Extension;
use axum::Json;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::service::routes) struct ListQuery {
    status: Option<String>,
    limit: Option<String>,
    page_token: Option<String>,
}

pub(in crate::service::routes) async fn list(
    State(state): State<AppState>,
    Extension(caller): Extension<Caller>,
    q: Result<Query<ListQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let q = query(q)?;
    let status = match q.status.as_deref() {
        None => None,
        Some(s) => Some(JobStatus::parse(s).ok_or_else(|| {
            let all: Vec<&str> = JobStatus::ALL.iter().map(|s| s.as_str()).collect();
            let detail = format!("unknown status {s:?}; one of {}", all.join(", "));
            ApiError::InvalidParameter { parameter: "status".into(), detail }
        })?),
    };
    let limit = match q.limit.as_deref().map(|l| (l, l.parse::<i64>())) {
        None => 100,
        Some((_, Ok(l @ 1..=1000))) => l,
        Some((l, _)) => {
            let detail = format!("must be an integer from 1 to 1000, got {l:?}");
            return Err(ApiError::InvalidParameter { parameter: "limit".into(), detail });
        }
    };
    let before = match q.page_token.as_deref() {
        None | Some("") => None,
        Some(t) => Some(
            t.strip_prefix("p")
                .filter(|h| !h.is_empty() && h.len() <= 15 && h.bytes().all(|b| b.is_ascii_hexdigit()))
                .and_then(|h| i64::from_str_radix(h, 16).ok())
                .ok_or_else(|| ApiError::InvalidParameter {
                    parameter: "page_token".into(),
                    detail: format!("not a page token of this list: {t:?}"),
                })?,
        ),
    };
    let owner = caller.owner().filter(|_| !caller.sees_all());
    let mut jobs = state.store.list(status, before, limit + 1, owner).await?;
    let more = jobs.len() as i64 > limit;
    jobs.truncate(limit as usize);
    let next_page_token = jobs.last().filter(|_| more).map(|last| format!("p{:x}", last.seq));
    Ok(Json(JobList { jobs: jobs.iter().map(JobView::from).collect(), next_page_token }).into_response())
}
