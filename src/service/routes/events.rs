//! `GET /v1/jobs/{id}/events`: Server-Sent Events of a job. The stream reads the
//! database when the job is announced on the node's broadcast channel (on SQLite
//! by its own workers after each batch; on PostgreSQL by the notifications of
//! every node's batches, its own included; a job's outcome also by the worker
//! that ends it, at once), never on a fixed short period.

use super::find;
use crate::service::wire::JobView;
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use tokio::sync::broadcast;

/// History rows read at a time by a stream.
const PAGE: usize = 1000;

/// Server-Sent Events: one `progress` event per iteration (`id` = iteration, so a
/// reconnect with `Last-Event-ID` continues after it), then one `status` event with
/// the finished job, and the stream ends. Keep-alive comments every 15 s; streams end
/// when the server shuts down.
pub(super) async fn events(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    use axum::response::sse::{Event, KeepAlive, Sse};
    find(&state, &id).await?;
    let after: Option<usize> = match headers.get("last-event-id") {
        None => None,
        Some(v) => Some(v.to_str().ok().and_then(|v| v.trim().parse().ok()).ok_or_else(|| {
            ApiError::BadRequest(
                "Last-Event-ID: must be the id of an event of this stream (an iteration number)".into(),
            )
        })?),
    };
    struct Cursor {
        state: AppState,
        id: String,
        next: usize,
        pending: std::collections::VecDeque<Event>,
        done: bool,
        /// Subscribed before the first read, so that no batch falls between a read
        /// and the wait.
        events: broadcast::Receiver<Arc<str>>,
    }
    let events = state.events.subscribe();
    let next = after.map_or(0, |a| a + 1);
    let cursor = Cursor { state, id, next, pending: Default::default(), done: false, events };
    let stream = futures_util::stream::unfold(cursor, |mut c| async move {
        loop {
            if let Some(e) = c.pending.pop_front() {
                return Some((Ok::<Event, std::convert::Infallible>(e), c));
            }
            if c.done || c.state.closing.load(Ordering::Relaxed) {
                return None;
            }
            let job = c.state.store.job(&c.id).await.ok().flatten();
            // a page at a time: streams catching up on a long history take turns
            let rows = c.state.store.history_from(&c.id, c.next, PAGE).await.unwrap_or_default();
            for p in rows {
                c.next = p.iteration + 1;
                let data = serde_json::to_string(&p).expect("progress serializes");
                c.pending.push_back(Event::default().event("progress").id(p.iteration.to_string()).data(data));
            }
            match job {
                Some(j) if j.status.is_final() && c.pending.is_empty() => {
                    let data = serde_json::to_string(&JobView::from(&j)).expect("a job serializes");
                    c.pending.push_back(Event::default().event("status").data(data));
                    c.done = true;
                }
                None => c.done = true,
                _ if c.pending.is_empty() => wait_for_job(&mut c.events, &c.id, &c.state.closing).await,
                _ => {}
            }
        }
    });
    let sse = Sse::new(stream).keep_alive(KeepAlive::new().interval(std::time::Duration::from_secs(15)));
    Ok(([("x-accel-buffering", "no")], sse).into_response())
}

/// Wait until `events` announces job `id` (or asks every stream to re-read), the
/// server closes, or 5 s pass (a safety net for a missed notification).
async fn wait_for_job(events: &mut broadcast::Receiver<Arc<str>>, id: &str, closing: &AtomicBool) {
    let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(5);
    loop {
        let wait = tokio::time::timeout_at(
            deadline.min(tokio::time::Instant::now() + std::time::Duration::from_millis(250)),
            events.recv(),
        );
        match wait.await {
            Ok(Ok(e)) if &*e == id || &*e == "*" => return,
            Ok(Ok(_)) => {}
            // lagged behind: some announcement may have been ours
            Ok(Err(broadcast::error::RecvError::Lagged(_))) => return,
            Ok(Err(broadcast::error::RecvError::Closed)) => return,
            Err(_) if closing.load(Ordering::Relaxed) || tokio::time::Instant::now() >= deadline => return,
            Err(_) => {}
        }
    }
}
