//! `POST /v1/jobs`: a JSON spec (inline geometry), or `multipart/form-data` with a
//! part named `spec` (the JSON spec) and one part per input file, named as in the
//! spec's `"input:NAME"`. The spec is validated with its inputs (images decoded,
//! meshes read) before anything is stored; job and inputs are stored in one
//! transaction before 201 is answered.

use crate::jobs::{format_size, parse_spec, prepare, MemoryEstimate};
use crate::service::isolation::parent::validate;
use crate::service::isolation::Isolation;
use crate::service::keys::Caller;
use crate::service::min_rate::{is_slow_body, SlowBody};
use crate::service::part_headers::{PartHeaderTooLong, PartHeaders};
use crate::service::store::{Admission, StoreError};
use crate::service::wire::JobView;
use crate::service::{ApiError, AppState, MAX_BODY_BYTES, MAX_UPLOAD_BYTES};
use axum::extract::{FromRequest, Multipart, Request, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::{Extension, Json};
use std::collections::HashMap;

/// The `Retry-After` of a refused submission (quota or full queue), in seconds.
const QUOTA_RETRY_SECONDS: u64 = 10;

/// Most parts of a multipart body (a spec and its inputs).
pub const MAX_PARTS: usize = 256;

/// A body that could not be read: too slow (408), too large (413) or malformed (400).
fn unreadable(e: &(dyn std::error::Error + 'static), limit: usize) -> ApiError {
    let mut next = Some(e);
    while let Some(e) = next {
        if e.is::<SlowBody>() {
            return ApiError::Timeout(e.to_string());
        }
        if e.is::<http_body_util::LengthLimitError>() {
            return ApiError::TooLarge(limit);
        }
        if e.is::<PartHeaderTooLong>() {
            return ApiError::BadRequest(e.to_string());
        }
        next = e.source();
    }
    ApiError::BadRequest(format!("malformed multipart body: {e}"))
}

/// The spec text and the input files of a multipart body. Everything the body
/// holds (the preamble, the parts' headers, their number) counts against
/// [`MAX_UPLOAD_BYTES`] and [`MAX_PARTS`].
async fn read_multipart(req: Request, state: &AppState) -> Result<(String, HashMap<String, Vec<u8>>), ApiError> {
    // the whole body, not only the parts' contents, is limited
    // and a part's headers end soon after its boundary
    let boundary = req
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .and_then(|t| t.split(';').find_map(|p| p.trim().strip_prefix("boundary=")))
        .map(|b| b.trim_matches('"').to_string())
        .unwrap_or_default();
    let req = req.map(|b| {
        let limited = axum::body::Body::new(http_body_util::Limited::new(b, MAX_UPLOAD_BYTES + (64 << 10)));
        axum::body::Body::new(PartHeaders::new(limited, &boundary))
    });
    let mut mp = Multipart::from_request(req, state)
        .await
        .map_err(|e| ApiError::BadRequest(format!("malformed multipart body: {}", e.body_text())))?;
    let mut spec = None;
    let mut inputs = HashMap::new();
    let (mut total, mut parts) = (0usize, 0usize);
    loop {
        let field = match mp.next_field().await {
            Ok(Some(f)) => f,
            Ok(None) => break,
            Err(e) => return Err(unreadable(&e, MAX_UPLOAD_BYTES)),
        };
        parts += 1;
        if parts > MAX_PARTS {
            return Err(ApiError::BadRequest(format!("the multipart body has more than {MAX_PARTS} parts")));
        }
        let name = field
            .name()
            .map(str::to_string)
            .filter(|n| !n.is_empty())
            .ok_or_else(|| ApiError::BadRequest("a multipart part has no name".into()))?;
        let mut data = Vec::new();
        let mut field = field;
        while let Some(chunk) = field.chunk().await.map_err(|e| match unreadable(&e, MAX_UPLOAD_BYTES) {
            ApiError::BadRequest(_) => ApiError::BadRequest(format!("part `{name}`: {}", e.body_text())),
            other => other,
        })? {
            total += chunk.len();
            if total > MAX_UPLOAD_BYTES {
                return Err(ApiError::TooLarge(MAX_UPLOAD_BYTES));
            }
            data.extend_from_slice(&chunk);
        }
        if name == "spec" {
            if spec.is_some() {
                return Err(ApiError::Invalid {
                    field: "spec".into(),
                    detail: "the part `spec` is given twice".into(),
                });
            }
            let text = String::from_utf8(data)
                .map_err(|_| ApiError::Invalid { field: "spec".into(), detail: "the spec part is not UTF-8".into() })?;
            spec = Some(text);
        } else if inputs.insert(name.clone(), data).is_some() {
            return Err(ApiError::BadRequest(format!("input part `{name}` is given twice")));
        }
    }
    let spec = spec.ok_or_else(|| ApiError::Invalid {
        field: "spec".into(),
        detail: "the multipart body has no part named `spec` (the JSON job spec)".into(),
    })?;
    Ok((spec, inputs))
}

/// Every uploaded part must be named by an `"input:NAME"` of the spec: nothing
/// unused is stored.
fn unreferenced_input(spec: &serde_json::Value, inputs: &HashMap<String, Vec<u8>>) -> Result<(), ApiError> {
    fn refs(v: &serde_json::Value, out: &mut Vec<String>) {
        match v {
            serde_json::Value::String(s) => out.extend(s.strip_prefix("input:").map(str::to_string)),
            serde_json::Value::Array(a) => a.iter().for_each(|x| refs(x, out)),
            serde_json::Value::Object(o) => o.values().for_each(|x| refs(x, out)),
            _ => {}
        }
    }
    let mut named = Vec::new();
    refs(spec, &mut named);
    let mut unused: Vec<&String> = inputs.keys().filter(|k| !named.contains(k)).collect();
    unused.sort();
    match unused.first() {
        Some(name) => Err(ApiError::Invalid {
            field: name.to_string(),
            detail: format!("the part `{name}` is not used by the spec (no \"input:{name}\" in it)"),
        }),
        None => Ok(()),
    }
}

pub(in crate::service::routes) async fn create(
    State(state): State<AppState>,
    Extension(caller): Extension<Caller>,
    req: Request,
) -> Result<Response, ApiError> {
    let ctype = req.headers().get(header::CONTENT_TYPE).and_then(|v| v.to_str().ok()).unwrap_or("").to_string();
    let (text, inputs) = if ctype.starts_with("application/json") {
        let body = axum::body::to_bytes(req.into_body(), MAX_BODY_BYTES).await.map_err(|e| match is_slow_body(&e) {
            true => ApiError::Timeout(e.to_string()),
            false => ApiError::TooLarge(MAX_BODY_BYTES),
        })?;
        let text = String::from_utf8(body.to_vec()).map_err(|_| ApiError::BadRequest("body is not UTF-8".into()))?;
        (text, HashMap::new())
    } else if ctype.starts_with("multipart/form-data") {
        read_multipart(req, &state).await?
    } else {
        return Err(ApiError::UnsupportedMedia(format!(
            "expected Content-Type application/json or multipart/form-data, got {ctype:?}"
        )));
    };
    // off the async threads: naming the field of a bad spec may deserialize it a few
    // dozen times, and validation decodes images and reads meshes; one at a time
    // per core, so that many submissions at once do not decode together
    let _turn = state.validations.clone().acquire_owned().await.map_err(|e| ApiError::Internal(e.to_string()))?;
    let (isolation, budgets) = (state.isolation.clone(), state.budgets);
    let (normalized, tree, inputs) = tokio::task::spawn_blocking(move || {
        let invalid = |e: crate::jobs::SpecError| ApiError::Invalid { field: e.field, detail: e.message };
        let spec = parse_spec(&text).map_err(invalid)?;
        let normalized = serde_json::to_string(&spec).expect("spec serializes");
        let tree = serde_json::to_value(&spec).expect("spec serializes");
        let asked = spec.limits.resolve().map_err(invalid)?;
        if let Some((field, detail)) = budgets.refuse(asked) {
            return Err(ApiError::Invalid { field: field.into(), detail });
        }
        match &isolation {
            // the inputs decoded in a process of their own, under the job's memory budget
            Isolation::Process { runner } => match validate(runner, budgets.within(asked), &normalized, &inputs) {
                Ok(Ok(())) => {}
                Ok(Err(r)) => return Err(ApiError::Invalid { field: r.field, detail: r.message }),
                Err(e) => return Err(ApiError::Internal(format!("validation: {e}"))),
            },
            Isolation::Thread => {
                let job = prepare(spec, &inputs).map_err(invalid)?;
                if let Some(budget) = budgets.within(asked).memory {
                    MemoryEstimate::of(&job)
                        .check(budget)
                        .map_err(|(field, detail)| ApiError::Invalid { field: field.into(), detail })?;
                }
            }
        }
        Ok((normalized, tree, inputs))
    })
    .await
    .map_err(|e| ApiError::Internal(e.to_string()))??;
    unreferenced_input(&tree, &inputs)?;
    let id = uuid::Uuid::new_v4().to_string();
    let admit = Admission {
        owner: caller.owner().map(str::to_string),
        max_active: caller.max_active(),
        max_queued: state.max_queued,
        max_storage: caller.max_storage(),
    };
    let job = match state.store.insert_job(&id, &normalized, &inputs, &admit).await {
        Ok(job) => job,
        Err(StoreError::ActiveQuota(max)) => {
            let detail = format!("this key may have {max} jobs accepted or running at a time, and has them");
            return Err(ApiError::TooMany { detail, retry_after: QUOTA_RETRY_SECONDS });
        }
        Err(StoreError::StorageQuota(kept, max)) => {
            let detail = format!(
                "this key's jobs keep {}, its storage quota is {}: delete some of them to make room",
                format_size(kept.max(0) as u64),
                format_size(max.max(0) as u64)
            );
            return Err(ApiError::TooMany { detail, retry_after: QUOTA_RETRY_SECONDS });
        }
        Err(StoreError::QueueFull(max)) => {
            let detail = format!("the service has {max} jobs waiting, as many as it queues");
            return Err(ApiError::Busy { detail, retry_after: QUOTA_RETRY_SECONDS });
        }
        Err(e) => return Err(e.into()),
    };
    state.wake.notify_one();
    let location = format!("/v1/jobs/{id}");
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], Json(JobView::from(&job))).into_response())
}
