//! `GET /v1/jobs/{id}/checkpoints` (iteration, time and link of each) and
//! `GET /v1/jobs/{id}/checkpoints/{n}.glb` (one checkpoint as glTF).

use super::results::{frames_to_draw, glb_response};
use super::{blocking, find};
use crate::service::store::{Which, CHECKPOINT_PAGE};
use crate::service::wire::CheckpointEntry;
use crate::service::{ApiError, AppState};
use axum::body::Body;
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use futures_util::StreamExt;

/// `GET /v1/jobs/{id}/checkpoints`: iteration, time and link of every
/// checkpoint, streamed a page of the index at a time.
pub(super) async fn list(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    // the first page now: a store error is an error response, not a cut body
    let first = state.store.checkpoint_index(&id, -1).await?;
    let entries = |id: &str, page: &[(i64, f64)], first: bool| {
        let mut s = String::with_capacity(page.len() * 100);
        for (k, &(iteration, time)) in page.iter().enumerate() {
            if !(first && k == 0) {
                s.push(',');
            }
            let href = format!("/v1/jobs/{id}/checkpoints/{iteration}.glb");
            s.push_str(&serde_json::to_string(&CheckpointEntry { iteration, time, href }).expect("entries serialize"));
        }
        s
    };
    let store = state.store.clone();
    let pages = futures_util::stream::unfold((Some(first), true), move |(page, first)| {
        let (store, id) = (store.clone(), id.clone());
        async move {
            let page = page.filter(|p| !p.is_empty())?;
            let text = entries(&id, &page, first);
            let next = match page.len() == CHECKPOINT_PAGE {
                true => match store.checkpoint_index(&id, page.last().expect("not empty").0).await {
                    Ok(p) => Some(p),
                    Err(e) => {
                        tracing::warn!("a checkpoint list stopped: {e}");
                        return Some((
                            Err(std::io::Error::other("the checkpoints could not be read to their end")),
                            (None, false),
                        ));
                    }
                },
                false => None,
            };
            Some((Ok(text), (next, false)))
        }
    });
    let body = futures_util::stream::once(async { Ok::<_, std::io::Error>("{\"checkpoints\":[".to_string()) })
        .chain(pages)
        .chain(futures_util::stream::once(async { Ok("]}".to_string()) }));
    Ok(([(header::CONTENT_TYPE, "application/json")], Body::from_stream(body)).into_response())
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
