//! `GET /v1/jobs/{id}/energy` (JSON, or `?format=csv`) and `GET
//! /v1/jobs/{id}/energy.svg`: the energy history. The JSON and CSV bodies are
//! streamed a page of rows at a time, and the plot is drawn from at most
//! [`PLOT_POINTS`] rows, so that a request's memory does not grow with the job's
//! history.

use super::thinned::Thinned;
use super::{find, query};
use crate::export::energy_svg;
use crate::flow::Progress;
use crate::service::store::Store;
use crate::service::{ApiError, AppState};
use axum::body::Body;
use axum::extract::rejection::QueryRejection;
use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use futures_util::StreamExt;
use serde::Deserialize;
use std::fmt::Write;

/// History rows read from the store at a time.
const PAGE: usize = 4096;

/// Most rows the plot is drawn from (evenly thinned beyond).
pub const PLOT_POINTS: usize = 8192;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FormatQuery {
    format: Option<String>,
}

#[derive(Clone, Copy)]
enum Format {
    Json,
    Csv,
}

pub(super) async fn history(
    State(state): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<FormatQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let q = query(q)?;
    let format = match q.format.as_deref() {
        Some("csv") => Format::Csv,
        None | Some("json") => Format::Json,
        Some(other) => {
            return Err(ApiError::InvalidParameter {
                parameter: "format".into(),
                detail: format!("unknown format {other:?} (json or csv)"),
            })
        }
    };
    find(&state, &id).await?;
    // the first page now: a store error is an error response, not a cut body
    let first = state.store.history_from(&id, 0, PAGE).await?;
    let (ctype, head, tail) = match format {
        Format::Json => ("application/json", "{\"history\":[", "]}"),
        Format::Csv => ("text/csv", "iteration,time,tau,energy,vertices,components\n", ""),
    };
    let body = futures_util::stream::once(async move { Ok::<_, std::io::Error>(head.to_string()) })
        .chain(pages(state.store.clone(), id, first).enumerate().map(move |(k, page)| {
            page.map(|rows| encode(&rows, format, k == 0)).map_err(|e| {
                tracing::warn!("a history stream stopped: {e}");
                std::io::Error::other("the history could not be read to its end")
            })
        }))
        .chain(futures_util::stream::once(async move { Ok(tail.to_string()) }));
    Ok(([(header::CONTENT_TYPE, ctype)], Body::from_stream(body)).into_response())
}

/// The pages of a job's history rows, `first` the first of them.
fn pages(
    store: Store,
    id: String,
    first: Vec<Progress>,
) -> impl futures_util::Stream<Item = Result<Vec<Progress>, crate::service::store::StoreError>> {
    futures_util::stream::unfold(Some(first), move |next| {
        let (store, id) = (store.clone(), id.clone());
        async move {
            let page = next?;
            let after = (page.len() == PAGE).then(|| page.last().map(|p| p.iteration + 1)).flatten();
            let following = match after {
                Some(from) => match store.history_from(&id, from, PAGE).await {
                    Ok(rows) if rows.is_empty() => None,
                    Ok(rows) => Some(rows),
                    Err(e) => return Some((Err(e), None)),
                },
                None => None,
            };
            (!page.is_empty()).then_some((Ok(page), following))
        }
    })
}

/// The rows of a page as JSON array members (after a comma unless `first`) or CSV lines.
fn encode(rows: &[Progress], format: Format, first: bool) -> String {
    let mut s = String::with_capacity(rows.len() * 120);
    for (k, p) in rows.iter().enumerate() {
        match format {
            Format::Json => {
                if !(first && k == 0) {
                    s.push(',');
                }
                s.push_str(&serde_json::to_string(p).expect("rows serialize"));
            }
            Format::Csv => {
                let _ = writeln!(
                    s,
                    "{},{:e},{:e},{:e},{},{}",
                    p.iteration, p.time, p.tau, p.energy, p.vertices, p.components
                );
            }
        }
    }
    s
}

pub(super) async fn plot(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    let first = state.store.history_from(&id, 0, PAGE).await?;
    let mut rows = std::pin::pin!(pages(state.store.clone(), id.clone(), first));
    let mut plotted = Thinned::new(PLOT_POINTS);
    while let Some(page) = rows.next().await {
        page?.into_iter().for_each(|p| plotted.push(p));
    }
    Ok(([(header::CONTENT_TYPE, "image/svg+xml")], energy_svg(&plotted.into_items(), &format!("job {id}")))
        .into_response())
}
