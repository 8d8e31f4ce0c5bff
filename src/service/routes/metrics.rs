//! `GET /metrics`: the node's metrics in Prometheus' (OpenMetrics) text format
//! ([`crate::service::metrics`]), and the layer that counts every routed
//! request.

use crate::service::{ApiError, AppState};
use axum::extract::{MatchedPath, Request, State};
use axum::http::header;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::time::Instant;

pub(super) async fn metrics(State(state): State<AppState>) -> Result<Response, ApiError> {
    state.metrics.set_jobs(&state.store.counts_by_status().await?);
    if state.metrics.stored_bytes_due() {
        // listing a large store takes time: the next scrape shows it
        let (store, metrics) = (state.store.clone(), state.metrics.clone());
        tokio::spawn(async move {
            match store.blobs().size_all(&["jobs"]).await {
                Ok(bytes) => metrics.set_stored_bytes(bytes),
                Err(e) => tracing::warn!("cannot measure the blob store: {e}"),
            }
        });
    }
    let ctype = "application/openmetrics-text; version=1.0.0; charset=utf-8";
    Ok(([(header::CONTENT_TYPE, ctype)], state.metrics.render()).into_response())
}

/// Count a routed request and its latency, by its route's pattern.
pub(super) async fn observe(State(state): State<AppState>, req: Request, next: Next) -> Response {
    let route = req.extensions().get::<MatchedPath>().map_or("(none)".to_string(), |p| p.as_str().to_string());
    let method = req.method().to_string();
    let start = Instant::now();
    let response = next.run(req).await;
    let m = &state.metrics;
    let labels =
        crate::service::metrics::RequestLabels { route: route.clone(), method, status: response.status().as_u16() };
    m.requests.get_or_create(&labels).inc();
    m.request_seconds
        .get_or_create(&crate::service::metrics::RouteLabels { route })
        .observe(start.elapsed().as_secs_f64());
    response
}
