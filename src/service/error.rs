//! API errors as RFC 9457 problem details (`application/problem+json`); internal
//! errors are logged, never sent to clients.

use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use serde_json::json;

#[derive(Debug)]
pub enum ApiError {
    /// 422 with the offending field.
    Invalid {
        field: String,
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
    Internal(String),
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        ApiError::Internal(e.to_string())
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let (status, title, detail, errors) = match self {
            ApiError::Invalid { field, detail } => (
                StatusCode::UNPROCESSABLE_ENTITY,
                "Invalid job spec",
                format!("{field}: {detail}"),
                Some(json!([{ "field": field, "detail": detail }])),
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
            ApiError::Unauthorized => (
                StatusCode::UNAUTHORIZED,
                "Unauthorized",
                "missing or wrong `Authorization: Bearer` token".into(),
                None,
            ),
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
        (status, [(header::CONTENT_TYPE, "application/problem+json")], body.to_string()).into_response()
    }
}
