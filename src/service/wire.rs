//! The bodies the API answers with (api/openapi.yaml's schemas), as typed structs.

use super::store::{JobRow, JobStatus};
use crate::flow::Progress;
use serde::Serialize;

/// A job (`Job` in the OpenAPI document): `GET /v1/jobs/{id}`, list entries, the
/// 201 of a submission and the `status` event of the stream.
#[derive(Debug, Serialize)]
pub struct JobView<'a> {
    pub id: &'a str,
    pub status: JobStatus,
    pub progress: Option<Progress>,
    pub stop_reason: Option<&'a str>,
    pub message: Option<&'a str>,
    pub created: &'a str,
    pub started: Option<&'a str>,
    pub finished: Option<&'a str>,
}

impl<'a> From<&'a JobRow> for JobView<'a> {
    fn from(j: &'a JobRow) -> Self {
        JobView {
            id: &j.id,
            status: j.status,
            progress: j.progress,
            stop_reason: j.stop_reason.as_deref(),
            message: j.message.as_deref(),
            created: &j.created_at,
            started: j.started_at.as_deref(),
            finished: j.finished_at.as_deref(),
        }
    }
}

/// `GET /v1/jobs`: a page of jobs, newest first.
#[derive(Debug, Serialize)]
pub struct JobList<'a> {
    pub jobs: Vec<JobView<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub next_page_token: Option<String>,
}

/// One entry of a manifest.
#[derive(Debug, Serialize)]
pub struct ResultFile {
    pub name: String,
    pub href: String,
    #[serde(rename = "type")]
    pub media_type: String,
}

/// `GET /v1/jobs/{id}/results`: the result files available now.
#[derive(Debug, Serialize)]
pub struct Manifest<'a> {
    pub id: &'a str,
    pub status: JobStatus,
    #[serde(rename = "final")]
    pub is_final: bool,
    pub files: Vec<ResultFile>,
    pub checkpoints: String,
}

/// One checkpoint of `GET /v1/jobs/{id}/checkpoints`.
#[derive(Debug, Serialize)]
pub struct CheckpointEntry {
    pub iteration: i64,
    pub time: f64,
    pub href: String,
}
