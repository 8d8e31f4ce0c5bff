//! The store's logic written once for both dialects: [`job_store!`] expands to
//! the rows' readers and to the `impl JobStore` of a backend, with every method
//! whose SQL the two dialects share (numbered `$N` parameters, `TRUE`/`FALSE`,
//! `CAST(… AS …)`, `ON CONFLICT`), beside the methods the backend writes itself
//! (claims, batches of rows, outcomes, notifications: what PostgreSQL does in one
//! statement and SQLite in a transaction of its one writer).
//!
//! What a backend module provides by name, for the expansion:
//! - `BEGIN`: how a writing transaction begins (`BEGIN IMMEDIATE` on SQLite);
//! - `ADMISSION_LOCK`: a statement that makes admissions one at a time on every
//!   node, if the transaction does not already (SQLite's one writer does);
//! - `INSERT_JOB`: the insert of a new job's row (`$1` id, `$2` spec, `$3`
//!   created_at, `$4` owner), which numbers it (`seq`) the dialect's way;
//! - `notify(tx, what)`: tell the other nodes (PostgreSQL's NOTIFY; nothing on SQLite);
//! - `fence(tx, id, lease)`: the lease check of `leases`;
//! - `clock_ms!()`: the database's clock in ms since the Unix epoch, as SQL.

/// Rows of a job's history or checkpoints deleted per statement when a deleted
/// job is purged, so that the one writer is never held long.
pub(crate) const PURGE_ROWS: i64 = 20_000;

/// See the module documentation: `$store` the backend, `$row` its row type,
/// `$read` / `$write` its pools for reads and writes; `$own` the backend's own
/// methods of `JobStore`.
macro_rules! job_store {
    ($store:ty, $row:ty, read: $read:ident, write: $write:ident, { $($own:tt)* }) => {
        fn job_from_row(r: &$row) -> JobRow {
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
                    surgery: None,
                }),
                results: results_of(r.get("results")),
                owner: r.get("owner"),
            }
        }

        fn key_from_row(r: &$row) -> KeyRow {
            KeyRow {
                name: r.get("name"),
                hash: r.get("hash"),
                admin: r.get("admin"),
                max_active: r.get("max_active"),
                max_storage: r.get("max_storage"),
                created_at: r.get("created_at"),
                revoked: r.get::<Option<String>, _>("revoked_at").is_some(),
            }
        }

        fn progress_from_row(r: &$row) -> Progress {
            Progress {
                iteration: r.get::<i64, _>("iteration") as usize,
                time: r.get("time"),
                tau: r.get("tau"),
                energy: r.get("energy"),
                vertices: r.get::<i64, _>("vertices") as usize,
                components: r.get::<i64, _>("components") as usize,
                surgery: r
                    .get::<Option<String>, _>("surgery")
                    .and_then(|s| serde_json::from_str(&s).ok()),
            }
        }

        #[async_trait::async_trait]
        impl JobStore for $store {
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
                let mut tx = self.$write.begin_with(BEGIN).await?;
                if let (true, Some(lock)) = (admit.limited(), ADMISSION_LOCK) {
                    // the counts cannot change before the insert
                    sqlx::query(lock).execute(&mut *tx).await?;
                }
                if let (Some(owner), Some(max)) = (&admit.owner, admit.max_active) {
                    let active: i64 = sqlx::query_scalar(
                        "SELECT COUNT(*) FROM jobs WHERE owner = $1 AND status IN ('accepted', 'running')",
                    )
                    .bind(owner)
                    .fetch_one(&mut *tx)
                    .await?;
                    if active >= max {
                        return Err(StoreError::ActiveQuota(max));
                    }
                }
                if let (Some(owner), Some(max)) = (&admit.owner, admit.max_storage) {
                    let kept: i64 = sqlx::query_scalar(
                        "SELECT CAST(COALESCE(SUM(stored_bytes), 0) AS BIGINT) FROM jobs \
                         WHERE owner = $1 AND deleted_at IS NULL",
                    )
                    .bind(owner)
                    .fetch_one(&mut *tx)
                    .await?;
                    if kept >= max {
                        return Err(StoreError::StorageQuota(kept, max));
                    }
                }
                if let Some(max) = admit.max_queued {
                    let queued: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE status = 'accepted'")
                        .fetch_one(&mut *tx)
                        .await?;
                    if queued >= max {
                        return Err(StoreError::QueueFull(max));
                    }
                }
                sqlx::query(INSERT_JOB).bind(id).bind(spec).bind(now()).bind(&admit.owner).execute(&mut *tx).await?;
                for (name, head) in heads {
                    sqlx::query("INSERT INTO inputs (job_id, name, data, in_blob, head) VALUES ($1, $2, $3, TRUE, $4)")
                        .bind(id)
                        .bind(name)
                        .bind(&[] as &[u8])
                        .bind(head.as_slice())
                        .execute(&mut *tx)
                        .await?;
                }
                notify(&mut tx, "queue").await?;
                tx.commit().await?;
                Ok(self.job(id).await?.expect("just inserted"))
            }

            async fn input_magics(&self, id: &str) -> StoreResult<Vec<Vec<u8>>> {
                let rows = sqlx::query("SELECT COALESCE(head, substr(data, 1, 8)) AS head FROM inputs WHERE job_id = $1")
                    .bind(id)
                    .fetch_all(&self.$read)
                    .await?;
                Ok(rows.iter().map(|r| r.get::<Vec<u8>, _>("head")).collect())
            }

            async fn input_rows(&self, id: &str) -> StoreResult<Vec<InputRow>> {
                let rows = sqlx::query("SELECT name, in_blob, data FROM inputs WHERE job_id = $1")
                    .bind(id)
                    .fetch_all(&self.$read)
                    .await?;
                Ok(rows
                    .iter()
                    .map(|r| InputRow { name: r.get("name"), in_blob: r.get("in_blob"), data: r.get("data") })
                    .collect())
            }

            async fn job(&self, id: &str) -> StoreResult<Option<JobRow>> {
                let r = sqlx::query("SELECT * FROM jobs WHERE id = $1 AND deleted_at IS NULL")
                    .bind(id)
                    .fetch_optional(&self.$read)
                    .await?;
                Ok(r.as_ref().map(job_from_row))
            }

            async fn list(
                &self,
                status: Option<JobStatus>,
                before: Option<i64>,
                limit: i64,
                owner: Option<&str>,
            ) -> StoreResult<Vec<JobRow>> {
                let rows = sqlx::query(
                    "SELECT * FROM jobs WHERE (CAST($1 AS TEXT) IS NULL OR status = $1) \
                     AND (CAST($2 AS BIGINT) IS NULL OR seq < $2) AND (CAST($4 AS TEXT) IS NULL OR owner = $4) \
                     AND deleted_at IS NULL ORDER BY seq DESC LIMIT $3",
                )
                .bind(status.map(JobStatus::as_str))
                .bind(before)
                .bind(limit)
                .bind(owner)
                .fetch_all(&self.$read)
                .await?;
                Ok(rows.iter().map(job_from_row).collect())
            }

            async fn ended_before(&self, before: &str, limit: i64) -> StoreResult<Vec<String>> {
                let ids = sqlx::query_scalar(
                    "SELECT id FROM jobs WHERE status IN ('successful', 'failed', 'dismissed') AND finished_at < $1 \
                     AND deleted_at IS NULL ORDER BY finished_at LIMIT $2",
                )
                .bind(before)
                .bind(limit)
                .fetch_all(&self.$read)
                .await?;
                Ok(ids)
            }

            async fn counts_by_status(&self) -> StoreResult<Vec<(String, i64)>> {
                let rows = sqlx::query("SELECT status, COUNT(*) AS n FROM jobs WHERE deleted_at IS NULL GROUP BY status")
                    .fetch_all(&self.$read)
                    .await?;
                Ok(rows.iter().map(|r| (r.get("status"), r.get("n"))).collect())
            }

            async fn insert_key(&self, key: &KeyRow) -> StoreResult<bool> {
                let done = sqlx::query(
                    "INSERT INTO keys (name, hash, admin, max_active, max_storage, created_at) \
                     VALUES ($1, $2, $3, $4, $5, $6) ON CONFLICT DO NOTHING",
                )
                .bind(&key.name)
                .bind(&key.hash)
                .bind(key.admin)
                .bind(key.max_active)
                .bind(key.max_storage)
                .bind(&key.created_at)
                .execute(&self.$write)
                .await?;
                Ok(done.rows_affected() == 1)
            }

            async fn keys(&self) -> StoreResult<Vec<KeyRow>> {
                let rows = sqlx::query("SELECT * FROM keys ORDER BY name").fetch_all(&self.$read).await?;
                Ok(rows.iter().map(key_from_row).collect())
            }

            async fn revoke_key(&self, name: &str) -> StoreResult<bool> {
                let done = sqlx::query("UPDATE keys SET revoked_at = $2 WHERE name = $1 AND revoked_at IS NULL")
                    .bind(name)
                    .bind(now())
                    .execute(&self.$write)
                    .await?;
                Ok(done.rows_affected() == 1)
            }

            async fn key_by_hash(&self, hash: &str) -> StoreResult<Option<KeyRow>> {
                let row = sqlx::query("SELECT * FROM keys WHERE hash = $1 AND revoked_at IS NULL")
                    .bind(hash)
                    .fetch_optional(&self.$read)
                    .await?;
                Ok(row.as_ref().map(key_from_row))
            }

            async fn has_keys(&self) -> StoreResult<bool> {
                let n: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM keys WHERE revoked_at IS NULL")
                    .fetch_one(&self.$read)
                    .await?;
                Ok(n > 0)
            }

            async fn owner_storage(&self, owner: &str, except: &str) -> StoreResult<u64> {
                let kept: i64 = sqlx::query_scalar(
                    "SELECT CAST(COALESCE(SUM(stored_bytes), 0) AS BIGINT) FROM jobs \
                     WHERE owner = $1 AND id <> $2 AND deleted_at IS NULL",
                )
                .bind(owner)
                .bind(except)
                .fetch_one(&self.$read)
                .await?;
                Ok(kept.max(0) as u64)
            }

            async fn set_stored(&self, id: &str, bytes: u64) -> StoreResult<()> {
                sqlx::query("UPDATE jobs SET stored_bytes = $2 WHERE id = $1")
                    .bind(id)
                    .bind(bytes.min(i64::MAX as u64) as i64)
                    .execute(&self.$write)
                    .await?;
                Ok(())
            }

            async fn lead(&self, task: &str, node: &str, ttl: std::time::Duration) -> StoreResult<bool> {
                let done = sqlx::query(concat!(
                    "INSERT INTO leaders (name, owner, expires) VALUES ($1, $2, ",
                    clock_ms!(),
                    " + $3) ON CONFLICT (name) DO UPDATE SET owner = excluded.owner, expires = excluded.expires \
                     WHERE leaders.owner = excluded.owner OR leaders.expires < ",
                    clock_ms!()
                ))
                .bind(task)
                .bind(node)
                .bind(ttl.as_millis().min(i64::MAX as u128) as i64)
                .execute(&self.$write)
                .await?;
                Ok(done.rows_affected() == 1)
            }

            async fn renew(&self, id: &str, lease: &Lease, policy: &ClaimPolicy) -> StoreResult<bool> {
                let done = sqlx::query(concat!(
                    "UPDATE jobs SET lease_expires = ",
                    clock_ms!(),
                    " + $3 WHERE id = $1 AND lease_epoch = $2 AND status = 'running'"
                ))
                .bind(id)
                .bind(lease.epoch)
                .bind(policy.lease.as_millis() as i64)
                .execute(&self.$write)
                .await?;
                Ok(done.rows_affected() == 1)
            }

            async fn abandon(&self, id: &str, lease: &Lease, why: &str) -> StoreResult<()> {
                let done = sqlx::query(
                    "UPDATE jobs SET lease_expires = 0, message = $3 \
                     WHERE id = $1 AND lease_epoch = $2 AND status = 'running'",
                )
                .bind(id)
                .bind(lease.epoch)
                .bind(format!("{}{why}", super::ABANDONED))
                .execute(&self.$write)
                .await?;
                (done.rows_affected() == 1).then_some(()).ok_or_else(|| StoreError::LeaseLost(id.to_string()))
            }

            async fn checkpoint_index(&self, id: &str, after: i64) -> StoreResult<Vec<(i64, f64)>> {
                let rows = sqlx::query(
                    "SELECT iteration, time FROM checkpoints WHERE job_id = $1 AND iteration > $2 \
                     ORDER BY iteration LIMIT $3",
                )
                .bind(id)
                .bind(after)
                .bind(super::CHECKPOINT_PAGE as i64)
                .fetch_all(&self.$read)
                .await?;
                Ok(rows.iter().map(|r| (r.get::<i64, _>("iteration"), r.get::<f64, _>("time"))).collect())
            }

            async fn checkpoint_rows(&self, id: &str, which: Which) -> StoreResult<Vec<CheckpointRow>> {
                let query = match which {
                    Which::Last => sqlx::query(
                        "SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 ORDER BY iteration DESC LIMIT 1",
                    )
                    .bind(id),
                    Which::At(n) => {
                        sqlx::query("SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 AND iteration = $2")
                            .bind(id)
                            .bind(n)
                    }
                    Which::After(n) => sqlx::query(
                        "SELECT iteration, blob, data FROM checkpoints WHERE job_id = $1 AND iteration > $2 \
                         ORDER BY iteration LIMIT $3",
                    )
                    .bind(id)
                    .bind(n)
                    .bind(super::CHECKPOINT_PAGE as i64),
                };
                let rows = query.fetch_all(&self.$read).await?;
                Ok(rows
                    .iter()
                    .map(|r| CheckpointRow { iteration: r.get("iteration"), blob: r.get("blob"), data: r.get("data") })
                    .collect())
            }

            async fn truncate_history(&self, id: &str, lease: &Lease, after: usize) -> StoreResult<()> {
                let mut tx = self.$write.begin_with(BEGIN).await?;
                fence(&mut tx, id, lease).await?;
                sqlx::query("DELETE FROM history WHERE job_id = $1 AND iteration > $2")
                    .bind(id)
                    .bind(after as i64)
                    .execute(&mut *tx)
                    .await?;
                Ok(tx.commit().await?)
            }

            async fn set_results(&self, id: &str, lease: Option<&Lease>, index: &str) -> StoreResult<bool> {
                let mut tx = self.$write.begin_with(BEGIN).await?;
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

            async fn cancel_requested(&self, id: &str) -> StoreResult<bool> {
                let r = sqlx::query("SELECT cancel_requested FROM jobs WHERE id = $1")
                    .bind(id)
                    .fetch_optional(&self.$read)
                    .await?;
                Ok(r.map(|r| r.get::<bool, _>("cancel_requested")).unwrap_or(true))
            }

            async fn mark_deleted(&self, id: &str) -> StoreResult<bool> {
                let done = sqlx::query(
                    "UPDATE jobs SET deleted_at = $2 WHERE id = $1 AND deleted_at IS NULL \
                     AND status IN ('successful', 'failed', 'dismissed')",
                )
                .bind(id)
                .bind(now())
                .execute(&self.$write)
                .await?;
                Ok(done.rows_affected() == 1)
            }

            async fn deleted_jobs(&self, limit: i64) -> StoreResult<Vec<String>> {
                let ids = sqlx::query_scalar(
                    "SELECT id FROM jobs WHERE deleted_at IS NOT NULL ORDER BY deleted_at LIMIT $1",
                )
                .bind(limit)
                .fetch_all(&self.$read)
                .await?;
                Ok(ids)
            }

            async fn purge_rows(&self, id: &str) -> StoreResult<bool> {
                for sql in [
                    "DELETE FROM history WHERE job_id = $1 AND iteration IN \
                     (SELECT iteration FROM history WHERE job_id = $1 ORDER BY iteration LIMIT $2)",
                    "DELETE FROM checkpoints WHERE job_id = $1 AND iteration IN \
                     (SELECT iteration FROM checkpoints WHERE job_id = $1 ORDER BY iteration LIMIT $2)",
                ] {
                    let done = sqlx::query(sql).bind(id).bind(super::shared::PURGE_ROWS).execute(&self.$write).await?;
                    if done.rows_affected() > 0 {
                        return Ok(false);
                    }
                }
                sqlx::query("DELETE FROM jobs WHERE id = $1 AND deleted_at IS NOT NULL")
                    .bind(id)
                    .execute(&self.$write)
                    .await?;
                Ok(true)
            }

            async fn history_count(&self, id: &str) -> StoreResult<u64> {
                let n: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM history WHERE job_id = $1")
                    .bind(id)
                    .fetch_one(&self.$read)
                    .await?;
                Ok(n as u64)
            }

            async fn history_from(&self, id: &str, from: usize, limit: usize) -> StoreResult<Vec<Progress>> {
                let rows = sqlx::query(
                    "SELECT * FROM history WHERE job_id = $1 AND iteration >= $2 ORDER BY iteration LIMIT $3",
                )
                .bind(id)
                .bind(from as i64)
                .bind(limit.min(i64::MAX as usize) as i64)
                .fetch_all(&self.$read)
                .await?;
                Ok(rows.iter().map(progress_from_row).collect())
            }

            $($own)*
        }
    };
}
