//! The rows a store reads and writes, the lease a worker holds, and the store's
//! errors.

use crate::flow::Progress;
use crate::service::blobs::BlobError;
use std::time::Duration;

/// The status of a job (OGC API – Processes), as stored and as the API shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JobStatus {
    Accepted,
    Running,
    Successful,
    Failed,
    Dismissed,
}

impl JobStatus {
    pub const ALL: [JobStatus; 5] =
        [JobStatus::Accepted, JobStatus::Running, JobStatus::Successful, JobStatus::Failed, JobStatus::Dismissed];

    pub fn as_str(self) -> &'static str {
        match self {
            JobStatus::Accepted => "accepted",
            JobStatus::Running => "running",
            JobStatus::Successful => "successful",
            JobStatus::Failed => "failed",
            JobStatus::Dismissed => "dismissed",
        }
    }

    pub fn parse(s: &str) -> Option<JobStatus> {
        JobStatus::ALL.into_iter().find(|x| x.as_str() == s)
    }

    /// The job has ended (it will not run again).
    pub fn is_final(self) -> bool {
        matches!(self, JobStatus::Successful | JobStatus::Failed | JobStatus::Dismissed)
    }
}

/// A stored status text (the tables' CHECK constraints allow only these).
pub(crate) fn status_of(text: &str) -> JobStatus {
    JobStatus::parse(text).unwrap_or(JobStatus::Failed)
}

/// A job as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct JobRow {
    pub id: String,
    /// Submission order (1, 2, ...).
    pub seq: i64,
    pub status: JobStatus,
    pub spec: String,
    pub created_at: String,
    pub started_at: Option<String>,
    pub finished_at: Option<String>,
    pub message: Option<String>,
    pub stop_reason: Option<String>,
    pub progress: Option<Progress>,
    /// The stored result files, once written.
    pub results: Option<ResultIndex>,
    /// The name of the key that created the job (`None`: no key, or the token).
    pub owner: Option<String>,
}

/// An API key: its name, the SHA-256 of the key (hex), whether it is an admin's,
/// its quotas (jobs accepted or running, bytes its jobs keep), and whether it
/// was revoked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyRow {
    pub name: String,
    pub hash: String,
    pub admin: bool,
    pub max_active: Option<i64>,
    pub max_storage: Option<i64>,
    pub created_at: String,
    pub revoked: bool,
}

/// Who a new job belongs to and what it may not pass when it is inserted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Admission {
    pub owner: Option<String>,
    /// Jobs of `owner` accepted or running at most (with this one).
    pub max_active: Option<i64>,
    /// Jobs accepted (waiting) on the whole service at most (with this one).
    pub max_queued: Option<i64>,
    /// Bytes the jobs of `owner` keep at most: no new job once they keep that much.
    pub max_storage: Option<i64>,
}

impl Admission {
    /// Whether any limit is to be checked.
    pub fn limited(&self) -> bool {
        self.max_queued.is_some() || (self.owner.is_some() && (self.max_active.is_some() || self.max_storage.is_some()))
    }
}

/// A checkpoint's frame, serialized: its iteration, time and JSON.
#[derive(Debug, Clone, PartialEq)]
pub struct MadeFrame {
    pub iteration: usize,
    pub time: f64,
    pub json: Vec<u8>,
}

impl MadeFrame {
    pub fn of(frame: &crate::jobs::Frame) -> MadeFrame {
        let json = serde_json::to_vec(frame).expect("frames serialize");
        MadeFrame { iteration: frame.state.iteration, time: frame.state.time, json }
    }
}

/// The lease a worker holds on a running job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Lease {
    pub owner: String,
    pub epoch: i64,
}

/// How claims behave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClaimPolicy {
    /// Length of a lease; renewed by heartbeats every third of it.
    pub lease: Duration,
    /// A job whose lease expired this many times (its worker died each time) ends
    /// failed instead of being claimed again.
    pub max_takeovers: i64,
}

impl Default for ClaimPolicy {
    fn default() -> Self {
        ClaimPolicy { lease: Duration::from_secs(15), max_takeovers: 3 }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error(transparent)]
    Db(#[from] sqlx::Error),
    #[error("database migration: {0}")]
    Migrate(#[from] sqlx::migrate::MigrateError),
    /// The job's lease moved on (another node took the job over): nothing was written.
    #[error("job {0}: the lease was lost to another worker")]
    LeaseLost(String),
    /// The blob store refused or failed.
    #[error("blob store: {0}")]
    Blob(#[from] BlobError),
    /// A new job was not inserted: its key has `max_active` jobs accepted or running.
    #[error("the key has {0} jobs accepted or running, its quota")]
    ActiveQuota(i64),
    /// A new job was not inserted: the service has `max_queued` jobs waiting.
    #[error("the service has {0} jobs waiting, as many as it queues")]
    QueueFull(i64),
    /// A new job was not inserted: the key's jobs keep `.0` bytes of its `max_storage` `.1`.
    #[error("the key's jobs keep {0} bytes, its storage quota is {1} bytes")]
    StorageQuota(i64, i64),
}

pub type StoreResult<T> = Result<T, StoreError>;

impl StoreError {
    /// The database could not be reached (restarting, connection lost), or ended
    /// the session (a transaction left idle too long while this node was paused:
    /// 25P03): the same request may succeed a moment later on a new connection.
    pub fn is_transient(&self) -> bool {
        match self {
            StoreError::Db(sqlx::Error::Database(e)) => {
                e.code().is_some_and(|c| c.starts_with("08") || c.starts_with("57P") || c == "25P03")
            }
            StoreError::Db(e) => matches!(
                e,
                sqlx::Error::Io(_) | sqlx::Error::PoolTimedOut | sqlx::Error::Protocol(_) | sqlx::Error::WorkerCrashed
            ),
            _ => false,
        }
    }
}

/// A job claimed by a worker: the job and the lease it now holds.
#[derive(Debug, Clone)]
pub struct Claimed {
    pub job: JobRow,
    pub lease: Lease,
    /// The job's lease had expired: this claim takes it over from a dead worker.
    pub takeover: bool,
}

/// Which checkpoint rows to read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    Last,
    At(i64),
    /// At most [`CHECKPOINT_PAGE`] rows after this iteration (`-1`: from the
    /// first), oldest first: a page, so that no read grows with a job's length.
    After(i64),
}

/// Bytes a history row takes in the database, about (the disk budget's count).
pub const HISTORY_ROW_BYTES: u64 = 64;

/// Checkpoint rows read at a time ([`Which::After`], `checkpoint_index`).
pub const CHECKPOINT_PAGE: usize = 4096;

/// A checkpoint row: the key of its frame in the blob store, or (rows stored
/// before blobs) the checkpoint's JSON itself.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckpointRow {
    pub iteration: i64,
    pub blob: Option<String>,
    pub data: String,
}

/// An input row: its name, and its bytes unless they are in the blob store.
#[derive(Debug, Clone, PartialEq)]
pub struct InputRow {
    pub name: String,
    pub in_blob: bool,
    pub data: Vec<u8>,
}

/// The result files a job's row points to: the blob folder `results/{set}` of the
/// job and the files in it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ResultIndex {
    pub set: String,
    pub files: Vec<ResultEntry>,
}

/// Result files written to a new blob folder ([`super::JobStore::store_results`])
/// and not yet pointed to by the row.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredResults {
    /// The [`ResultIndex`] as stored in the row.
    pub index: String,
    /// The new folder.
    pub set: String,
    /// The folder the row pointed to before, if another.
    pub before: Option<String>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ResultEntry {
    pub name: String,
    pub media_type: String,
}

/// The row of a stored checkpoint: its iteration and time, and the key of its
/// frame in the blob store.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckpointKey {
    pub iteration: i64,
    pub time: f64,
    pub key: String,
}
