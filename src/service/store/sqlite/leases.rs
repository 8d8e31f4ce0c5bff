//! Leases on SQLite: claims in `BEGIN IMMEDIATE` transactions (one writer at a
//! time), renewals and the fence, on the database's clock, as on PostgreSQL.

use super::job_from_row;
use crate::flow::Progress;
use crate::service::store::{crash_message, now, ClaimPolicy, Claimed, Lease, StoreError, StoreResult, ABANDONED};
use sqlx::sqlite::SqlitePool;
use sqlx::{Row, Sqlite, Transaction};

/// Within `tx`: refuse unless `lease` is still the job's; whether cancellation
/// was requested.
pub(super) async fn fence(tx: &mut Transaction<'_, Sqlite>, id: &str, lease: &Lease) -> StoreResult<bool> {
    let held =
        sqlx::query("SELECT cancel_requested FROM jobs WHERE id = ?1 AND lease_epoch = ?2 AND status = 'running'")
            .bind(id)
            .bind(lease.epoch)
            .fetch_optional(&mut **tx)
            .await?;
    held.map(|r| r.get::<i64, _>(0) != 0).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
}

/// Within `tx`: the fence and the job's progress (its last history row `p`) in
/// one statement, a round trip less than [`fence`] and an update; whether
/// cancellation was requested.
pub(super) async fn fenced_progress(
    tx: &mut Transaction<'_, Sqlite>,
    id: &str,
    lease: &Lease,
    p: &Progress,
) -> StoreResult<bool> {
    let held = sqlx::query(
        "UPDATE jobs SET (iteration, time, tau, energy, vertices, components) = (?3, ?4, ?5, ?6, ?7, ?8) \
         WHERE id = ?1 AND lease_epoch = ?2 AND status = 'running' RETURNING cancel_requested",
    )
    .bind(id)
    .bind(lease.epoch)
    .bind(p.iteration as i64)
    .bind(p.time)
    .bind(p.tau)
    .bind(p.energy)
    .bind(p.vertices as i64)
    .bind(p.components as i64)
    .fetch_optional(&mut **tx)
    .await?;
    held.map(|r| r.get::<i64, _>(0) != 0).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
}

/// Claim the oldest accepted job, or a running one given up (failing it instead
/// once it has been taken over `policy.max_takeovers` times).
pub(super) async fn claim_next(pool: &SqlitePool, owner: &str, policy: &ClaimPolicy) -> StoreResult<Option<Claimed>> {
    let lease_ms = policy.lease.as_millis() as i64;
    loop {
        let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
        // one node: a running job is taken over only once given up (its attempt
        // abandoned, or left by a process that stopped: lease_expires = 0), never
        // for a lease that ran out while this process lived (its renewals waited
        // for a write lock another process held: the job is alive)
        let pick = sqlx::query(
            "SELECT id, status, takeovers, message FROM jobs WHERE status IN ('accepted', 'running') \
             AND (status = 'accepted' OR lease_expires = 0) ORDER BY seq LIMIT 1",
        )
        .fetch_optional(&mut *tx)
        .await?;
        let Some(pick) = pick else { return Ok(None) };
        let id: String = pick.get("id");
        let takeover = pick.get::<&str, _>("status") == "running";
        let takeovers = pick.get::<i64, _>("takeovers") + takeover as i64;
        if takeover && takeovers > policy.max_takeovers {
            sqlx::query(
                "UPDATE jobs SET status = 'failed', message = ?2, finished_at = ?3, takeovers = ?4, \
                 lease_epoch = lease_epoch + 1 WHERE id = ?1",
            )
            .bind(&id)
            .bind(crash_message(takeovers - 1, pick.get::<Option<String>, _>("message").as_deref()))
            .bind(now())
            .bind(takeovers)
            .execute(&mut *tx)
            .await?;
            tx.commit().await?;
            continue;
        }
        let r = sqlx::query(concat!(
            "UPDATE jobs SET status = 'running', started_at = COALESCE(started_at, ?2), lease_owner = ?3, \
             lease_epoch = lease_epoch + 1, lease_expires = ",
            clock_ms!(),
            " + ?4, takeovers = ?5 WHERE id = ?1 RETURNING *"
        ))
        .bind(&id)
        .bind(now())
        .bind(owner)
        .bind(lease_ms)
        .bind(takeovers)
        .fetch_one(&mut *tx)
        .await?;
        tx.commit().await?;
        let lease = Lease { owner: owner.to_string(), epoch: r.get("lease_epoch") };
        return Ok(Some(Claimed { job: job_from_row(&r), lease, takeover }));
    }
}

/// Give the job back to the queue (its node stops); fenced.
pub(super) async fn release(pool: &SqlitePool, id: &str, lease: &Lease) -> StoreResult<()> {
    let done = sqlx::query(
        "UPDATE jobs SET status = 'accepted', lease_expires = NULL, lease_epoch = lease_epoch + 1 \
         WHERE id = ?1 AND lease_epoch = ?2 AND status = 'running'",
    )
    .bind(id)
    .bind(lease.epoch)
    .execute(pool)
    .await?;
    (done.rows_affected() == 1).then_some(()).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
}

/// Jobs left running by a process that stopped without giving them back (a
/// crash, a kill): their leases expire now, so that their next claim counts an
/// attempt; a process stopped gracefully gave its jobs back ([`release`]).
pub(super) async fn requeue_running(pool: &SqlitePool) -> StoreResult<u64> {
    let why = format!("{ABANDONED}the service stopped while the job ran (a crash or a kill of its process)");
    Ok(sqlx::query(
        "UPDATE jobs SET lease_expires = 0, lease_epoch = lease_epoch + 1, message = ?1 WHERE status = 'running'",
    )
    .bind(why)
    .execute(pool)
    .await?
    .rows_affected())
}
