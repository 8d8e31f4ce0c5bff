//! Leases on PostgreSQL: claims with `FOR UPDATE SKIP LOCKED` in short
//! transactions, renewals and the fence, all on the database's clock.

use super::{job_from_row, CHANNEL};
use crate::service::store::{crash_message, now, ClaimPolicy, Claimed, Lease, StoreError, StoreResult};
use sqlx::postgres::PgPool;
use sqlx::{Postgres, Row, Transaction};

/// Within `tx`: lock the job's row and refuse unless `lease` is still its lease;
/// whether cancellation was requested.
pub(super) async fn fence(tx: &mut Transaction<'_, Postgres>, id: &str, lease: &Lease) -> StoreResult<bool> {
    let held = sqlx::query(
        "SELECT cancel_requested FROM jobs WHERE id = $1 AND lease_epoch = $2 AND status = 'running' FOR UPDATE",
    )
    .bind(id)
    .bind(lease.epoch)
    .fetch_optional(&mut **tx)
    .await?;
    held.map(|r| r.get::<bool, _>(0)).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
}

/// Claim the oldest accepted job, or a running one whose lease expired (failing
/// it instead once it has been taken over `policy.max_takeovers` times).
pub(super) async fn claim_next(pool: &PgPool, owner: &str, policy: &ClaimPolicy) -> StoreResult<Option<Claimed>> {
    let lease_ms = policy.lease.as_millis() as i64;
    loop {
        let mut tx = pool.begin().await?;
        let pick = sqlx::query(concat!(
            "SELECT id, status, takeovers, message FROM jobs WHERE status IN ('accepted', 'running') \
             AND (status = 'accepted' OR lease_expires < ",
            clock_ms!(),
            ") ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED"
        ))
        .fetch_optional(&mut *tx)
        .await?;
        let Some(pick) = pick else { return Ok(None) };
        let id: String = pick.get("id");
        let takeover = pick.get::<&str, _>("status") == "running";
        let takeovers = pick.get::<i32, _>("takeovers") as i64 + takeover as i64;
        if takeover && takeovers > policy.max_takeovers {
            sqlx::query(
                "UPDATE jobs SET status = 'failed', message = $2, finished_at = $3, takeovers = $4, \
                 lease_epoch = lease_epoch + 1, lease_expires = NULL WHERE id = $1",
            )
            .bind(&id)
            .bind(crash_message(takeovers - 1, pick.get::<Option<String>, _>("message").as_deref()))
            .bind(now())
            .bind(takeovers as i32)
            .execute(&mut *tx)
            .await?;
            sqlx::query("SELECT pg_notify($1, $2)").bind(CHANNEL).bind(&id).execute(&mut *tx).await?;
            tx.commit().await?;
            continue;
        }
        let r = sqlx::query(concat!(
            "UPDATE jobs SET status = 'running', started_at = COALESCE(started_at, $2), lease_owner = $3, \
             lease_epoch = lease_epoch + 1, lease_expires = ",
            clock_ms!(),
            " + $4, takeovers = $5 WHERE id = $1 RETURNING *"
        ))
        .bind(&id)
        .bind(now())
        .bind(owner)
        .bind(lease_ms)
        .bind(takeovers as i32)
        .fetch_one(&mut *tx)
        .await?;
        tx.commit().await?;
        let lease = Lease { owner: owner.to_string(), epoch: r.get("lease_epoch") };
        return Ok(Some(Claimed { job: job_from_row(&r), lease, takeover }));
    }
}

/// Give the job back to the queue (its node stops); fenced.
pub(super) async fn release(pool: &PgPool, id: &str, lease: &Lease) -> StoreResult<()> {
    let mut tx = pool.begin().await?;
    fence(&mut tx, id, lease).await?;
    sqlx::query("UPDATE jobs SET status = 'accepted', lease_expires = NULL WHERE id = $1")
        .bind(id)
        .execute(&mut *tx)
        .await?;
    sqlx::query("SELECT pg_notify($1, $2)").bind(CHANNEL).bind("queue").execute(&mut *tx).await?;
    Ok(tx.commit().await?)
}
