//! The PostgreSQL store: any number of nodes on one database. Jobs are claimed
//! with `FOR UPDATE SKIP LOCKED` in short transactions, leases expire on the
//! database's clock, and every batch of history rows sends one notification on
//! the channel [`CHANNEL`] (the job's id: a wake-up hint for event streams on
//! every node, [`PgStore::watch`]).

mod listen;

use super::{
    migrations, now, results_of, status_of, Admission, Blobs, CheckpointKey, CheckpointRow, ClaimPolicy, Claimed,
    InputRow, JobRow, JobStatus, JobStore, KeyRow, Lease, StoreError, StoreResult, Which,
};
use crate::flow::Progress;
use sqlx::postgres::{PgConnectOptions, PgPool, PgPoolOptions, PgRow};
use sqlx::Row;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::broadcast;

/// The notification channel of history batches and outcomes.
pub const CHANNEL: &str = "shapeflow_jobs";

/// The database clock in ms since the Unix epoch, as SQL.
macro_rules! clock_ms {
    () => {
        "(extract(epoch from clock_timestamp()) * 1000)::bigint"
    };
}

mod leases;
use leases::fence;

#[derive(Clone)]
pub struct PgStore {
    pool: PgPool,
    blobs: Blobs,
}

fn key_from_row(r: &PgRow) -> KeyRow {
    KeyRow {
        name: r.get("name"),
        hash: r.get("hash"),
        admin: r.get("admin"),
        max_active: r.get("max_active"),
        created_at: r.get("created_at"),
        revoked: r.get::<Option<String>, _>("revoked_at").is_some(),
    }
}

fn job_from_row(r: &PgRow) -> JobRow {
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

impl PgStore {
    /// Connect (a small pool; connections are re-established after a database
    /// restart) and migrate. A transaction left idle for 5 s (its node paused or cut
    /// off in the middle of one) is aborted by the server, so that the job rows it
    /// locked can be claimed again.
    pub async fn open(url: &str, blobs: Blobs) -> StoreResult<Self> {
        let options = PgConnectOptions::from_str(url)?.options([("idle_in_transaction_session_timeout", "5s")]);
        let pool = PgPoolOptions::new()
            .max_connections(8)
            .acquire_timeout(Duration::from_secs(10))
            .test_before_acquire(true)
            // a connection left in a transaction (a failed COMMIT) is closed
            .after_release(|conn, _| Box::pin(async move { Ok(!sqlx::Connection::is_in_transaction(conn)) }))
            .connect_with(options)
            .await?;
        migrations::migrator(migrations::POSTGRES).run(&pool).await?;
        Ok(PgStore { pool, blobs })
    }
}

#[async_trait::async_trait]
impl JobStore for PgStore {
    fn backend(&self) -> &'static str {
        "postgres"
    }

    fn blobs(&self) -> &Blobs {
        &self.blobs
    }

    /// Forward the notifications of [`CHANNEL`] to `events` (the job's id), from a
    /// task that listens on its own connection; after a lost connection (which may
    /// have dropped notifications) it sends `"*"`, on which every stream re-reads.
    fn watch(&self, events: broadcast::Sender<Arc<str>>) {
        listen::forward(self.pool.clone(), CHANNEL, events);
    }

    fn announces(&self) -> bool {
        true
    }

    async fn insert_rows(
        &self,
        id: &str,
        spec: &str,
        heads: &[(String, Vec<u8>)],
        admit: &Admission,
    ) -> StoreResult<JobRow> {
        let mut tx = self.pool.begin().await?;
        if admit.max_active.is_some() || admit.max_queued.is_some() {
            // one admission at a time on every node: the counts cannot change before the insert
            sqlx::query("SELECT pg_advisory_xact_lock(hashtext('shapeflow admission'))").execute(&mut *tx).await?;
        }
        if let (Some(owner), Some(max)) = (&admit.owner, admit.max_active) {
            let active: i64 =
                sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE owner = $1 AND status IN ('accepted', 'running')")
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
        let r = sqlx::query(
            "INSERT INTO jobs (id, status, spec, created_at, owner) VALUES ($1, 'accepted', $2, $3, $4) RETURNING *",
        )
        .bind(id)
        .bind(spec)
        .bind(now())
        .bind(&admit.owner)
        .fetch_one(&mut *tx)
        .await?;
        for (name, head) in heads {
            sqlx::query("INSERT INTO inputs (job_id, name, data, in_blob, head) VALUES ($1, $2, '', TRUE, $3)")
                .bind(id)
                .bind(name)
                .bind(head.as_slice())
                .execute(&mut *tx)
                .await?;
        }
        sqlx::query("SELECT pg_notify($1, $2)").bind(CHANNEL).bind("queue").execute(&mut *tx).await?;
        tx.commit().await?;
        Ok(job_from_row(&r))
    }

    async fn input_magics(&self, id: &str) -> StoreResult<Vec<Vec<u8>>> {
        let rows =
            sqlx::query("SELECT COALESCE(head, substring(data from 1 for 8)) AS head FROM inputs WHERE job_id = $1")
                .bind(id)
                .fetch_all(&self.pool)
                .await?;
        Ok(rows.iter().map(|r| r.get::<Vec<u8>, _>("head")).collect())
    }

    async fn input_rows(&self, id: &str) -> StoreResult<Vec<InputRow>> {
        let rows = sqlx::query("SELECT name, in_blob, data FROM inputs WHERE job_id = $1")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        Ok(rows
            .iter()
            .map(|r| InputRow { name: r.get("name"), in_blob: r.get("in_blob"), data: r.get("data") })
            .collect())
    }

    async fn job(&self, id: &str) -> StoreResult<Option<JobRow>> {
        let r = sqlx::query("SELECT * FROM jobs WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
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
            "SELECT * FROM jobs WHERE ($1::text IS NULL OR status = $1) AND ($2::bigint IS NULL OR seq < $2) \
             AND ($4::text IS NULL OR owner = $4) ORDER BY seq DESC LIMIT $3",
        )
        .bind(status)
        .bind(before)
        .bind(limit)
        .bind(owner)
        .fetch_all(&self.pool)
        .await?;
        Ok(rows.iter().map(job_from_row).collect())
    }

    async fn ended_before(&self, before: &str, limit: i64) -> StoreResult<Vec<String>> {
        let ids = sqlx::query_scalar(
            "SELECT id FROM jobs WHERE status IN ('successful', 'failed', 'dismissed') AND finished_at < $1 \
             ORDER BY finished_at LIMIT $2",
        )
        .bind(before)
        .bind(limit)
        .fetch_all(&self.pool)
        .await?;
        Ok(ids)
    }

    async fn counts_by_status(&self) -> StoreResult<Vec<(String, i64)>> {
        let rows = sqlx::query("SELECT status, COUNT(*) AS n FROM jobs GROUP BY status").fetch_all(&self.pool).await?;
        Ok(rows.iter().map(|r| (r.get("status"), r.get("n"))).collect())
    }

    async fn insert_key(&self, key: &KeyRow) -> StoreResult<bool> {
        let done = sqlx::query(
            "INSERT INTO keys (name, hash, admin, max_active, created_at) VALUES ($1, $2, $3, $4, $5) \
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
        let rows = sqlx::query("SELECT * FROM keys ORDER BY name").fetch_all(&self.pool).await?;
        Ok(rows.iter().map(key_from_row).collect())
    }

    async fn revoke_key(&self, name: &str) -> StoreResult<bool> {
        let done = sqlx::query("UPDATE keys SET revoked_at = $2 WHERE name = $1 AND revoked_at IS NULL")
            .bind(name)
            .bind(now())
            .execute(&self.pool)
            .await?;
        Ok(done.rows_affected() == 1)
    }

    async fn key_by_hash(&self, hash: &str) -> StoreResult<Option<KeyRow>> {
        let row = sqlx::query("SELECT * FROM keys WHERE hash = $1 AND revoked_at IS NULL")
            .bind(hash)
            .fetch_optional(&self.pool)
            .await?;
        Ok(row.as_ref().map(key_from_row))
    }

    async fn has_keys(&self) -> StoreResult<bool> {
        let n: i64 =
            sqlx::query_scalar("SELECT COUNT(*) FROM keys WHERE revoked_at IS NULL").fetch_one(&self.pool).await?;
        Ok(n > 0)
    }

    /// Nodes share the database: a running job belongs to its lease holder until
    /// the lease expires.
    /// A primary (not a read-only standby) that answers.
    async fn writable(&self) -> StoreResult<()> {
        let standby: bool = sqlx::query_scalar("SELECT pg_is_in_recovery()").fetch_one(&self.pool).await?;
        match standby {
            false => Ok(()),
            true => Err(StoreError::Db(sqlx::Error::Protocol("the database is a read-only standby".into()))),
        }
    }

    async fn requeue_running(&self) -> StoreResult<u64> {
        Ok(0)
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
        let rows = sqlx::query("SELECT iteration, time FROM checkpoints WHERE job_id = $1 AND iteration > $2 ORDER BY iteration LIMIT 4096")
            .bind(id)
            .bind(after)
            .fetch_all(&self.pool)
            .await?;
        Ok(rows.iter().map(|r| (r.get::<i64, _>("iteration"), r.get::<f64, _>("time"))).collect())
    }

    async fn checkpoint_rows(&self, id: &str, which: Which) -> StoreResult<Vec<CheckpointRow>> {
        let (sql, iteration) = match which {
            Which::Last => (
                "SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 AND $2::bigint = $2 \
                 ORDER BY iteration DESC LIMIT 1",
                0,
            ),
            Which::At(n) => ("SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 AND iteration = $2", n),
            Which::After(n) => (
                "SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 AND iteration > $2 \
                 ORDER BY iteration LIMIT 4096",
                n,
            ),
        };
        let rows = sqlx::query(sql).bind(id).bind(iteration).fetch_all(&self.pool).await?;
        Ok(rows
            .iter()
            .map(|r| CheckpointRow { iteration: r.get("iteration"), blob: r.get("blob"), data: r.get("data") })
            .collect())
    }

    /// The fence, the job's progress, the batch's history rows, its checkpoints'
    /// rows and the notification in one statement: one round trip, atomic on its
    /// own (each part runs only where the fence's update found the lease).
    async fn record_rows(
        &self,
        id: &str,
        lease: &Lease,
        rows: &[Progress],
        checkpoints: &[CheckpointKey],
    ) -> StoreResult<bool> {
        let col = |f: fn(&Progress) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
        let int = |f: fn(&Progress) -> usize| rows.iter().map(|p| f(p) as i64).collect::<Vec<i64>>();
        let last = rows.last();
        let held = sqlx::query(
            "WITH fence AS ( \
                 UPDATE jobs SET iteration = COALESCE($3, iteration), time = COALESCE($4, time), \
                 tau = COALESCE($5, tau), energy = COALESCE($6, energy), vertices = COALESCE($7, vertices), \
                 components = COALESCE($8, components) \
                 WHERE id = $1 AND lease_epoch = $2 AND status = 'running' RETURNING cancel_requested), \
             rows AS ( \
                 INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components) \
                 SELECT $1, u.* FROM UNNEST($9::bigint[], $10::float8[], $11::float8[], $12::float8[], \
                 $13::bigint[], $14::bigint[]) AS u WHERE EXISTS (SELECT 1 FROM fence) \
                 ON CONFLICT (job_id, iteration) DO UPDATE SET time = EXCLUDED.time, tau = EXCLUDED.tau, \
                 energy = EXCLUDED.energy, vertices = EXCLUDED.vertices, components = EXCLUDED.components), \
             frames AS ( \
                 INSERT INTO checkpoints (job_id, iteration, time, data, blob) \
                 SELECT $1, c.iteration, c.time, '', c.blob FROM UNNEST($15::bigint[], $16::float8[], $17::text[]) \
                 AS c (iteration, time, blob) WHERE EXISTS (SELECT 1 FROM fence) \
                 ON CONFLICT (job_id, iteration) DO UPDATE SET time = EXCLUDED.time, data = '', blob = EXCLUDED.blob) \
             SELECT cancel_requested, pg_notify($18, $1) FROM fence",
        )
        .bind(id)
        .bind(lease.epoch)
        .bind(last.map(|p| p.iteration as i64))
        .bind(last.map(|p| p.time))
        .bind(last.map(|p| p.tau))
        .bind(last.map(|p| p.energy))
        .bind(last.map(|p| p.vertices as i64))
        .bind(last.map(|p| p.components as i64))
        .bind(int(|p| p.iteration))
        .bind(col(|p| p.time))
        .bind(col(|p| p.tau))
        .bind(col(|p| p.energy))
        .bind(int(|p| p.vertices))
        .bind(int(|p| p.components))
        .bind(checkpoints.iter().map(|c| c.iteration).collect::<Vec<i64>>())
        .bind(checkpoints.iter().map(|c| c.time).collect::<Vec<f64>>())
        .bind(checkpoints.iter().map(|c| c.key.as_str()).collect::<Vec<&str>>())
        .bind(CHANNEL)
        .fetch_optional(&self.pool)
        .await?;
        held.map(|r| r.get::<bool, _>(0)).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
    }

    async fn truncate_history(&self, id: &str, lease: &Lease, after: usize) -> StoreResult<()> {
        let mut tx = self.pool.begin().await?;
        fence(&mut tx, id, lease).await?;
        sqlx::query("DELETE FROM history WHERE job_id = $1 AND iteration > $2")
            .bind(id)
            .bind(after as i64)
            .execute(&mut *tx)
            .await?;
        Ok(tx.commit().await?)
    }

    async fn set_results(&self, id: &str, lease: Option<&Lease>, index: &str) -> StoreResult<bool> {
        let mut tx = self.pool.begin().await?;
        let sql = match lease {
            Some(lease) => {
                fence(&mut tx, id, lease).await?;
                "UPDATE jobs SET results = $2 WHERE id = $1"
            }
            None => "UPDATE jobs SET results = $2 WHERE id = $1 AND results IS NULL",
        };
        let done = sqlx::query(sql).bind(id).bind(index).execute(&mut *tx).await?;
        tx.commit().await?;
        Ok(done.rows_affected() == 1)
    }

    /// One statement: the fence (the lease's epoch in the update's condition), the
    /// outcome and the notification.
    async fn finish(
        &self,
        id: &str,
        lease: Option<&Lease>,
        status: JobStatus,
        stop_reason: Option<&str>,
        message: Option<&str>,
        results: Option<&str>,
    ) -> StoreResult<()> {
        let ended = sqlx::query(
            "UPDATE jobs SET status = $2, stop_reason = $3, message = $4, finished_at = $5, lease_expires = NULL, \
             results = COALESCE($6, results) \
             WHERE id = $1 AND ($7::bigint IS NULL OR (lease_epoch = $7 AND status = 'running')) \
             RETURNING pg_notify($8, $1)",
        )
        .bind(id)
        .bind(status.as_str())
        .bind(stop_reason)
        .bind(message)
        .bind(now())
        .bind(results)
        .bind(lease.map(|l| l.epoch))
        .bind(CHANNEL)
        .fetch_optional(&self.pool)
        .await?;
        match (ended, lease) {
            (None, Some(_)) => Err(StoreError::LeaseLost(id.to_string())),
            _ => Ok(()),
        }
    }

    async fn cancel_requested(&self, id: &str) -> StoreResult<bool> {
        let r =
            sqlx::query("SELECT cancel_requested FROM jobs WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
        Ok(r.map(|r| r.get::<bool, _>("cancel_requested")).unwrap_or(true))
    }

    async fn request_cancel(&self, id: &str) -> StoreResult<Option<JobStatus>> {
        let mut tx = self.pool.begin().await?;
        let Some(r) =
            sqlx::query("SELECT status FROM jobs WHERE id = $1 FOR UPDATE").bind(id).fetch_optional(&mut *tx).await?
        else {
            return Ok(None);
        };
        let status = status_of(r.get::<&str, _>("status"));
        if status == JobStatus::Accepted {
            sqlx::query(
                "UPDATE jobs SET status = 'dismissed', stop_reason = 'cancelled', \
                 message = 'cancelled before it started', finished_at = $2 WHERE id = $1",
            )
            .bind(id)
            .bind(now())
            .execute(&mut *tx)
            .await?;
        }
        sqlx::query("UPDATE jobs SET cancel_requested = TRUE WHERE id = $1").bind(id).execute(&mut *tx).await?;
        sqlx::query("SELECT pg_notify($1, $2)").bind(CHANNEL).bind(id).execute(&mut *tx).await?;
        tx.commit().await?;
        Ok(Some(status))
    }

    async fn history_count(&self, id: &str) -> StoreResult<u64> {
        let n: i64 =
            sqlx::query_scalar("SELECT COUNT(*) FROM history WHERE job_id = $1").bind(id).fetch_one(&self.pool).await?;
        Ok(n as u64)
    }

    async fn delete_rows(&self, id: &str) -> StoreResult<()> {
        sqlx::query("DELETE FROM jobs WHERE id = $1").bind(id).execute(&self.pool).await?;
        Ok(())
    }

    async fn history_from(&self, id: &str, from: usize, limit: usize) -> StoreResult<Vec<Progress>> {
        let rows =
            sqlx::query("SELECT * FROM history WHERE job_id = $1 AND iteration >= $2 ORDER BY iteration LIMIT $3")
                .bind(id)
                .bind(from as i64)
                .bind(limit.min(i64::MAX as usize) as i64)
                .fetch_all(&self.pool)
                .await?;
        Ok(rows
            .iter()
            .map(|r| Progress {
                iteration: r.get::<i64, _>("iteration") as usize,
                time: r.get("time"),
                tau: r.get("tau"),
                energy: r.get("energy"),
                vertices: r.get::<i64, _>("vertices") as usize,
                components: r.get::<i64, _>("components") as usize,
            })
            .collect())
    }
}
