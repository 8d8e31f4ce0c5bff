//! The SQLite store: the embedded default, for one node. One pool with a single
//! connection serializes writers (WAL, synchronous=NORMAL); the reads of requests
//! and event streams go through [`READERS`] read-only connections beside it;
//! leases work as on PostgreSQL, and jobs left running at a restart go back to the
//! queue.

use super::{
    migrations, now, results_of, status_of, surgery_json, Admission, Blobs, CheckpointKey, CheckpointRow, ClaimPolicy,
    Claimed, InputRow, JobRow, JobStatus, JobStore, KeyRow, Lease, StoreError, StoreResult, Which,
};
use crate::flow::Progress;
use sqlx::sqlite::{
    SqliteAutoVacuum, SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteSynchronous,
};
use sqlx::{Row, Sqlite};
use std::path::Path;
use std::time::Duration;

/// History rows per INSERT (7 parameters each, well below SQLite's 32,766).
const HISTORY_ROWS_PER_STATEMENT: usize = 512;

/// The database clock in ms since the Unix epoch, as SQL.
macro_rules! clock_ms {
    () => {
        "CAST((julianday('now') - 2440587.5) * 86400000.0 AS INTEGER)"
    };
}

mod leases;
use leases::{fence, fenced_progress};

#[derive(Clone)]
pub struct SqliteStore {
    /// One connection: the writer (SQLite has one at a time).
    pool: SqlitePool,
    /// Read-only connections for the reads of requests and event streams, which
    /// WAL lets run beside the writer and each other.
    reader: SqlitePool,
    blobs: Blobs,
}

/// Read-only connections beside the writer.
const READERS: u32 = 4;

/// How a writing transaction begins: the write lock at once (no upgrade from a
/// read lock that another writer could make fail).
const BEGIN: &str = "BEGIN IMMEDIATE";
/// None: the one writer's transaction already makes admissions one at a time.
const ADMISSION_LOCK: Option<&str> = None;
const INSERT_JOB: &str = "INSERT INTO jobs (id, seq, status, spec, created_at, owner) \
     VALUES ($1, (SELECT COALESCE(MAX(seq), 0) + 1 FROM jobs), 'accepted', $2, $3, $4)";

/// One node: its workers announce to its event streams themselves.
async fn notify(_tx: &mut sqlx::Transaction<'_, Sqlite>, _what: &str) -> StoreResult<()> {
    Ok(())
}

impl SqliteStore {
    /// Open (creating if missing) and migrate the database file.
    pub async fn open(path: &Path, blobs: Blobs) -> StoreResult<Self> {
        let options = SqliteConnectOptions::new()
            .filename(path)
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(10))
            .foreign_keys(true);
        // no ping before each acquire (sqlx's default): a connection to a local
        // file does not go stale, and the ping is one more round trip to the
        // connection's thread for every statement and transaction
        let pool = SqlitePoolOptions::new()
            .max_connections(1)
            .test_before_acquire(false)
            // a connection whose COMMIT failed (a full disk) is still in its
            // transaction for sqlx: closed, and the next write opens a new one
            .after_release(|conn, _| Box::pin(async move { Ok(!sqlx::Connection::is_in_transaction(conn)) }))
            // deleted rows' pages go back to the disk by `reclaim` (for a new file;
            // an older one needs a VACUUM once, docs/operations.md)
            .connect_with(options.clone().auto_vacuum(SqliteAutoVacuum::Incremental))
            .await?;
        migrations::migrator(migrations::SQLITE).run(&pool).await?;
        let reader = SqlitePoolOptions::new()
            .max_connections(READERS)
            .test_before_acquire(false)
            .connect_with(options.read_only(true))
            .await?;
        Ok(SqliteStore { pool, reader, blobs })
    }
}

job_store!(SqliteStore, sqlx::sqlite::SqliteRow, read: reader, write: pool, {
    fn backend(&self) -> &'static str {
        "sqlite"
    }

    async fn reclaim(&self) -> StoreResult<bool> {
        sqlx::query("PRAGMA incremental_vacuum").execute(&self.pool).await?;
        // (busy, frames in the WAL, frames checkpointed)
        let (busy, _, _): (i64, i64, i64) = sqlx::query_as("PRAGMA wal_checkpoint(TRUNCATE)").fetch_one(&self.pool).await?;
        Ok(busy == 0)
    }

    /// The write lock taken and given back.
    async fn writable(&self) -> StoreResult<()> {
        let tx = self.pool.begin_with(BEGIN).await?;
        Ok(tx.rollback().await?)
    }

    async fn requeue_running(&self) -> StoreResult<u64> {
        // the epoch moves on: a worker of the previous process can no longer write
        leases::requeue_running(&self.pool).await
    }

    async fn claim_next(&self, owner: &str, policy: &ClaimPolicy) -> StoreResult<Option<Claimed>> {
        leases::claim_next(&self.pool, owner, policy).await
    }

    async fn release(&self, id: &str, lease: &Lease) -> StoreResult<()> {
        leases::release(&self.pool, id, lease).await
    }

    async fn record_rows(
        &self,
        id: &str,
        lease: &Lease,
        rows: &[Progress],
        checkpoints: &[CheckpointKey],
    ) -> StoreResult<bool> {
        let mut tx = self.pool.begin_with(BEGIN).await?;
        let cancel = match rows.last() {
            Some(p) => fenced_progress(&mut tx, id, lease, p).await?,
            None => fence(&mut tx, id, lease).await?,
        };
        for chunk in rows.chunks(HISTORY_ROWS_PER_STATEMENT) {
            sqlx::QueryBuilder::<Sqlite>::new("INSERT OR REPLACE INTO history (job_id, iteration, time, tau, energy, vertices, components, surgery) ")
                .push_values(chunk, |mut row, p| {
                    row.push_bind(id)
                        .push_bind(p.iteration as i64)
                        .push_bind(p.time)
                        .push_bind(p.tau)
                        .push_bind(p.energy)
                        .push_bind(p.vertices as i64)
                        .push_bind(p.components as i64)
                        .push_bind(surgery_json(p));
                })
                .build()
                .execute(&mut *tx)
                .await?;
        }
        for c in checkpoints {
            sqlx::query(
                "INSERT OR REPLACE INTO checkpoints (job_id, iteration, time, data, blob) VALUES (?1, ?2, ?3, '', ?4)",
            )
            .bind(id)
            .bind(c.iteration)
            .bind(c.time)
            .bind(&c.key)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(cancel)
    }

    async fn finish(
        &self,
        id: &str,
        lease: Option<&Lease>,
        status: JobStatus,
        stop_reason: Option<&str>,
        message: Option<&str>,
        results: Option<&str>,
    ) -> StoreResult<()> {
        let mut tx = self.pool.begin_with(BEGIN).await?;
        if let Some(lease) = lease {
            fence(&mut tx, id, lease).await?;
        }
        sqlx::query(
            "UPDATE jobs SET status = ?2, stop_reason = ?3, message = ?4, finished_at = ?5, lease_expires = NULL, \
             results = COALESCE(?6, results) WHERE id = ?1",
        )
        .bind(id)
        .bind(status.as_str())
        .bind(stop_reason)
        .bind(message)
        .bind(now())
        .bind(results)
        .execute(&mut *tx)
        .await?;
        Ok(tx.commit().await?)
    }

    async fn request_cancel(&self, id: &str) -> StoreResult<Option<JobStatus>> {
        let Some(job) = self.job(id).await? else { return Ok(None) };
        if job.status == JobStatus::Accepted {
            self.finish(id, None, JobStatus::Dismissed, Some("cancelled"), Some("cancelled before it started"), None)
                .await?;
        }
        sqlx::query("UPDATE jobs SET cancel_requested = TRUE WHERE id = $1").bind(id).execute(&self.pool).await?;
        Ok(Some(job.status))
    }
});

#[cfg(test)]
mod tests {
    use super::*;
    use crate::service::store::StoreError;

    /// A batch is written under the lease it names and refused under any other; the
    /// fence reports a cancellation request, with and without history rows.
    #[tokio::test]
    async fn the_rows_of_a_batch_are_fenced_by_the_lease() {
        let dir = tempfile::tempdir().unwrap();
        let store = SqliteStore::open(&dir.path().join("jobs.db"), Blobs::local(dir.path()).unwrap()).await.unwrap();
        store.insert_rows("j1", "{}", &[], &Default::default()).await.unwrap();
        let claimed = store.claim_next("node", &ClaimPolicy::default()).await.unwrap().unwrap();
        let lease = claimed.lease;
        let row = |iteration| Progress {
            iteration,
            time: 0.1,
            tau: 0.1,
            energy: 2.0,
            vertices: 8,
            components: 1,
            surgery: None,
        };
        let rows: Vec<Progress> = (0..3).map(row).collect();
        assert!(!store.record_rows("j1", &lease, &rows, &[]).await.unwrap());
        assert_eq!(store.job("j1").await.unwrap().unwrap().progress.unwrap().iteration, 2);
        assert_eq!(store.history("j1").await.unwrap(), rows);
        let stale = Lease { owner: "node".into(), epoch: lease.epoch + 1 };
        assert!(matches!(store.record_rows("j1", &stale, &[row(3)], &[]).await, Err(StoreError::LeaseLost(_))));
        assert!(matches!(store.record_rows("j1", &stale, &[], &[]).await, Err(StoreError::LeaseLost(_))));
        assert_eq!(store.history("j1").await.unwrap(), rows, "a refused batch writes nothing");
        store.request_cancel("j1").await.unwrap();
        assert!(store.record_rows("j1", &lease, &[row(3)], &[]).await.unwrap());
        assert!(store.record_rows("j1", &lease, &[], &[]).await.unwrap());
    }
}
