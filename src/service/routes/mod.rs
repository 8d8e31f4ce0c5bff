//! The HTTP routes: the router, listed once, and one module per resource or
//! endpoint. Handlers read and write through the store ([`super::store`]); none
//! holds SQL.

mod checkpoints;
mod energy;
mod events;
mod jobs;
mod metrics;
mod openapi;
mod origin;
mod readyz;
mod results;
mod thinned;
mod ui;

use super::keys::Caller;
use super::store::JobRow;
use super::{ApiError, AppState};
use axum::extract::rejection::QueryRejection;
use axum::extract::{DefaultBodyLimit, Query, Request, State};
use axum::http::header;
use axum::middleware::{self, Next};
use axum::response::Response;
use axum::routing::{get, post};
use axum::Router;
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::trace::TraceLayer;

pub use openapi::{openapi_json, OPENAPI_YAML};

/// Every route of [`router`] as (method, path): the contract test checks it against
/// `api/openapi.yaml` and against the router itself.
pub const ROUTES: &[(&str, &str)] = &[
    ("GET", "/healthz"),
    ("GET", "/readyz"),
    ("GET", "/metrics"),
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
    ("GET", "/v1/jobs/{id}/results/mask.nii.gz"),
    ("GET", "/v1/jobs/{id}/results/labels.nii.gz"),
    ("GET", "/v1/jobs/{id}/results/objects.csv"),
    ("GET", "/v1/jobs/{id}/results/labels.tif"),
    ("GET", "/v1/jobs/{id}/results/labels.ome.tif"),
    ("GET", "/v1/jobs/{id}/results/rois.zip"),
    ("GET", "/v1/jobs/{id}/results/shape.vtp"),
    ("GET", "/v1/jobs/{id}/results/evolution_vtk.zip"),
    ("GET", "/v1/jobs/{id}/checkpoints"),
    ("GET", "/v1/jobs/{id}/checkpoints/{n}.glb"),
];

/// The HTTP application.
pub fn router(state: AppState) -> Router {
    let app = Router::new()
        .route("/healthz", get(|| async { "ok" }))
        .route("/readyz", get(readyz::readyz))
        .route("/metrics", get(metrics::metrics))
        .route("/", get(ui::index))
        .route("/jobs/{id}", get(ui::job_page))
        .route("/ui/{*path}", get(ui::asset))
        .route("/v1/openapi.json", get(openapi::document))
        .route("/v1/jobs", post(jobs::create::create).get(jobs::list::list))
        .route("/v1/jobs/{id}", get(jobs::get::get).delete(jobs::delete::delete))
        .route("/v1/jobs/{id}/cancel", post(jobs::cancel::cancel))
        .route("/v1/jobs/{id}/events", get(events::events))
        .route("/v1/jobs/{id}/energy", get(energy::history))
        .route("/v1/jobs/{id}/energy.svg", get(energy::plot))
        .route("/v1/jobs/{id}/results", get(results::manifest))
        .route("/v1/jobs/{id}/results/shape.json", get(results::shape))
        .route("/v1/jobs/{id}/results/shape.glb", get(results::shape_glb))
        .route("/v1/jobs/{id}/results/evolution.glb", get(results::evolution_glb))
        .route("/v1/jobs/{id}/results/{image}", get(results::image_result))
        .route("/v1/jobs/{id}/checkpoints", get(checkpoints::list))
        .route("/v1/jobs/{id}/checkpoints/{file}", get(checkpoints::glb))
        .route_layer(middleware::from_fn_with_state(state.clone(), metrics::observe))
        .fallback(no_route)
        .layer(DefaultBodyLimit::disable())
        .layer(middleware::from_fn_with_state(state.clone(), authorize))
        .layer(middleware::from_fn_with_state(state.clone(), origin::same_origin))
        .layer(middleware::from_fn(super::error::method_not_allowed));
    let app = match origin::cors(&state.cors_origins) {
        Some(cors) => app.layer(cors),
        None => app,
    };
    app.layer(PropagateRequestIdLayer::x_request_id())
        .layer(
            TraceLayer::new_for_http()
                .make_span_with(|req: &Request| {
                    let id = req.headers().get("x-request-id").and_then(|v| v.to_str().ok()).unwrap_or("");
                    tracing::info_span!("request", request_id = %id, method = %req.method(), uri = %req.uri().path())
                })
                .on_request(())
                .on_response(|res: &Response, latency: std::time::Duration, _: &tracing::Span| {
                    tracing::info!(status = res.status().as_u16(), ms = latency.as_secs_f64() * 1e3, "answered");
                }),
        )
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid))
        .with_state(state)
}

async fn no_route(req: Request) -> ApiError {
    ApiError::NotFound(format!("no route {} {}", req.method(), req.uri().path()))
}

/// Once a key or the token exists, every route but `/healthz`, `/readyz` and
/// the viewer page's needs one ([`Keys`](crate::service::keys::Keys)); the caller
/// goes on in the request's extensions, and a job another key owns is not found.
async fn authorize(State(state): State<AppState>, mut req: Request, next: Next) -> Result<Response, ApiError> {
    let path = req.uri().path();
    let public = matches!(path, "/healthz" | "/readyz") || ui::is_page(path);
    let caller = match public || !state.keys.required(&state.store).await? {
        true => Caller::Open,
        false => {
            let given = req.headers().get(header::AUTHORIZATION).and_then(|v| v.to_str().ok());
            let bearer = given.and_then(|g| g.strip_prefix("Bearer ")).ok_or(ApiError::Unauthorized)?;
            state.keys.caller(&state.store, bearer).await?.ok_or(ApiError::Unauthorized)?
        }
    };
    if !caller.sees_all() {
        if let Some(id) = path.strip_prefix("/v1/jobs/").map(|rest| rest.split('/').next().unwrap_or("")) {
            match state.store.job(id).await? {
                Some(job) if !caller.may_see(job.owner.as_deref()) => {
                    return Err(ApiError::NotFound(format!("no job {id}")));
                }
                _ => {}
            }
        }
    }
    req.extensions_mut().insert(caller);
    Ok(next.run(req).await)
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

/// The job `id`, or 404.
async fn find(state: &AppState, id: &str) -> Result<JobRow, ApiError> {
    state.store.job(id).await?.ok_or_else(|| ApiError::NotFound(format!("no job {id}")))
}

/// `f` on the blocking pool (engine work: preparing a job, building glTF).
async fn blocking<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f).await.map_err(|e| ApiError::Internal(e.to_string()))
}
