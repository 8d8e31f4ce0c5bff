//! The PostgreSQL store: any number of nodes on one database. Jobs are claimed
//! with `FOR UPDATE SKIP LOCKED` in short transactions, leases expire on the
//! database's clock, and every batch of history rows sends one notification on
//! the channel [`CHANNEL`] (the job's id: a wake-up hint for event streams on
//! every node, [`PgStore::watch`]).

mod listen;

use super::{
    migrations, now, results_of, status_of, surgery_json, Admission, Blobs, CheckpointKey, CheckpointRow, ClaimPolicy,
    Claimed, InputRow, JobRow, JobStatus, JobStore, KeyRow, Lease, StoreError, StoreResult, Which,
};
use crate::flow::Progress;
use sqlx::postgres::{PgConnectOptions, PgPool, PgPoolOptions, PgRow};
use sqlx::{Postgres, Row};
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

const BEGIN: &str = "BEGIN";
/// One admission at a time on every node: the counts cannot change before the insert.
const ADMISSION_LOCK: Option<&str> = Some("SELECT pg_advisory_xact_lock(hashtext('shapeflow admission'))");
const INSERT_JOB: &str = "INSERT INTO jobs (id, status, spec, created_at, owner) VALUES ($1, 'accepted', $2, $3, $4)";

/// Tell every node's event streams (and idle workers: `"queue"`) about `what`.
async fn notify(tx: &mut sqlx::Transaction<'_, Postgres>, what: &str) -> StoreResult<()> {
    sqlx::query("SELECT pg_notify($1, $2)").bind(CHANNEL).bind(what).execute(&mut **tx).await?;
    Ok(())
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

job_store!(PgStore, PgRow, read: pool, write: pool, {
    fn backend(&self) -> &'static str {
        "postgres"
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

    async fn release(&self, id: &str, lease: &Lease) -> StoreResult<()> {
        leases::release(&self.pool, id, lease).await
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
                 INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components, surgery) \
                 SELECT $1, u.* FROM UNNEST($9::bigint[], $10::float8[], $11::float8[], $12::float8[], \
                 $13::bigint[], $14::bigint[], $19::text[]) AS u WHERE EXISTS (SELECT 1 FROM fence) \
                 ON CONFLICT (job_id, iteration) DO UPDATE SET time = EXCLUDED.time, tau = EXCLUDED.tau, \
                 energy = EXCLUDED.energy, vertices = EXCLUDED.vertices, components = EXCLUDED.components, \
                 surgery = EXCLUDED.surgery), \
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
        .bind(rows.iter().map(surgery_json).collect::<Vec<Option<String>>>())
        .fetch_optional(&self.pool)
        .await?;
        held.map(|r| r.get::<bool, _>(0)).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
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
});
