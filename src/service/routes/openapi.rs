//! `GET /v1/openapi.json`: the HTTP contract.

use axum::Json;
use serde_json::Value;

/// The contract `api/openapi.yaml`, embedded at build time.
pub const OPENAPI_YAML: &str = include_str!("../../../api/openapi.yaml");

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

pub(super) async fn document() -> Json<Value> {
    Json(openapi_json().clone())
}
