//! Browser safety: a page of another site must not drive a service on the
//! user's machine. A state-changing request (`POST`, `PUT`, `PATCH`, `DELETE`)
//! whose `Origin` is neither the service's own (the scheme and the `Host` it was
//! asked under) nor one `serve --cors-origin` allows is 403; requests without
//! `Origin` (curl, scripts) pass. CORS headers are sent only for the allowed
//! origins ([`cors`]).

use crate::service::{ApiError, AppState};
use axum::extract::{Request, State};
use axum::http::{header, HeaderName, HeaderValue, Method};
use axum::middleware::Next;
use axum::response::Response;
use tower_http::cors::{AllowOrigin, CorsLayer};

/// Refuse a state-changing request from a foreign origin (see the module).
pub(super) async fn same_origin(State(state): State<AppState>, req: Request, next: Next) -> Result<Response, ApiError> {
    let changes = matches!(*req.method(), Method::POST | Method::PUT | Method::PATCH | Method::DELETE);
    if let (true, Some(origin)) = (changes, req.headers().get(header::ORIGIN)) {
        let host = req.headers().get(header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
        let origin = origin.to_str().unwrap_or("");
        let own = !host.is_empty() && [format!("http://{host}"), format!("https://{host}")].iter().any(|o| o == origin);
        if !own && !state.cors_origins.iter().any(|o| o == origin) {
            return Err(ApiError::Forbidden(format!(
                "{} from the origin {origin:?}: only this service's own pages, and the origins given with \
                 `serve --cors-origin`, may change its jobs",
                req.method()
            )));
        }
    }
    Ok(next.run(req).await)
}

/// The CORS layer of the allowed `origins`; `None` if there are none (no CORS
/// headers at all).
pub(super) fn cors(origins: &[String]) -> Option<CorsLayer> {
    let values: Vec<HeaderValue> = origins.iter().filter_map(|o| HeaderValue::from_str(o).ok()).collect();
    (!values.is_empty()).then(|| {
        CorsLayer::new()
            .allow_origin(AllowOrigin::list(values))
            .allow_methods([Method::GET, Method::POST, Method::DELETE])
            .allow_headers([header::AUTHORIZATION, header::CONTENT_TYPE, HeaderName::from_static("last-event-id")])
            .expose_headers([header::LOCATION, header::RETRY_AFTER])
    })
}
