//! API errors as RFC 9457 problem details (`application/problem+json`); internal
//! errors are logged, never sent to clients.

use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use serde_json::json;

#[derive(Debug)]
pub enum ApiError {
    /// 422 with the offending field of the spec (or multipart part).
    Invalid {
        field: String,
        detail: String,
    },
    /// 422 with the offending query parameter.
    InvalidParameter {
        parameter: String,
        detail: String,
    },
    NotFound(String),
    Conflict(String),
    BadRequest(String),
    /// 415: the body's media type is not accepted.
    UnsupportedMedia(String),
    /// 413 with the limit in bytes.
    TooLarge(usize),
    /// 401: missing or wrong bearer token.
    Unauthorized,
    /// 403: the request is not allowed (a foreign `Origin`).
    Forbidden(String),
    /// 408: the request did not arrive in time (a body below the minimum rate).
    Timeout(String),
    /// 429 with `Retry-After` (seconds): a key's quota is used up.
    TooMany {
        detail: String,
        retry_after: u64,
    },
    /// 503: the node cannot take work now (why).
    Unavailable(String),
    /// 503 with `Retry-After` (seconds): the queue is full.
    Busy {
        detail: String,
        retry_after: u64,
    },
    Internal(String),
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        ApiError::Internal(e.to_string())
    }
}

impl From<super::store::StoreError> for ApiError {
    fn from(e: super::store::StoreError) -> Self {
        ApiError::Internal(e.to_string())
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let mut retry = None;
        let (status, title, detail, errors) = match self {
            ApiError::Invalid { field, detail } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "Invalid job spec",
                format!("{field}: {detail}"),
                Some(json!([{ "field": field, "detail": detail }])),
            ),
            ApiError::InvalidParameter { parameter, detail } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "Invalid query parameter",
                format!("{parameter}: {detail}"),
                Some(json!([{ "field": parameter, "detail": detail }])),
            ),
            ApiError::NotFound(d) => (StatusCode::NOT_FOUND, "Not found", d, None),
            ApiError::Conflict(d) => (StatusCode::CONFLICT, "Conflict", d, None),
            ApiError::BadRequest(d) => (StatusCode::BAD_REQUEST, "Bad request", d, None),
            ApiError::UnsupportedMedia(d) => (StatusCode::UNSUPPORTED_MEDIA_TYPE, "Unsupported media type", d, None),
            ApiError::TooLarge(limit) => (
                StatusCode::PAYLOAD_TOO_LARGE,
                "Payload too large",
                format!("the request body exceeds the limit of {limit} bytes"),
                None,
            ),
            ApiError::Unauthorized => {
                (StatusCode::UNAUTHORIZED, "Unauthorized", "missing or wrong `Authorization: Bearer` key".into(), None)
            }
            ApiError::Forbidden(d) => (StatusCode::FORBIDDEN, "Forbidden", d, None),
            ApiError::Timeout(d) => (StatusCode::REQUEST_TIMEOUT, "Request timeout", d, None),
            ApiError::TooMany { detail, retry_after } => {
                retry = Some(retry_after);
                (StatusCode::TOO_MANY_REQUESTS, "Too many requests", detail, None)
            }
            ApiError::Unavailable(d) => (StatusCode::SERVICE_UNAVAILABLE, "Not ready", d, None),
            ApiError::Busy { detail, retry_after } => {
                retry = Some(retry_after);
                (StatusCode::SERVICE_UNAVAILABLE, "Busy", detail, None)
            }
            ApiError::Internal(d) => {
                tracing::error!("internal error: {d}");
                (
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "Internal error",
                    "the server failed; see its log".to_string(),
                    None,
                )
            }
        };
        let mut body = json!({ "type": "about:blank", "title": title, "status": status.as_u16(), "detail": detail });
        if let Some(e) = errors {
            body["errors"] = e;
        }
        let mut response =
            (status, [(header::CONTENT_TYPE, "application/problem+json")], body.to_string()).into_response();
        if let Some(seconds) = retry {
            response.headers_mut().insert(header::RETRY_AFTER, header::HeaderValue::from(seconds));
        }
        if status == StatusCode::UNAUTHORIZED {
            response.headers_mut().insert(header::WWW_AUTHENTICATE, header::HeaderValue::from_static("Bearer"));
        }
        response
    }
}

/// Gives axum's bare `405 Method Not Allowed` (its `Allow` header kept) a problem
/// body like every other error.
pub(super) async fn method_not_allowed(req: axum::extract::Request, next: axum::middleware::Next) -> Response {
    let what = format!("{} {}", req.method(), req.uri().path());
    let response = next.run(req).await;
    if response.status() != StatusCode::METHOD_NOT_ALLOWED || response.headers().contains_key(header::CONTENT_TYPE) {
        return response;
    }
    let (mut parts, _) = response.into_parts();
    let body = json!({
        "type": "about:blank",
        "title": "Method not allowed",
        "status": 405,
        "detail": format!("{what}: the method is not allowed on this path (see the Allow header)"),
    });
    parts.headers.insert(header::CONTENT_TYPE, header::HeaderValue::from_static("application/problem+json"));
    Response::from_parts(parts, axum::body::Body::from(body.to_string()))
}
