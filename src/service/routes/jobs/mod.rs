//! `/v1/jobs` and `/v1/jobs/{id}`: one module per endpoint.

pub(super) mod cancel;
pub(super) mod create;
pub(super) mod delete;
pub(super) mod get;
pub(super) mod list;
