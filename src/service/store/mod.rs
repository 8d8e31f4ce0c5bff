//! The job store: one trait, [`JobStore`], with a SQLite implementation (the
//! embedded default, one node) and a PostgreSQL one (any number of nodes); SQL
//! lives only in those two files. Each backend has its own migrations
//! (`migrations/sqlite`, `migrations/postgres`).
//!
//! A running job holds a lease: its owner, an epoch (raised by every claim) and an
//! expiry on the database's clock. Every write of a job's history, checkpoints and
//! outcome names the lease it holds and is refused ([`StoreError::LeaseLost`]) if
//! the job's epoch has moved on, so a worker that lost its lease (paused,
//! partitioned) changes nothing. A job whose lease expired is claimed again by
//! any node and resumes from its last checkpoint.

mod postgres;
mod sqlite;

use crate::flow::{Checkpoint, Progress};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

pub use postgres::PgStore;
pub use sqlite::SqliteStore;

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

/// What every backend stores and how (see the module documentation).
#[async_trait::async_trait]
pub trait JobStore: Send + Sync + 'static {
    /// Which backend ("sqlite", "postgres").
    fn backend(&self) -> &'static str;
    /// Forward other nodes' activity to `events` (a job's id per history batch or
    /// outcome; `"*"`: re-read everything). Nothing to do on a single node, whose
    /// workers send to `events` themselves.
    fn watch(&self, _events: tokio::sync::broadcast::Sender<Arc<str>>) {}
    /// Store a new accepted job and its uploaded inputs, in one transaction.
    async fn insert_job(&self, id: &str, spec: &str, inputs: &HashMap<String, Vec<u8>>) -> StoreResult<JobRow>;
    /// The first bytes (at most 8) of each uploaded input of a job.
    async fn input_magics(&self, id: &str) -> StoreResult<Vec<Vec<u8>>>;
    /// The uploaded inputs of a job, by name.
    async fn inputs(&self, id: &str) -> StoreResult<HashMap<String, Vec<u8>>>;
    async fn job(&self, id: &str) -> StoreResult<Option<JobRow>>;
    /// Jobs newest first, optionally of one status and submitted before `before`
    /// (a `seq`), at most `limit`.
    async fn list(&self, status: Option<JobStatus>, before: Option<i64>, limit: i64) -> StoreResult<Vec<JobRow>>;
    /// Single node only (SQLite): jobs left running by a crash or a stop go back to
    /// the queue at start. On a shared database this is the leases' work: 0.
    async fn requeue_running(&self) -> StoreResult<u64>;
    /// Claim the oldest accepted job, or a running one whose lease expired, for
    /// `owner`, in one short transaction. A job taken over more than
    /// `policy.max_takeovers` times is ended failed instead (and the next looked at).
    async fn claim_next(&self, owner: &str, policy: &ClaimPolicy) -> StoreResult<Option<Claimed>>;
    /// Extend the lease by `policy.lease`; `false` if it was lost.
    async fn renew(&self, id: &str, lease: &Lease, policy: &ClaimPolicy) -> StoreResult<bool>;
    /// Give a running job back to the queue (a node stopping); fenced.
    async fn release(&self, id: &str, lease: &Lease) -> StoreResult<()>;
    /// The newest checkpoint of a job.
    async fn last_checkpoint(&self, id: &str) -> StoreResult<Option<Checkpoint>>;
    /// `(iteration, time)` of every checkpoint of a job, oldest first.
    async fn checkpoint_index(&self, id: &str) -> StoreResult<Vec<(i64, f64)>>;
    /// The checkpoint of a job at `iteration`.
    async fn checkpoint_at(&self, id: &str, iteration: i64) -> StoreResult<Option<Checkpoint>>;
    /// Every checkpoint of a job, oldest first.
    async fn checkpoints(&self, id: &str) -> StoreResult<Vec<Checkpoint>>;
    /// Append history rows (replacing rows already present after a resume), update
    /// the job's progress and store a checkpoint, in one transaction fenced by
    /// `lease`; on PostgreSQL also one notification for the batch. Returns whether
    /// cancellation was requested (read by the fence).
    async fn record(
        &self,
        id: &str,
        lease: &Lease,
        rows: &[Progress],
        checkpoint: Option<&Checkpoint>,
    ) -> StoreResult<bool>;
    /// Drop history rows after a checkpoint (before resuming from it); fenced.
    async fn truncate_history(&self, id: &str, lease: &Lease, after: usize) -> StoreResult<()>;
    /// End a job: fenced by `lease` if given (a worker), unconditional otherwise
    /// (cancelling an accepted job).
    async fn finish(
        &self,
        id: &str,
        lease: Option<&Lease>,
        status: JobStatus,
        stop_reason: Option<&str>,
        message: Option<&str>,
    ) -> StoreResult<()>;
    /// Whether cancellation was requested (true for a job that no longer exists).
    async fn cancel_requested(&self, id: &str) -> StoreResult<bool>;
    /// Request cancellation: an accepted job is dismissed at once, a running one
    /// flagged (its worker, on whichever node, sees the flag at its next write).
    /// Returns the status before the request, `None` if unknown.
    async fn request_cancel(&self, id: &str) -> StoreResult<Option<JobStatus>>;
    async fn delete(&self, id: &str) -> StoreResult<()>;
    /// History rows from iteration `from` on, at most `limit`.
    async fn history_from(&self, id: &str, from: usize, limit: usize) -> StoreResult<Vec<Progress>>;
    async fn history(&self, id: &str) -> StoreResult<Vec<Progress>> {
        self.history_from(id, 0, usize::MAX).await
    }
}

/// The store of a running service.
pub type Store = Arc<dyn JobStore>;

/// Open the store `database` names: `postgres://…` / `postgresql://…`, a
/// `sqlite:` URL, or a SQLite file path (created if missing); migrated.
pub async fn open(database: &str) -> StoreResult<Store> {
    if database.starts_with("postgres://") || database.starts_with("postgresql://") {
        Ok(Arc::new(PgStore::open(database).await?))
    } else {
        let path = database.strip_prefix("sqlite://").or_else(|| database.strip_prefix("sqlite:")).unwrap_or(database);
        Ok(Arc::new(SqliteStore::open(std::path::Path::new(path)).await?))
    }
}

/// RFC 3339 UTC from the system clock (timestamps shown to users; leases use the
/// database's clock).
pub(crate) fn now() -> String {
    let secs =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0);
    let days = (secs / 86400.0).floor() as i64;
    let rem = secs - days as f64 * 86400.0;
    let (h, m, s) = ((rem / 3600.0) as i64, ((rem % 3600.0) / 60.0) as i64, rem % 60.0);
    // civil from days (Howard Hinnant's algorithm)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + if mo <= 2 { 1 } else { 0 };
    format!("{y:04}-{mo:02}-{d:02}T{h:02}:{m:02}:{s:06.3}Z")
}

/// The message of a job ended after too many takeovers.
pub(crate) fn crash_message(takeovers: i64) -> String {
    format!("the job's worker stopped without a trace {takeovers} times (a node crashed or was killed while running it); not tried again")
}
