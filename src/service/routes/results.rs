//! `GET /v1/jobs/{id}/results` (the manifest) and the result files. An ended
//! job's files were computed once, by its worker, and are served as stored. A
//! running job shows its latest checkpoint: shape.json, shape.glb and
//! evolution.glb are encoded from the stored frames (checkpoints with their
//! fields: nothing is solved); its image results come when it ends. An ended job
//! whose files were never stored (its nodes kept dying, or an older version ran
//! it) has them computed on the first request, and stored. A running job's
//! evolution.glb is built from as many of its checkpoints as it shows (never all
//! of them read), one build at a time, once per new checkpoint.

use super::thinned::Thinned;
use super::{blocking, find};
use crate::export::shape_json;
use crate::jobs::{
    evolution_frames_of, image_result_names, parse_spec, prepare, result_files, Frame, GlbContext, PreparedJob,
    EVOLUTION_VTK_ZIP, GLB,
};
use crate::service::store::{JobRow, ResultIndex, Which};
use crate::service::wire::{Manifest, ResultFile};
use crate::service::{ApiError, AppState};
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::Json;

/// The files a running job's latest checkpoint shows.
const RUNNING_FILES: [(&str, &str); 3] =
    [("shape.json", "application/json"), ("shape.glb", GLB), ("evolution.glb", GLB)];

/// The job prepared again from its stored spec and inputs: only for what an older
/// version did not store (frames without fields, result files, the glb context).
async fn rebuild(state: &AppState, id: &str) -> Result<PreparedJob, ApiError> {
    let row = find(state, id).await?;
    let spec = parse_spec(&row.spec).map_err(|e| ApiError::Internal(format!("stored spec of {id}: {e}")))?;
    let inputs = state.store.inputs(id).await?;
    blocking(move || prepare(spec, &inputs))
        .await?
        .map_err(|e| ApiError::Internal(format!("stored spec of {}: {e}", row.id)))
}

/// The frames `which` of job `id` and what their glb files share; frames stored
/// without fields get them (the job prepared again). `None` if there is no such
/// frame.
pub(super) async fn frames_to_draw(
    state: &AppState,
    id: &str,
    which: Which,
) -> Result<Option<(GlbContext, Vec<Frame>)>, ApiError> {
    let frames = state.store.frames(id, which).await?;
    draw(state, id, frames).await
}

/// `frames` of job `id` and what their glb files share, as [`frames_to_draw`].
async fn draw(state: &AppState, id: &str, frames: Vec<Frame>) -> Result<Option<(GlbContext, Vec<Frame>)>, ApiError> {
    if frames.is_empty() {
        return Ok(None);
    }
    let context = state.store.context(id).await?;
    if let (Some(context), true) = (&context, frames.iter().all(|f| f.fields.is_some())) {
        return Ok(Some((context.clone(), frames)));
    }
    let job = rebuild(state, id).await?;
    let (context, frames) = blocking(move || {
        let frames = frames.into_iter().map(|f| if f.fields.is_some() { f } else { Frame::of(&job, &f.state) });
        (GlbContext::of(&job), frames.collect::<Vec<_>>())
    })
    .await?;
    state.store.put_context(id, serde_json::to_vec(&context).expect("contexts serialize")).await?;
    Ok(Some((context, frames)))
}

/// The stored result files of an ended job (computed and stored now if they are
/// missing); `None` for a job still queued or running, or one with no state.
async fn ended_results(state: &AppState, row: &JobRow) -> Result<Option<ResultIndex>, ApiError> {
    if !row.status.is_final() {
        return Ok(None);
    }
    if let Some(index) = &row.results {
        return Ok(Some(index.clone()));
    }
    let kept = state.store.kept_frames(&row.id).await?.into_frames();
    let Some((_, frames)) = draw(state, &row.id, kept).await? else { return Ok(None) };
    let job = rebuild(state, &row.id).await?;
    let files = blocking(move || result_files(&job, &frames)).await?;
    state.store.put_results(&row.id, None, &files).await?;
    Ok(state.store.job(&row.id).await?.and_then(|j| j.results))
}

pub(super) fn glb_response(bytes: impl Into<bytes::Bytes>, name: &str) -> Response {
    (
        [
            (header::CONTENT_TYPE, GLB.to_string()),
            (header::CONTENT_DISPOSITION, format!("inline; filename=\"{name}\"")),
        ],
        bytes.into(),
    )
        .into_response()
}

/// `GET /v1/jobs/{id}/results`: the result files available now.
pub(super) async fn manifest(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = find(&state, &id).await?;
    let base = format!("/v1/jobs/{id}");
    let file = |name: &str, href: String, media_type: &str| ResultFile {
        name: name.to_string(),
        href,
        media_type: media_type.to_string(),
    };
    let mut files = vec![
        file("energy", format!("{base}/energy"), "application/json"),
        file("energy.csv", format!("{base}/energy?format=csv"), "text/csv"),
        file("energy.svg", format!("{base}/energy.svg"), "image/svg+xml"),
    ];
    if let Some(index) = ended_results(&state, &job).await? {
        files.extend(index.files.iter().map(|f| file(&f.name, format!("{base}/results/{}", f.name), &f.media_type)));
    } else if !job.status.is_final() && !state.store.checkpoint_rows(&id, Which::Last).await?.is_empty() {
        files.extend(RUNNING_FILES.iter().map(|(name, media)| file(name, format!("{base}/results/{name}"), media)));
    }
    let checkpoints = format!("{base}/checkpoints");
    Ok(Json(Manifest { id: &id, status: job.status, is_final: job.status.is_final(), files, checkpoints })
        .into_response())
}

/// The stored file `name` of an ended job; `None` for a running job.
async fn stored(state: &AppState, id: &str, name: &str) -> Result<Option<Response>, ApiError> {
    let row = find(state, id).await?;
    let Some(index) = ended_results(state, &row).await? else { return Ok(None) };
    match state.store.result_file(id, &index, name).await? {
        Some((media, bytes)) => Ok(Some(([(header::CONTENT_TYPE, media)], bytes).into_response())),
        None => Err(ApiError::NotFound(format!("job {id} has no result {name}"))),
    }
}

/// The latest frame of a running job, or 404.
async fn latest(state: &AppState, id: &str) -> Result<(GlbContext, Frame), ApiError> {
    let no_result = || ApiError::NotFound(format!("job {id} has no result yet"));
    let (context, mut frames) = frames_to_draw(state, id, Which::Last).await?.ok_or_else(no_result)?;
    Ok((context, frames.pop().ok_or_else(no_result)?))
}

/// `GET /v1/jobs/{id}/results/shape.json`: what the job's final state shows (a
/// segmentation's contour refined onto the edges, with pixel coordinates and the
/// objects), or the latest checkpoint of a running job.
pub(super) async fn shape(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    if let Some(r) = stored(&state, &id, "shape.json").await? {
        return Ok(r);
    }
    let frames = state.store.frames(&id, Which::Last).await?;
    let s = &frames.last().ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?.state;
    Ok(Json(shape_json(&s.mesh, s.energy, s.iteration, None)).into_response())
}

/// `GET /v1/jobs/{id}/results/mask.png`, `overlay.png`, `labels.png` (2D),
/// `mask.nrrd`, `labels.nrrd`, `mask.nii.gz`, `labels.nii.gz` (3D), `objects.csv`:
/// the segmentation of an ended image job.
pub(super) async fn image_result(
    State(state): State<AppState>,
    Path((id, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let row = find(&state, &id).await?;
    // the VTK files of every job, written when it ends
    if ["shape.vtp", EVOLUTION_VTK_ZIP].contains(&file.as_str()) {
        return match stored(&state, &id, &file).await? {
            Some(r) => Ok(r),
            None => Err(ApiError::NotFound(format!(
                "job {id} is {}: its VTK files are written when it ends",
                row.status.as_str()
            ))),
        };
    }
    let known = [2, 3].iter().any(|&d| image_result_names(d).iter().any(|(n, _)| *n == file));
    if !known {
        return Err(ApiError::NotFound(format!(
            "no result {file:?}; GET /v1/jobs/{id}/results lists this job's files"
        )));
    }
    let spec: serde_json::Value = serde_json::from_str(&row.spec).unwrap_or_default();
    if spec["problem"]["type"] != "segmentation" {
        return Err(ApiError::NotFound(format!("job {id} is not an image job: it has no {file}")));
    }
    match stored(&state, &id, &file).await? {
        Some(r) => Ok(r),
        None => Err(ApiError::NotFound(format!(
            "job {id} is {}: its image results are written when it ends",
            row.status.as_str()
        ))),
    }
}

/// `GET /v1/jobs/{id}/results/shape.glb`: the final state as its results show it,
/// or the latest checkpoint of a running job.
pub(super) async fn shape_glb(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    if let Some(r) = stored(&state, &id, "shape.glb").await? {
        return Ok(r);
    }
    let (context, frame) = latest(&state, &id).await?;
    let bytes = blocking(move || context.frame_glb(&frame)).await?;
    Ok(glb_response(bytes, "shape.glb"))
}

/// `GET /v1/jobs/{id}/results/evolution.glb`: every checkpoint, animated.
pub(super) async fn evolution_glb(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    if let Some(r) = stored(&state, &id, "evolution.glb").await? {
        return Ok(r);
    }
    let no_checkpoint = || ApiError::NotFound(format!("job {id} has no checkpoint yet"));
    let last = state.store.checkpoint_rows(&id, Which::Last).await?.pop().ok_or_else(no_checkpoint)?.iteration;
    // one build at a time, and once per new checkpoint of a job
    let mut built = state.evolutions.lock().await;
    if let Some((_, bytes)) = built.iter().find(|(key, _)| *key == (id.clone(), last)) {
        return Ok(glb_response(bytes.clone(), "evolution.glb"));
    }
    // of the checkpoints, as many as evolution.glb shows at the latest one's size,
    // evenly picked with the first and the last: the others are never read
    let newest = state.store.frames(&id, Which::At(last)).await?.pop().ok_or_else(no_checkpoint)?;
    let picks = shown(&state, &id, evolution_frames_of(&newest.state.mesh), last).await?;
    let mut frames = Vec::with_capacity(picks.len() + 1);
    for &it in picks.iter().filter(|&&it| it != last) {
        frames.extend(state.store.frames(&id, Which::At(it)).await?);
    }
    frames.push(newest);
    let (context, frames) = draw(&state, &id, frames).await?.ok_or_else(no_checkpoint)?;
    let bytes = blocking(move || context.evolution_glb(&frames)).await?.ok_or_else(no_checkpoint)?;
    let bytes = bytes::Bytes::from(bytes);
    built.retain(|((job, _), _)| *job != id);
    built.push_front(((id, last), bytes.clone()));
    built.truncate(EVOLUTIONS_KEPT);
    Ok(glb_response(bytes, "evolution.glb"))
}

/// The iterations of the `fit` checkpoints (at least 2) up to `last` that
/// evolution.glb shows, evenly picked with the first and the last; the index is
/// read a page at a time and at most `2 fit` iterations are kept ([`Thinned`]),
/// so that the memory does not grow with the number of checkpoints.
async fn shown(state: &AppState, id: &str, fit: usize, last: i64) -> Result<Vec<i64>, ApiError> {
    let fit = fit.max(2);
    let (mut thinned, mut after) = (Thinned::new(2 * fit), -1);
    while after < last {
        let page = state.store.checkpoint_index(id, after).await?;
        let Some(&(end, _)) = page.last() else { break };
        page.iter().filter(|(it, _)| *it <= last).for_each(|&(it, _)| thinned.push(it));
        after = end;
    }
    let mut kept = thinned.into_items();
    if kept.last() != Some(&last) {
        kept.push(last);
    }
    let n = kept.len();
    Ok(match n.min(fit) {
        0 | 1 => vec![last],
        fit => (0..fit).map(|k| kept[k * (n - 1) / (fit - 1)]).collect(),
    })
}

/// Running jobs' evolution.glb kept built, the newest first.
pub(super) const EVOLUTIONS_KEPT: usize = 2;
