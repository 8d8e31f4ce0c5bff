//! The SQLite store: the embedded default, for one node. One pool with a single
//! connection serializes writers (WAL, synchronous=NORMAL); the reads of requests
//! and event streams go through [`READERS`] read-only connections beside it;
//! leases work as on PostgreSQL, and jobs left running at a restart go back to the
//! queue.

use super::{
    migrations, now, results_of, status_of, Admission, Blobs, CheckpointKey, CheckpointRow, ClaimPolicy, Claimed,
    InputRow, JobRow, JobStatus, JobStore, KeyRow, Lease, StoreError, StoreResult, Which,
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

fn job_from_row(r: &sqlx::sqlite::SqliteRow) -> JobRow {
    let iteration: Option<i64> = r.get("iteration");
    JobRow {
        id: r.get("id"),
        seq: r.get("seq"),
        status: status_of(r.get::<&str, _>("status")),
        spec: r.get("spec"),
        created_at: r.get("created_at"),
        started_at: r.get("started_at"),
        finished_at: r.get("finished_at"),
        message: r.get("message"),
        stop_reason: r.get("stop_reason"),
        progress: iteration.map(|it| Progress {
            iteration: it as usize,
            time: r.get("time"),
            tau: r.get("tau"),
            energy: r.get("energy"),
            vertices: r.get::<i64, _>("vertices") as usize,
            components: r.get::<i64, _>("components") as usize,
        }),
        results: results_of(r.get("results")),
        owner: r.get("owner"),
    }
}

fn key_from_row(r: &sqlx::sqlite::SqliteRow) -> KeyRow {
    KeyRow {
        name: r.get("name"),
        hash: r.get("hash"),
        admin: r.get("admin"),
        max_active: r.get("max_active"),
        created_at: r.get("created_at"),
        revoked: r.get::<Option<String>, _>("revoked_at").is_some(),
    }
}

fn progress_from_row(r: &sqlx::sqlite::SqliteRow) -> Progress {
    Progress {
        iteration: r.get::<i64, _>("iteration") as usize,
        time: r.get("time"),
        tau: r.get("tau"),
        energy: r.get("energy"),
        vertices: r.get::<i64, _>("vertices") as usize,
        components: r.get::<i64, _>("components") as usize,
    }
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

#[async_trait::async_trait]
impl JobStore for SqliteStore {
    fn backend(&self) -> &'static str {
        "sqlite"
    }

    fn blobs(&self) -> &Blobs {
        &self.blobs
    }

    async fn insert_rows(
        &self,
        id: &str,
        spec: &str,
        heads: &[(String, Vec<u8>)],
        admit: &Admission,
    ) -> StoreResult<JobRow> {
        // the one writer's transaction: the counts cannot change before the insert
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        if let (Some(owner), Some(max)) = (&admit.owner, admit.max_active) {
            let active: i64 =
                sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE owner = ?1 AND status IN ('accepted', 'running')")
                    .bind(owner)
                    .fetch_one(&mut *tx)
                    .await?;
            if active >= max {
                return Err(StoreError::ActiveQuota(max));
            }
        }
        if let Some(max) = admit.max_queued {
            let queued: i64 =
                sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE status = 'accepted'").fetch_one(&mut *tx).await?;
            if queued >= max {
                return Err(StoreError::QueueFull(max));
            }
        }
        sqlx::query(
            "INSERT INTO jobs (id, seq, status, spec, created_at, owner) \
             VALUES (?1, (SELECT COALESCE(MAX(seq), 0) + 1 FROM jobs), 'accepted', ?2, ?3, ?4)",
        )
        .bind(id)
        .bind(spec)
        .bind(now())
        .bind(&admit.owner)
        .execute(&mut *tx)
        .await?;
        for (name, head) in heads {
            sqlx::query("INSERT INTO inputs (job_id, name, data, in_blob, head) VALUES (?1, ?2, x'', 1, ?3)")
                .bind(id)
                .bind(name)
                .bind(head.as_slice())
                .execute(&mut *tx)
                .await?;
        }
        tx.commit().await?;
        Ok(self.job(id).await?.expect("just inserted"))
    }

    async fn input_magics(&self, id: &str) -> StoreResult<Vec<Vec<u8>>> {
        let rows = sqlx::query("SELECT COALESCE(head, substr(data, 1, 8)) AS head FROM inputs WHERE job_id = ?1")
            .bind(id)
            .fetch_all(&self.reader)
            .await?;
        Ok(rows.iter().map(|r| r.get::<Vec<u8>, _>("head")).collect())
    }

    async fn input_rows(&self, id: &str) -> StoreResult<Vec<InputRow>> {
        let rows = sqlx::query("SELECT name, in_blob, data FROM inputs WHERE job_id = ?1")
            .bind(id)
            .fetch_all(&self.reader)
            .await?;
        Ok(rows
            .iter()
            .map(|r| InputRow { name: r.get("name"), in_blob: r.get::<i64, _>("in_blob") != 0, data: r.get("data") })
            .collect())
    }

    async fn job(&self, id: &str) -> StoreResult<Option<JobRow>> {
        let r = sqlx::query("SELECT * FROM jobs WHERE id = ?1").bind(id).fetch_optional(&self.reader).await?;
        Ok(r.as_ref().map(job_from_row))
    }

    async fn list(
        &self,
        status: Option<JobStatus>,
        before: Option<i64>,
        limit: i64,
        owner: Option<&str>,
    ) -> StoreResult<Vec<JobRow>> {
        let status = status.map(JobStatus::as_str);
        let rows = sqlx::query(
            "SELECT * FROM jobs WHERE (?1 IS NULL OR status = ?1) AND (?2 IS NULL OR seq < ?2) \
             AND (?4 IS NULL OR owner = ?4) ORDER BY seq DESC LIMIT ?3",
        )
        .bind(status)
        .bind(before)
        .bind(limit)
        .bind(owner)
        .fetch_all(&self.reader)
        .await?;
        Ok(rows.iter().map(job_from_row).collect())
    }

    async fn ended_before(&self, before: &str, limit: i64) -> StoreResult<Vec<String>> {
        let ids = sqlx::query_scalar(
            "SELECT id FROM jobs WHERE status IN ('successful', 'failed', 'dismissed') AND finished_at < ?1 \
             ORDER BY finished_at LIMIT ?2",
        )
        .bind(before)
        .bind(limit)
        .fetch_all(&self.reader)
        .await?;
        Ok(ids)
    }

    async fn reclaim(&self) -> StoreResult<()> {
        sqlx::query("PRAGMA incremental_vacuum").execute(&self.pool).await?;
        sqlx::query("PRAGMA wal_checkpoint(TRUNCATE)").execute(&self.pool).await?;
        Ok(())
    }

    async fn counts_by_status(&self) -> StoreResult<Vec<(String, i64)>> {
        let rows =
            sqlx::query("SELECT status, COUNT(*) AS n FROM jobs GROUP BY status").fetch_all(&self.reader).await?;
        Ok(rows.iter().map(|r| (r.get("status"), r.get("n"))).collect())
    }

    async fn insert_key(&self, key: &KeyRow) -> StoreResult<bool> {
        let done = sqlx::query(
            "INSERT INTO keys (name, hash, admin, max_active, created_at) VALUES (?1, ?2, ?3, ?4, ?5) \
             ON CONFLICT DO NOTHING",
        )
        .bind(&key.name)
        .bind(&key.hash)
        .bind(key.admin)
        .bind(key.max_active)
        .bind(&key.created_at)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    async fn keys(&self) -> StoreResult<Vec<KeyRow>> {
        let rows = sqlx::query("SELECT * FROM keys ORDER BY name").fetch_all(&self.reader).await?;
        Ok(rows.iter().map(key_from_row).collect())
    }

    async fn revoke_key(&self, name: &str) -> StoreResult<bool> {
        let done = sqlx::query("UPDATE keys SET revoked_at = ?2 WHERE name = ?1 AND revoked_at IS NULL")
            .bind(name)
            .bind(now())
            .execute(&self.pool)
            .await?;
        Ok(done.rows_affected() == 1)
    }

    async fn key_by_hash(&self, hash: &str) -> StoreResult<Option<KeyRow>> {
        let row = sqlx::query("SELECT * FROM keys WHERE hash = ?1 AND revoked_at IS NULL")
            .bind(hash)
            .fetch_optional(&self.reader)
            .await?;
        Ok(row.as_ref().map(key_from_row))
    }

    async fn has_keys(&self) -> StoreResult<bool> {
        let n: i64 =
            sqlx::query_scalar("SELECT COUNT(*) FROM keys WHERE revoked_at IS NULL").fetch_one(&self.reader).await?;
        Ok(n > 0)
    }

    /// The write lock taken and given back.
    async fn writable(&self) -> StoreResult<()> {
        let tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        Ok(tx.rollback().await?)
    }

    async fn requeue_running(&self) -> StoreResult<u64> {
        // the epoch moves on: a worker of the previous process can no longer write
        leases::requeue_running(&self.pool).await
    }

    async fn claim_next(&self, owner: &str, policy: &ClaimPolicy) -> StoreResult<Option<Claimed>> {
        leases::claim_next(&self.pool, owner, policy).await
    }

    async fn renew(&self, id: &str, lease: &Lease, policy: &ClaimPolicy) -> StoreResult<bool> {
        leases::renew(&self.pool, id, lease, policy).await
    }

    async fn release(&self, id: &str, lease: &Lease) -> StoreResult<()> {
        leases::release(&self.pool, id, lease).await
    }

    async fn abandon(&self, id: &str, lease: &Lease, why: &str) -> StoreResult<()> {
        leases::abandon(&self.pool, id, lease, why).await
    }

    async fn checkpoint_index(&self, id: &str, after: i64) -> StoreResult<Vec<(i64, f64)>> {
        let rows = sqlx::query("SELECT iteration, time FROM checkpoints WHERE job_id = ?1 AND iteration > ?2 ORDER BY iteration LIMIT 4096")
            .bind(id)
            .bind(after)
            .fetch_all(&self.reader)
            .await?;
        Ok(rows.iter().map(|r| (r.get::<i64, _>("iteration"), r.get::<f64, _>("time"))).collect())
    }

    async fn checkpoint_rows(&self, id: &str, which: Which) -> StoreResult<Vec<CheckpointRow>> {
        let (sql, iteration) = match which {
            Which::Last => (
                "SELECT iteration, blob, data FROM checkpoints WHERE job_id = ?1 AND ?2 = ?2 \
                 ORDER BY iteration DESC LIMIT 1",
                0,
            ),
            Which::At(n) => ("SELECT iteration, blob, data FROM checkpoints WHERE job_id = ?1 AND iteration = ?2", n),
            Which::After(n) => (
                "SELECT iteration, blob, data FROM checkpoints WHERE job_id = ?1 AND iteration > ?2 \
                 ORDER BY iteration LIMIT 4096",
                n,
            ),
        };
        let rows = sqlx::query(sql).bind(id).bind(iteration).fetch_all(&self.reader).await?;
        Ok(rows
            .iter()
            .map(|r| CheckpointRow { iteration: r.get("iteration"), blob: r.get("blob"), data: r.get("data") })
            .collect())
    }

    async fn record_rows(
        &self,
        id: &str,
        lease: &Lease,
        rows: &[Progress],
        checkpoints: &[CheckpointKey],
    ) -> StoreResult<bool> {
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let cancel = match rows.last() {
            Some(p) => fenced_progress(&mut tx, id, lease, p).await?,
            None => fence(&mut tx, id, lease).await?,
        };
        for chunk in rows.chunks(HISTORY_ROWS_PER_STATEMENT) {
            sqlx::QueryBuilder::<Sqlite>::new("INSERT OR REPLACE INTO history ")
                .push_values(chunk, |mut row, p| {
                    row.push_bind(id)
                        .push_bind(p.iteration as i64)
                        .push_bind(p.time)
                        .push_bind(p.tau)
                        .push_bind(p.energy)
                        .push_bind(p.vertices as i64)
                        .push_bind(p.components as i64);
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

    async fn truncate_history(&self, id: &str, lease: &Lease, after: usize) -> StoreResult<()> {
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        fence(&mut tx, id, lease).await?;
        sqlx::query("DELETE FROM history WHERE job_id = ?1 AND iteration > ?2")
            .bind(id)
            .bind(after as i64)
            .execute(&mut *tx)
            .await?;
        Ok(tx.commit().await?)
    }

    async fn set_results(&self, id: &str, lease: Option<&Lease>, index: &str) -> StoreResult<bool> {
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let sql = match lease {
            Some(lease) => {
                fence(&mut tx, id, lease).await?;
                "UPDATE jobs SET results = ?2 WHERE id = ?1"
            }
            None => "UPDATE jobs SET results = ?2 WHERE id = ?1 AND results IS NULL",
        };
        let done = sqlx::query(sql).bind(id).bind(index).execute(&mut *tx).await?;
        tx.commit().await?;
        Ok(done.rows_affected() == 1)
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
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
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

    async fn cancel_requested(&self, id: &str) -> StoreResult<bool> {
        let r = sqlx::query("SELECT cancel_requested FROM jobs WHERE id = ?1")
            .bind(id)
            .fetch_optional(&self.reader)
            .await?;
        Ok(r.map(|r| r.get::<i64, _>("cancel_requested") != 0).unwrap_or(true))
    }

    async fn request_cancel(&self, id: &str) -> StoreResult<Option<JobStatus>> {
        let Some(job) = self.job(id).await? else { return Ok(None) };
        if job.status == JobStatus::Accepted {
            self.finish(id, None, JobStatus::Dismissed, Some("cancelled"), Some("cancelled before it started"), None)
                .await?;
        }
        sqlx::query("UPDATE jobs SET cancel_requested = 1 WHERE id = ?1").bind(id).execute(&self.pool).await?;
        Ok(Some(job.status))
    }

    async fn history_count(&self, id: &str) -> StoreResult<u64> {
        let n: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM history WHERE job_id = ?1")
            .bind(id)
            .fetch_one(&self.reader)
            .await?;
        Ok(n as u64)
    }

    async fn delete_rows(&self, id: &str) -> StoreResult<()> {
        sqlx::query("DELETE FROM jobs WHERE id = ?1").bind(id).execute(&self.pool).await?;
        Ok(())
    }

    async fn history_from(&self, id: &str, from: usize, limit: usize) -> StoreResult<Vec<Progress>> {
        let rows =
            sqlx::query("SELECT * FROM history WHERE job_id = ?1 AND iteration >= ?2 ORDER BY iteration LIMIT ?3")
                .bind(id)
                .bind(from as i64)
                .bind(limit.min(i64::MAX as usize) as i64)
                .fetch_all(&self.reader)
                .await?;
        Ok(rows.iter().map(progress_from_row).collect())
    }
}

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
        let row = |iteration| Progress { iteration, time: 0.1, tau: 0.1, energy: 2.0, vertices: 8, components: 1 };
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
