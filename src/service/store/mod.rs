//! The job store: one trait, [`JobStore`], with a SQLite implementation (the
//! embedded default, one node) and a PostgreSQL one (any number of nodes); SQL
//! lives only in those two files. Each backend has its own migrations
//! (`migrations/sqlite`, `migrations/postgres`); what the two share is written
//! once, in `shared`. The large bytes (inputs,
//! checkpoints with their fields, result files) go to the blob store
//! ([`Blobs`]) before the rows that point to them; `types` has the rows.
//!
//! A running job holds a lease: its owner, an epoch (raised by every claim) and an
//! expiry on the database's clock. Every write of a job's history, checkpoints and
//! outcome names the lease it holds and is refused ([`StoreError::LeaseLost`]) if
//! the job's epoch has moved on, so a worker that lost its lease (paused,
//! partitioned) changes nothing. A job whose lease expired is claimed again by
//! any node and resumes from its last checkpoint.

#[macro_use]
mod shared;
mod migrations;
mod postgres;
mod rows;
mod sqlite;
mod time;
mod types;

use super::blobs::{input_key, BlobError, Blobs};
use crate::flow::{Checkpoint, Progress};
use crate::jobs::{Frame, GlbContext, KeptFrames, ResultFile};
use futures_util::TryFutureExt;
use std::collections::HashMap;
use std::sync::Arc;

pub use postgres::PgStore;
pub(crate) use rows::{crash_message, results_of, surgery_json, ABANDONED};
pub use sqlite::SqliteStore;
pub(crate) use time::now;
pub use time::rfc3339_ago;
pub(crate) use types::status_of;
pub use types::{
    Admission, CheckpointKey, CheckpointRow, ClaimPolicy, Claimed, InputRow, JobRow, JobStatus, KeyRow, Lease,
    MadeFrame, ResultEntry, ResultIndex, StoreError, StoreResult, StoredResults, Which, CHECKPOINT_PAGE,
    HISTORY_ROW_BYTES,
};

/// What every backend stores and how (see the module documentation). The
/// required methods are SQL on the backend's rows; the provided ones put the
/// large bytes in the blob store first and the rows that point to them after.
#[async_trait::async_trait]
pub trait JobStore: Send + Sync + 'static {
    /// Which backend ("sqlite", "postgres").
    fn backend(&self) -> &'static str;
    /// Where inputs, frames and result files are kept.
    fn blobs(&self) -> &Blobs;
    /// Forward other nodes' activity to `events` (a job's id per history batch or
    /// outcome; `"*"`: re-read everything). Nothing to do on a single node, whose
    /// workers send to `events` themselves.
    fn watch(&self, _events: tokio::sync::broadcast::Sender<Arc<str>>) {}
    /// Whether the store announces every history batch and outcome itself (to
    /// every node, through [`JobStore::watch`]), so that a node's writers need not
    /// announce batches again to its own event streams (a stream woken twice reads
    /// the database twice; outcomes are announced at once all the same, and a
    /// stream that read one has ended).
    fn announces(&self) -> bool {
        false
    }
    /// Whether the database takes writes now (readiness): an error if not.
    async fn writable(&self) -> StoreResult<()>;
    /// Insert a new accepted job and the rows of its inputs (already in the blob
    /// store; `heads`: name and first bytes of each), in one transaction, owned by
    /// `admit.owner`; refused ([`StoreError::ActiveQuota`], [`StoreError::QueueFull`])
    /// if it would pass `admit`'s limits, which the transaction checks atomically.
    async fn insert_rows(
        &self,
        id: &str,
        spec: &str,
        heads: &[(String, Vec<u8>)],
        admit: &Admission,
    ) -> StoreResult<JobRow>;
    /// The first bytes (at most 8) of each uploaded input of a job.
    async fn input_magics(&self, id: &str) -> StoreResult<Vec<Vec<u8>>>;
    async fn input_rows(&self, id: &str) -> StoreResult<Vec<InputRow>>;
    async fn job(&self, id: &str) -> StoreResult<Option<JobRow>>;
    /// Jobs newest first, optionally of one status, submitted before `before`
    /// (a `seq`) and owned by `owner`, at most `limit`.
    async fn list(
        &self,
        status: Option<JobStatus>,
        before: Option<i64>,
        limit: i64,
        owner: Option<&str>,
    ) -> StoreResult<Vec<JobRow>>;
    /// Jobs that ended before `before` (RFC 3339), oldest first, at most `limit`.
    async fn ended_before(&self, before: &str, limit: i64) -> StoreResult<Vec<String>>;
    /// Give the space of deleted rows back to the disk (SQLite: an incremental
    /// vacuum and a checkpoint of the WAL); nothing to do elsewhere. Whether it
    /// all went back: false when a busy writer kept the checkpoint from the end
    /// of the WAL (the sweep tries again).
    async fn reclaim(&self) -> StoreResult<bool> {
        Ok(true)
    }
    /// The number of jobs of each status present.
    async fn counts_by_status(&self) -> StoreResult<Vec<(String, i64)>>;
    /// Store a new key; `false` if one of that name exists (revoked or not).
    async fn insert_key(&self, key: &KeyRow) -> StoreResult<bool>;
    /// Every key, revoked ones too, by name.
    async fn keys(&self) -> StoreResult<Vec<KeyRow>>;
    /// Revoke the key `name`; `false` if there is no such key not yet revoked.
    async fn revoke_key(&self, name: &str) -> StoreResult<bool>;
    /// The key (not revoked) whose hash is `hash`.
    async fn key_by_hash(&self, hash: &str) -> StoreResult<Option<KeyRow>>;
    /// Whether any key (not revoked) exists: then every `/v1` route needs one.
    async fn has_keys(&self) -> StoreResult<bool>;
    /// The bytes kept by the jobs of `owner` other than `except` (as of their
    /// attempts' ends, [`JobStore::set_stored`]).
    async fn owner_storage(&self, owner: &str, except: &str) -> StoreResult<u64>;
    /// Note the bytes a job keeps now (its checkpoints, result files and history).
    async fn set_stored(&self, id: &str, bytes: u64) -> StoreResult<()>;
    /// Whether `node` leads `task` (a sweep that one node of a cluster at a time
    /// does) for the next `ttl`: taken if free or expired, extended if held.
    async fn lead(&self, task: &str, node: &str, ttl: std::time::Duration) -> StoreResult<bool>;
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
    /// End an attempt that went wrong (its process died, it panicked): the lease
    /// expires now, so that the next claim takes the job over from its last
    /// checkpoint and counts the attempt ([`ClaimPolicy::max_takeovers`]); the
    /// job's message says why ([`ABANDONED`] and `why`); fenced.
    async fn abandon(&self, id: &str, lease: &Lease, why: &str) -> StoreResult<()>;
    /// `(iteration, time)` of the checkpoints of a job after iteration `after`
    /// (`-1`: from the first), oldest first, at most [`CHECKPOINT_PAGE`].
    async fn checkpoint_index(&self, id: &str, after: i64) -> StoreResult<Vec<(i64, f64)>>;
    /// Checkpoint rows of a job, oldest first.
    async fn checkpoint_rows(&self, id: &str, which: Which) -> StoreResult<Vec<CheckpointRow>>;
    /// Append history rows (replacing rows already present after a resume), update
    /// the job's progress and add the rows of checkpoints (their iteration, time
    /// and the key of their frame), in one transaction fenced by `lease`; on
    /// PostgreSQL also one notification for the batch. Returns whether
    /// cancellation was requested (read by the fence).
    async fn record_rows(
        &self,
        id: &str,
        lease: &Lease,
        rows: &[Progress],
        checkpoints: &[CheckpointKey],
    ) -> StoreResult<bool>;
    /// Drop history rows after a checkpoint (before resuming from it); fenced.
    async fn truncate_history(&self, id: &str, lease: &Lease, after: usize) -> StoreResult<()>;
    /// Point the job's row to its result files: fenced by `lease` if given (a
    /// worker), else only if the row points to none yet (results of an ended job
    /// written on first request). Returns whether the row was changed.
    async fn set_results(&self, id: &str, lease: Option<&Lease>, index: &str) -> StoreResult<bool>;
    /// End a job: fenced by `lease` if given (a worker), unconditional otherwise
    /// (cancelling an accepted job). `results`, the index of result files stored
    /// with [`JobStore::store_results`], points the row to them in the same
    /// transaction.
    async fn finish(
        &self,
        id: &str,
        lease: Option<&Lease>,
        status: JobStatus,
        stop_reason: Option<&str>,
        message: Option<&str>,
        results: Option<&str>,
    ) -> StoreResult<()>;
    /// Whether cancellation was requested (true for a job that no longer exists).
    async fn cancel_requested(&self, id: &str) -> StoreResult<bool>;
    /// Request cancellation: an accepted job is dismissed at once, a running one
    /// flagged (its worker, on whichever node, sees the flag at its next write).
    /// Returns the status before the request, `None` if unknown.
    async fn request_cancel(&self, id: &str) -> StoreResult<Option<JobStatus>>;
    /// Mark an ended job deleted: from now on it is absent from every read
    /// ([`JobStore::job`], lists, counts) and its rows and blobs go in the
    /// background ([`JobStore::purge`]). `false` if there is no such ended job.
    async fn mark_deleted(&self, id: &str) -> StoreResult<bool>;
    /// Jobs marked deleted and not yet purged, the oldest marks first.
    async fn deleted_jobs(&self, limit: i64) -> StoreResult<Vec<String>>;
    /// Delete a few thousand rows of a job marked deleted (history, then
    /// checkpoints), or its row once they are gone: `true` when the row is gone.
    async fn purge_rows(&self, id: &str) -> StoreResult<bool>;
    /// The number of a job's history rows.
    async fn history_count(&self, id: &str) -> StoreResult<u64>;
    /// History rows from iteration `from` on, at most `limit`.
    async fn history_from(&self, id: &str, from: usize, limit: usize) -> StoreResult<Vec<Progress>>;

    async fn history(&self, id: &str) -> StoreResult<Vec<Progress>> {
        self.history_from(id, 0, usize::MAX).await
    }

    /// Store a new accepted job: its inputs in the blob store, then its rows.
    async fn insert_job(
        &self,
        id: &str,
        spec: &str,
        inputs: &HashMap<String, Vec<u8>>,
        admit: &Admission,
    ) -> StoreResult<JobRow> {
        let mut heads = Vec::with_capacity(inputs.len());
        for (name, data) in inputs {
            self.blobs().put(&input_key(id, name), data.clone()).await?;
            heads.push((name.clone(), data[..data.len().min(8)].to_vec()));
        }
        let inserted = self.insert_rows(id, spec, &heads, admit).await;
        if inserted.is_err() && !inputs.is_empty() {
            // refused or failed: its inputs are not kept
            let _ = self.blobs().delete_all(&["jobs", id]).await;
        }
        inserted
    }

    /// The uploaded inputs of a job, by name.
    async fn inputs(&self, id: &str) -> StoreResult<HashMap<String, Vec<u8>>> {
        let mut inputs = HashMap::new();
        for row in self.input_rows(id).await? {
            let data = if row.in_blob { self.blobs().get_existing(&input_key(id, &row.name)).await? } else { row.data };
            inputs.insert(row.name, data);
        }
        Ok(inputs)
    }

    /// Checkpoints of a job with their fields, oldest first.
    async fn frames(&self, id: &str, which: Which) -> StoreResult<Vec<Frame>> {
        let mut frames = Vec::new();
        for row in self.checkpoint_rows(id, which).await? {
            let iteration = row.iteration;
            let bytes = self.frame_json(id, row).await?;
            let frame = serde_json::from_slice(&bytes)
                .map_err(|e| BlobError(format!("checkpoint {iteration} of job {id} cannot be read: {e}")))?;
            frames.push(frame);
        }
        Ok(frames)
    }

    /// The JSON of a stored checkpoint's frame.
    async fn frame_json(&self, id: &str, row: CheckpointRow) -> StoreResult<Vec<u8>> {
        Ok(match &row.blob {
            Some(key) => self.blobs().get_existing(&["jobs", id, "checkpoints", key]).await?,
            None => row.data.into_bytes(),
        })
    }

    /// The frames of a job's stored checkpoints that evolution.glb keeps
    /// ([`KeptFrames`]), read a page of rows and one frame at a time; a frame that
    /// cannot be read is left out with a warning.
    async fn kept_frames(&self, id: &str) -> StoreResult<KeptFrames> {
        let mut kept = KeptFrames::default();
        let mut after = -1;
        loop {
            let rows = self.checkpoint_rows(id, Which::After(after)).await?;
            let Some(last) = rows.last() else { return Ok(kept) };
            after = last.iteration;
            for row in rows {
                let iteration = row.iteration;
                let json = self.frame_json(id, row).await?;
                match serde_json::from_slice::<Frame>(&json) {
                    Ok(frame) => kept.push(frame),
                    Err(e) => tracing::warn!(job = %id, iteration, "a stored checkpoint cannot be read: {e}"),
                }
            }
        }
    }

    /// The number of a job's stored checkpoints (read a page of the index at a time).
    async fn checkpoint_count(&self, id: &str) -> StoreResult<usize> {
        let (mut count, mut after) = (0, -1);
        loop {
            let page = self.checkpoint_index(id, after).await?;
            let Some(&(last, _)) = page.last() else { return Ok(count) };
            (count, after) = (count + page.len(), last);
        }
    }

    /// What a job stores now against its disk budget: its checkpoints' frames,
    /// its result files and [`HISTORY_ROW_BYTES`] per history row.
    async fn stored_bytes(&self, id: &str) -> StoreResult<u64> {
        let frames = self.blobs().size_all(&["jobs", id, "checkpoints"]).await?;
        let results = self.blobs().size_all(&["jobs", id, "results"]).await?;
        Ok(frames + results + self.history_count(id).await? * HISTORY_ROW_BYTES)
    }

    /// The newest checkpoint of a job.
    async fn last_checkpoint(&self, id: &str) -> StoreResult<Option<Checkpoint>> {
        Ok(self.frames(id, Which::Last).await?.pop().map(|f| f.state))
    }

    /// History rows and checkpoints with their fields (each frame in the blob store
    /// under a key with the lease's epoch, then their rows), in one transaction:
    /// see [`JobStore::record_rows`].
    async fn record(&self, id: &str, lease: &Lease, rows: &[Progress], frames: &[Frame]) -> StoreResult<bool> {
        let made: Vec<MadeFrame> = frames.iter().map(MadeFrame::of).collect();
        self.record_made(id, lease, rows, &made).await
    }

    /// [`JobStore::record`] of frames already serialized.
    async fn record_made(&self, id: &str, lease: &Lease, rows: &[Progress], frames: &[MadeFrame]) -> StoreResult<bool> {
        let mut keys = Vec::with_capacity(frames.len());
        for frame in frames {
            let key = format!("{}.e{}.json", frame.iteration, lease.epoch);
            self.blobs().put(&["jobs", id, "checkpoints", &key], frame.json.clone()).await?;
            keys.push(CheckpointKey { iteration: frame.iteration as i64, time: frame.time, key });
        }
        self.record_rows(id, lease, rows, &keys).await
    }

    /// Store the result files of a job in a new blob folder (named after `lease`'s
    /// epoch for a worker), beside a read of the folder the row points to now; the
    /// row is not changed (see [`JobStore::finish`] and [`JobStore::put_results`]).
    async fn store_results(&self, id: &str, lease: Option<&Lease>, files: &[ResultFile]) -> StoreResult<StoredResults> {
        let set = match lease {
            Some(l) => format!("e{}", l.epoch),
            None => format!("r{}", uuid::Uuid::new_v4().simple()),
        };
        // the files at once (on S3 each is a request), the row's current index beside them
        let set_ref = set.as_str();
        let puts = files.iter().map(|f| async move {
            self.blobs().put(&["jobs", id, "results", set_ref, &f.name], f.bytes.clone()).await
        });
        let (_, job) = futures_util::future::try_join(
            futures_util::future::try_join_all(puts).map_err(StoreError::from),
            self.job(id),
        )
        .await?;
        let before = job.and_then(|j| j.results).map(|b| b.set).filter(|b| *b != set);
        let entries = files
            .iter()
            .map(|f| ResultEntry { name: f.name.to_string(), media_type: f.media_type.to_string() })
            .collect();
        let index = serde_json::to_string(&ResultIndex { set: set.clone(), files: entries }).expect("serializes");
        Ok(StoredResults { index, set, before })
    }

    /// After the row was (or was not) pointed to `stored`: drop the folder that is
    /// no longer pointed to.
    async fn drop_results(&self, id: &str, stored: &StoredResults, pointed: bool) -> StoreResult<()> {
        let old = if pointed { stored.before.as_deref() } else { Some(stored.set.as_str()) };
        if let Some(old) = old {
            self.blobs().delete_all(&["jobs", id, "results", old]).await?;
        }
        Ok(())
    }

    /// Store the result files of a job (see [`JobStore::set_results`] for `lease`)
    /// in a new blob folder, point the row to it and drop the folder it pointed to
    /// before. Returns whether the files were stored.
    async fn put_results(&self, id: &str, lease: Option<&Lease>, files: &[ResultFile]) -> StoreResult<bool> {
        let stored = self.store_results(id, lease, files).await?;
        let changed = self.set_results(id, lease, &stored.index).await?;
        self.drop_results(id, &stored, changed).await?;
        Ok(changed)
    }

    /// A stored result file of job `id` whose row points to `index`: its media
    /// type and bytes.
    async fn result_file(&self, id: &str, index: &ResultIndex, name: &str) -> StoreResult<Option<(String, Vec<u8>)>> {
        let Some(entry) = index.files.iter().find(|f| f.name == name) else { return Ok(None) };
        let bytes = self.blobs().get_existing(&["jobs", id, "results", &index.set, name]).await?;
        Ok(Some((entry.media_type.clone(), bytes)))
    }

    /// Store what every glb of the job shares ([`GlbContext`]), as its JSON.
    async fn put_context(&self, id: &str, json: Vec<u8>) -> StoreResult<()> {
        Ok(self.blobs().put(&["jobs", id, "context.json"], json).await?)
    }

    async fn context(&self, id: &str) -> StoreResult<Option<GlbContext>> {
        let Some(bytes) = self.blobs().get(&["jobs", id, "context.json"]).await? else { return Ok(None) };
        Ok(serde_json::from_slice(&bytes).ok())
    }

    /// Delete a job marked deleted: its blobs, then its rows a statement of a few
    /// thousand at a time (the writer is never held long), the job's row last,
    /// so that a purge cut short is taken up again by the next.
    async fn purge(&self, id: &str) -> StoreResult<()> {
        self.blobs().delete_all(&["jobs", id]).await?;
        while !self.purge_rows(id).await? {
            tokio::task::yield_now().await;
        }
        Ok(())
    }
}

/// The store of a running service.
pub type Store = Arc<dyn JobStore>;

/// Open the store `database` names: `postgres://…` / `postgresql://…`, a
/// `sqlite:` URL, or a SQLite file path (created if missing); migrated. Its
/// large bytes go to `blobs`.
pub async fn open(database: &str, blobs: Blobs) -> StoreResult<Store> {
    if database.starts_with("postgres://") || database.starts_with("postgresql://") {
        Ok(Arc::new(PgStore::open(database, blobs).await?))
    } else {
        let path = database.strip_prefix("sqlite://").or_else(|| database.strip_prefix("sqlite:")).unwrap_or(database);
        Ok(Arc::new(SqliteStore::open(std::path::Path::new(path), blobs).await?))
    }
}
