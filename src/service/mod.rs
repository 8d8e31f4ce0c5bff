//! The job service (docs/user-guide.md): axum routes over a job store (SQLite on
//! one node, PostgreSQL for many; [`store`]) and a fixed pool of worker threads. Routes so far: `POST /v1/jobs` (JSON),
//! `GET /v1/jobs`, `GET|DELETE /v1/jobs/{id}`, `POST /v1/jobs/{id}/cancel`,
//! `GET /v1/jobs/{id}/events` (SSE), `GET /v1/jobs/{id}/energy` (JSON or `?format=csv`),
//! `GET /v1/jobs/{id}/results` (manifest), `.../results/{shape.json, shape.glb,
//! evolution.glb}`, `GET /v1/jobs/{id}/checkpoints` and `.../checkpoints/{n}.glb`,
//! `GET /healthz`.

mod error;
mod results;
pub mod store;
mod submit;
mod ui;
pub mod worker;

use crate::export::{energy_csv, energy_svg, shape_json};
use axum::extract::rejection::QueryRejection;
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
pub use error::ApiError;
use serde::Deserialize;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use store::{ClaimPolicy, JobRow, Store};
use tokio::sync::{broadcast, Notify};
use worker::{Registry, Worker};

pub use crate::limits::{MAX_BODY_BYTES, MAX_UPLOAD_BYTES};

/// Shared state of the handlers.
#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub registry: Registry,
    pub wake: Arc<Notify>,
    /// With a token, every route but `/healthz` and the viewer page's needs `Authorization: Bearer <token>`.
    pub token: Option<Arc<str>>,
    /// Set when the server shuts down: open event streams end.
    pub closing: Arc<AtomicBool>,
    /// A job's id after each of its history batches and its outcome, from this
    /// node's workers and (PostgreSQL) other nodes' notifications; `"*"`: re-read.
    pub events: broadcast::Sender<Arc<str>>,
}

/// Every route of [`router`] as (method, path): the contract test checks it against
/// `api/openapi.yaml` and against the router itself.
pub const ROUTES: &[(&str, &str)] = &[
    ("GET", "/healthz"),
    ("GET", "/"),
    ("GET", "/jobs/{id}"),
    ("GET", "/ui/{path}"),
    ("GET", "/v1/openapi.json"),
    ("POST", "/v1/jobs"),
    ("GET", "/v1/jobs"),
    ("GET", "/v1/jobs/{id}"),
    ("DELETE", "/v1/jobs/{id}"),
    ("POST", "/v1/jobs/{id}/cancel"),
    ("GET", "/v1/jobs/{id}/events"),
    ("GET", "/v1/jobs/{id}/energy"),
    ("GET", "/v1/jobs/{id}/energy.svg"),
    ("GET", "/v1/jobs/{id}/results"),
    ("GET", "/v1/jobs/{id}/results/shape.json"),
    ("GET", "/v1/jobs/{id}/results/shape.glb"),
    ("GET", "/v1/jobs/{id}/results/evolution.glb"),
    ("GET", "/v1/jobs/{id}/results/mask.png"),
    ("GET", "/v1/jobs/{id}/results/overlay.png"),
    ("GET", "/v1/jobs/{id}/results/mask.nrrd"),
    ("GET", "/v1/jobs/{id}/results/labels.png"),
    ("GET", "/v1/jobs/{id}/results/labels.nrrd"),
    ("GET", "/v1/jobs/{id}/results/objects.csv"),
    ("GET", "/v1/jobs/{id}/checkpoints"),
    ("GET", "/v1/jobs/{id}/checkpoints/{n}.glb"),
];

/// The HTTP application.
pub fn router(state: AppState) -> Router {
    Router::new()
        .route("/healthz", get(|| async { "ok" }))
        .route("/", get(ui::index))
        .route("/jobs/{id}", get(ui::job_page))
        .route("/ui/{*path}", get(ui::asset))
        .route("/v1/openapi.json", get(openapi))
        .route("/v1/jobs", post(submit::create_job).get(list_jobs))
        .route("/v1/jobs/{id}", get(get_job).delete(delete_job))
        .route("/v1/jobs/{id}/cancel", post(cancel_job))
        .route("/v1/jobs/{id}/events", get(events))
        .route("/v1/jobs/{id}/energy", get(energy))
        .route("/v1/jobs/{id}/energy.svg", get(energy_plot))
        .route("/v1/jobs/{id}/results", get(results::manifest))
        .route("/v1/jobs/{id}/results/shape.json", get(shape))
        .route("/v1/jobs/{id}/results/shape.glb", get(results::shape_glb))
        .route("/v1/jobs/{id}/results/evolution.glb", get(results::evolution_glb))
        .route("/v1/jobs/{id}/results/{image}", get(results::image_result))
        .route("/v1/jobs/{id}/checkpoints", get(results::checkpoint_list))
        .route("/v1/jobs/{id}/checkpoints/{file}", get(results::checkpoint_glb))
        .fallback(no_route)
        .layer(DefaultBodyLimit::disable())
        .layer(middleware::from_fn_with_state(state.clone(), authorize))
        .layer(middleware::from_fn(error::method_not_allowed))
        .with_state(state)
}

async fn no_route(req: Request) -> ApiError {
    ApiError::NotFound(format!("no route {} {}", req.method(), req.uri().path()))
}

/// The parameters of a query string, or 422 naming the one that could not be read
/// (unknown, e.g. misspelt, or given twice).
fn query<T>(q: Result<Query<T>, QueryRejection>) -> Result<T, ApiError> {
    q.map(|Query(t)| t).map_err(|e| {
        let detail = e.body_text();
        let parameter = detail.split('`').nth(1).unwrap_or("(query)").to_string();
        ApiError::InvalidParameter { parameter, detail }
    })
}

async fn authorize(State(state): State<AppState>, req: Request, next: Next) -> Result<Response, ApiError> {
    if let Some(token) = &state.token {
        if req.uri().path() != "/healthz" && !ui::is_page(req.uri().path()) {
            let given = req.headers().get(header::AUTHORIZATION).and_then(|v| v.to_str().ok());
            if given.and_then(|g| g.strip_prefix("Bearer ")) != Some(token.as_ref()) {
                return Err(ApiError::Unauthorized);
            }
        }
    }
    Ok(next.run(req).await)
}

fn job_json(j: &JobRow) -> Value {
    json!({
        "id": j.id,
        "status": j.status,
        "progress": j.progress,
        "stop_reason": j.stop_reason,
        "message": j.message,
        "created": j.created_at,
        "started": j.started_at,
        "finished": j.finished_at,
    })
}

/// The contract `api/openapi.yaml`, embedded at build time.
pub const OPENAPI_YAML: &str = include_str!("../../api/openapi.yaml");

/// `api/openapi.yaml` as JSON (converted once), its `JobSpec` the schema derived from
/// the spec's types ([`crate::jobs::openapi_schemas`]).
pub fn openapi_json() -> &'static Value {
    static DOC: std::sync::OnceLock<Value> = std::sync::OnceLock::new();
    DOC.get_or_init(|| {
        let mut doc: Value = serde_norway::from_str(OPENAPI_YAML).expect("api/openapi.yaml is valid YAML");
        // the outline of `JobSpec` in the YAML gives way to the schema derived from the spec's types
        let schemas = doc["components"]["schemas"].as_object_mut().expect("api/openapi.yaml has components.schemas");
        schemas.extend(crate::jobs::openapi_schemas());
        doc
    })
}

async fn openapi() -> Json<Value> {
    Json(openapi_json().clone())
}

async fn find(state: &AppState, id: &str) -> Result<JobRow, ApiError> {
    state.store.job(id).await?.ok_or_else(|| ApiError::NotFound(format!("no job {id}")))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ListQuery {
    status: Option<String>,
    limit: Option<String>,
    page_token: Option<String>,
}

/// Statuses a job can have (OGC API – Processes).
const STATUSES: [&str; 5] = ["accepted", "running", "successful", "failed", "dismissed"];

/// `GET /v1/jobs?status=&limit=&page_token=`: newest first, `limit` (1–1000, default
/// 100) per page; `next_page_token` is present when more jobs follow.
async fn list_jobs(
    State(state): State<AppState>,
    q: Result<Query<ListQuery>, QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    let q = query(q)?;
    if let Some(s) = q.status.as_deref() {
        if !STATUSES.contains(&s) {
            let detail = format!("unknown status {s:?}; one of {}", STATUSES.join(", "));
            return Err(ApiError::InvalidParameter { parameter: "status".into(), detail });
        }
    }
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
    let mut jobs = state.store.list(q.status.as_deref(), before, limit + 1).await?;
    let more = jobs.len() as i64 > limit;
    jobs.truncate(limit as usize);
    let mut body = json!({ "jobs": jobs.iter().map(job_json).collect::<Vec<_>>() });
    if more {
        if let Some(last) = jobs.last() {
            body["next_page_token"] = json!(format!("p{:x}", last.seq));
        }
    }
    Ok(Json(body))
}

async fn get_job(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    Ok(Json(job_json(&find(&state, &id).await?)))
}

async fn cancel_job(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let job = find(&state, &id).await?;
    if matches!(job.status.as_str(), "successful" | "failed" | "dismissed") {
        return Err(ApiError::Conflict(format!("job {id} is already {}", job.status)));
    }
    state.store.request_cancel(&id).await?;
    if let Some(flag) = state.registry.lock().unwrap().get(&id) {
        flag.store(true, Ordering::Relaxed);
    }
    let job = find(&state, &id).await?;
    Ok((StatusCode::ACCEPTED, Json(job_json(&job))).into_response())
}

async fn delete_job(State(state): State<AppState>, Path(id): Path<String>) -> Result<StatusCode, ApiError> {
    let job = find(&state, &id).await?;
    if matches!(job.status.as_str(), "accepted" | "running") {
        return Err(ApiError::Conflict(format!("job {id} is {}; cancel it first", job.status)));
    }
    state.store.delete(&id).await?;
    Ok(StatusCode::NO_CONTENT)
}

/// Server-Sent Events: one `progress` event per iteration (`id` = iteration, so a
/// reconnect with `Last-Event-ID` continues after it), then one `status` event with
/// the finished job, and the stream ends. Keep-alive comments every 15 s; streams end
/// when the server shuts down.
async fn events(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    use axum::response::sse::{Event, KeepAlive, Sse};
    find(&state, &id).await?;
    let after: Option<usize> =
        headers.get("last-event-id").and_then(|v| v.to_str().ok()).and_then(|v| v.trim().parse().ok());
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
            let rows = c.state.store.history_from(&c.id, c.next).await.unwrap_or_default();
            for p in rows {
                c.next = p.iteration + 1;
                let data = serde_json::to_string(&p).expect("progress serializes");
                c.pending.push_back(Event::default().event("progress").id(p.iteration.to_string()).data(data));
            }
            match job {
                Some(j) if !matches!(j.status.as_str(), "accepted" | "running") && c.pending.is_empty() => {
                    c.pending.push_back(Event::default().event("status").data(job_json(&j).to_string()));
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

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FormatQuery {
    format: Option<String>,
}

async fn energy(
    State(state): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<FormatQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let q = query(q)?;
    find(&state, &id).await?;
    let rows = state.store.history(&id).await?;
    match q.format.as_deref() {
        Some("csv") => Ok(([(header::CONTENT_TYPE, "text/csv")], energy_csv(&rows)).into_response()),
        None | Some("json") => Ok(Json(json!({ "history": rows })).into_response()),
        Some(other) => Err(ApiError::InvalidParameter {
            parameter: "format".into(),
            detail: format!("unknown format {other:?} (json or csv)"),
        }),
    }
}

async fn energy_plot(State(state): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    find(&state, &id).await?;
    let rows = state.store.history(&id).await?;
    Ok(([(header::CONTENT_TYPE, "image/svg+xml")], energy_svg(&rows, &format!("job {id}"))).into_response())
}

/// `GET /v1/jobs/{id}/results/shape.json`: the latest state as its results show it
/// (a segmentation's contour refined onto the edges, with pixel coordinates).
async fn shape(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let row = find(&state, &id).await?;
    let cp = state
        .store
        .last_checkpoint(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job {id} has no result yet")))?;
    let spec: Value = serde_json::from_str(&row.spec).unwrap_or(Value::Null);
    if spec["problem"]["type"] != "segmentation" {
        return Ok(Json(shape_json(&cp.mesh, cp.energy, cp.iteration, None)));
    }
    let job = results::rebuild(&state, &id).await?;
    let doc = tokio::task::spawn_blocking(move || {
        let shown = crate::jobs::result_state(&job, &cp);
        crate::jobs::StateResults::new(&job, &shown).shape_document()
    })
    .await
    .map_err(|e| ApiError::Internal(e.to_string()))?;
    Ok(Json(doc))
}

/// How a node runs.
#[derive(Debug, Clone)]
pub struct ServiceConfig {
    /// A SQLite file path or `sqlite:` URL, or a `postgres://` URL ([`store::open`]).
    pub database: String,
    /// Worker threads (0: none, an API-only node).
    pub workers: usize,
    /// With a token, every route but `/healthz` and the viewer page's needs it.
    pub token: Option<String>,
    pub policy: ClaimPolicy,
}

/// A running service: the HTTP state and the worker threads.
pub struct Service {
    pub state: AppState,
    shutdown: Arc<AtomicBool>,
    workers: Vec<std::thread::JoinHandle<()>>,
}

impl Service {
    /// [`Service::start_with`] on a SQLite file with `workers` (at least one) worker
    /// threads and the default leases.
    pub async fn start(
        database: &std::path::Path,
        workers: usize,
        token: Option<String>,
    ) -> Result<Self, store::StoreError> {
        let database = database.to_string_lossy().into_owned();
        Self::start_with(ServiceConfig { database, workers: workers.max(1), token, policy: ClaimPolicy::default() })
            .await
    }

    /// Open the store (on SQLite, jobs left running by a stop or crash go back to
    /// the queue; on PostgreSQL their leases expire) and start the worker threads.
    /// Call from within a tokio runtime.
    pub async fn start_with(config: ServiceConfig) -> Result<Self, store::StoreError> {
        let store = store::open(&config.database).await?;
        let requeued = store.requeue_running().await?;
        if requeued > 0 {
            tracing::info!(requeued, "jobs interrupted by a previous stop go back to the queue");
        }
        let (events, _) = broadcast::channel(1024);
        store.watch(events.clone());
        let state = AppState {
            store,
            registry: Arc::new(Mutex::new(HashMap::new())),
            wake: Arc::new(Notify::new()),
            token: config.token.map(Arc::from),
            closing: Arc::new(AtomicBool::new(false)),
            events,
        };
        let shutdown = Arc::new(AtomicBool::new(false));
        let rt = tokio::runtime::Handle::current();
        let node = format!("{}-{}", std::process::id(), &uuid::Uuid::new_v4().simple().to_string()[..8]);
        let workers = (0..config.workers)
            .map(|k| {
                let w = Worker {
                    store: state.store.clone(),
                    rt: rt.clone(),
                    registry: state.registry.clone(),
                    wake: state.wake.clone(),
                    shutdown: shutdown.clone(),
                    events: state.events.clone(),
                    owner: format!("{node}/{k}"),
                    policy: config.policy,
                };
                std::thread::Builder::new()
                    .name(format!("worker-{k}"))
                    .spawn(move || w.run_forever())
                    .expect("spawn worker")
            })
            .collect();
        Ok(Service { state, shutdown, workers })
    }

    pub fn router(&self) -> Router {
        router(self.state.clone())
    }

    /// Stop the workers: running jobs stop at their next step and write a
    /// checkpoint; on SQLite they stay `running`, to resume at the next start, on
    /// PostgreSQL they go back to the queue for another node.
    pub async fn stop(self) {
        self.state.closing.store(true, Ordering::Relaxed);
        self.shutdown.store(true, Ordering::Relaxed);
        for flag in self.state.registry.lock().unwrap().values() {
            flag.store(true, Ordering::Relaxed);
        }
        self.state.wake.notify_waiters();
        let workers = self.workers;
        let _ = tokio::task::spawn_blocking(move || workers.into_iter().for_each(|w| drop(w.join()))).await;
    }
}
