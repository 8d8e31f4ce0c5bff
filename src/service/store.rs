//! The SQLite store: every SQL statement of the service lives here. One pool with a
//! single connection serializes writers (WAL, synchronous=NORMAL).

use crate::flow::{Checkpoint, Progress};
use sqlx::sqlite::{SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteSynchronous};
use sqlx::Row;
use std::collections::HashMap;
use std::path::Path;
use std::time::Duration;

/// A job as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct JobRow {
    pub id: String,
    /// Submission order (1, 2, ...).
    pub seq: i64,
    pub status: String,
    pub spec: String,
    pub created_at: String,
    pub started_at: Option<String>,
    pub finished_at: Option<String>,
    pub message: Option<String>,
    pub stop_reason: Option<String>,
    pub progress: Option<Progress>,
}

#[derive(Clone)]
pub struct Store {
    pool: SqlitePool,
}

fn now() -> String {
    // RFC 3339 UTC from the system clock, without a date-time crate
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

fn job_from_row(r: &sqlx::sqlite::SqliteRow) -> JobRow {
    let iteration: Option<i64> = r.get("iteration");
    JobRow {
        id: r.get("id"),
        seq: r.get("seq"),
        status: r.get("status"),
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
    }
}

impl Store {
    /// Open (creating if missing) and migrate the database file.
    pub async fn open(path: &Path) -> Result<Self, sqlx::Error> {
        let options = SqliteConnectOptions::new()
            .filename(path)
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(10))
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new().max_connections(1).connect_with(options).await?;
        sqlx::migrate!("./migrations").run(&pool).await?;
        Ok(Store { pool })
    }

    /// Store a new accepted job and its uploaded inputs, in one transaction.
    pub async fn insert_job(
        &self,
        id: &str,
        spec: &str,
        inputs: &HashMap<String, Vec<u8>>,
    ) -> Result<JobRow, sqlx::Error> {
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        sqlx::query(
            "INSERT INTO jobs (id, seq, status, spec, created_at) \
             VALUES (?1, (SELECT COALESCE(MAX(seq), 0) + 1 FROM jobs), 'accepted', ?2, ?3)",
        )
        .bind(id)
        .bind(spec)
        .bind(now())
        .execute(&mut *tx)
        .await?;
        for (name, data) in inputs {
            sqlx::query("INSERT INTO inputs (job_id, name, data) VALUES (?1, ?2, ?3)")
                .bind(id)
                .bind(name)
                .bind(data.as_slice())
                .execute(&mut *tx)
                .await?;
        }
        tx.commit().await?;
        Ok(self.job(id).await?.expect("just inserted"))
    }

    /// The first bytes (at most 8) of each uploaded input of a job: enough to tell
    /// the file type without loading the files.
    pub async fn input_magics(&self, id: &str) -> Result<Vec<Vec<u8>>, sqlx::Error> {
        let rows = sqlx::query("SELECT substr(data, 1, 8) AS head FROM inputs WHERE job_id = ?1")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        Ok(rows.iter().map(|r| r.get::<Vec<u8>, _>("head")).collect())
    }

    /// The uploaded inputs of a job, by name.
    pub async fn inputs(&self, id: &str) -> Result<HashMap<String, Vec<u8>>, sqlx::Error> {
        let rows =
            sqlx::query("SELECT name, data FROM inputs WHERE job_id = ?1").bind(id).fetch_all(&self.pool).await?;
        Ok(rows.iter().map(|r| (r.get::<String, _>("name"), r.get::<Vec<u8>, _>("data"))).collect())
    }

    pub async fn job(&self, id: &str) -> Result<Option<JobRow>, sqlx::Error> {
        let r = sqlx::query("SELECT * FROM jobs WHERE id = ?1").bind(id).fetch_optional(&self.pool).await?;
        Ok(r.as_ref().map(job_from_row))
    }

    /// Jobs newest first, optionally of one status and submitted before `before`
    /// (a `seq`), at most `limit`.
    pub async fn list(
        &self,
        status: Option<&str>,
        before: Option<i64>,
        limit: i64,
    ) -> Result<Vec<JobRow>, sqlx::Error> {
        let rows = sqlx::query(
            "SELECT * FROM jobs WHERE (?1 IS NULL OR status = ?1) AND (?2 IS NULL OR seq < ?2) \
             ORDER BY seq DESC LIMIT ?3",
        )
        .bind(status)
        .bind(before)
        .bind(limit)
        .fetch_all(&self.pool)
        .await?;
        Ok(rows.iter().map(job_from_row).collect())
    }

    /// Jobs left running by a crash go back to the queue (they resume from their
    /// last checkpoint).
    pub async fn requeue_running(&self) -> Result<u64, sqlx::Error> {
        Ok(sqlx::query("UPDATE jobs SET status = 'accepted' WHERE status = 'running'")
            .execute(&self.pool)
            .await?
            .rows_affected())
    }

    /// Take the oldest accepted job and mark it running.
    pub async fn claim_next(&self) -> Result<Option<JobRow>, sqlx::Error> {
        let r = sqlx::query(
            "UPDATE jobs SET status = 'running', started_at = COALESCE(started_at, ?1) \
             WHERE id = (SELECT id FROM jobs WHERE status = 'accepted' ORDER BY seq LIMIT 1) RETURNING *",
        )
        .bind(now())
        .fetch_optional(&self.pool)
        .await?;
        Ok(r.as_ref().map(job_from_row))
    }

    /// The newest checkpoint of a job.
    pub async fn last_checkpoint(&self, id: &str) -> Result<Option<Checkpoint>, sqlx::Error> {
        let r = sqlx::query("SELECT data FROM checkpoints WHERE job_id = ?1 ORDER BY iteration DESC LIMIT 1")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?;
        Ok(r.and_then(|r| serde_json::from_str(&r.get::<String, _>("data")).ok()))
    }

    /// `(iteration, time)` of every checkpoint of a job, oldest first.
    pub async fn checkpoint_index(&self, id: &str) -> Result<Vec<(i64, f64)>, sqlx::Error> {
        let rows = sqlx::query("SELECT iteration, time FROM checkpoints WHERE job_id = ?1 ORDER BY iteration")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        Ok(rows.iter().map(|r| (r.get::<i64, _>("iteration"), r.get::<f64, _>("time"))).collect())
    }

    /// The checkpoint of a job at `iteration`.
    pub async fn checkpoint_at(&self, id: &str, iteration: i64) -> Result<Option<Checkpoint>, sqlx::Error> {
        let r = sqlx::query("SELECT data FROM checkpoints WHERE job_id = ?1 AND iteration = ?2")
            .bind(id)
            .bind(iteration)
            .fetch_optional(&self.pool)
            .await?;
        Ok(r.and_then(|r| serde_json::from_str(&r.get::<String, _>("data")).ok()))
    }

    /// Every checkpoint of a job, oldest first.
    pub async fn checkpoints(&self, id: &str) -> Result<Vec<Checkpoint>, sqlx::Error> {
        let rows = sqlx::query("SELECT data FROM checkpoints WHERE job_id = ?1 ORDER BY iteration")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        Ok(rows.iter().filter_map(|r| serde_json::from_str(&r.get::<String, _>("data")).ok()).collect())
    }

    /// Append history rows and update the job's progress in one transaction. Rows
    /// already present (after a resume) are replaced, never duplicated.
    pub async fn record(
        &self,
        id: &str,
        rows: &[Progress],
        checkpoint: Option<&Checkpoint>,
    ) -> Result<(), sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        for p in rows {
            sqlx::query("INSERT OR REPLACE INTO history VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)")
                .bind(id)
                .bind(p.iteration as i64)
                .bind(p.time)
                .bind(p.tau)
                .bind(p.energy)
                .bind(p.vertices as i64)
                .bind(p.components as i64)
                .execute(&mut *tx)
                .await?;
        }
        if let Some(p) = rows.last() {
            sqlx::query(
                "UPDATE jobs SET (iteration, time, tau, energy, vertices, components) = \
                 (SELECT iteration, time, tau, energy, vertices, components FROM history \
                  WHERE job_id = ?1 AND iteration = ?2) WHERE id = ?1",
            )
            .bind(id)
            .bind(p.iteration as i64)
            .execute(&mut *tx)
            .await?;
        }
        if let Some(c) = checkpoint {
            sqlx::query("INSERT OR REPLACE INTO checkpoints VALUES (?1, ?2, ?3, ?4)")
                .bind(id)
                .bind(c.iteration as i64)
                .bind(c.time)
                .bind(serde_json::to_string(c).expect("checkpoint serializes"))
                .execute(&mut *tx)
                .await?;
        }
        tx.commit().await
    }

    /// Drop history rows after a checkpoint (before resuming from it).
    pub async fn truncate_history(&self, id: &str, after: usize) -> Result<(), sqlx::Error> {
        sqlx::query("DELETE FROM history WHERE job_id = ?1 AND iteration > ?2")
            .bind(id)
            .bind(after as i64)
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    pub async fn finish(
        &self,
        id: &str,
        status: &str,
        stop_reason: Option<&str>,
        message: Option<&str>,
    ) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET status = ?2, stop_reason = ?3, message = ?4, finished_at = ?5 WHERE id = ?1")
            .bind(id)
            .bind(status)
            .bind(stop_reason)
            .bind(message)
            .bind(now())
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    pub async fn cancel_requested(&self, id: &str) -> Result<bool, sqlx::Error> {
        let r =
            sqlx::query("SELECT cancel_requested FROM jobs WHERE id = ?1").bind(id).fetch_optional(&self.pool).await?;
        Ok(r.map(|r| r.get::<i64, _>("cancel_requested") != 0).unwrap_or(true))
    }

    /// Request cancellation: an accepted job is dismissed at once, a running one
    /// flagged. Returns the status before the request, `None` if unknown.
    pub async fn request_cancel(&self, id: &str) -> Result<Option<String>, sqlx::Error> {
        let Some(job) = self.job(id).await? else { return Ok(None) };
        if job.status == "accepted" {
            self.finish(id, "dismissed", Some("cancelled"), Some("cancelled before it started")).await?;
        }
        sqlx::query("UPDATE jobs SET cancel_requested = 1 WHERE id = ?1").bind(id).execute(&self.pool).await?;
        Ok(Some(job.status))
    }

    pub async fn delete(&self, id: &str) -> Result<(), sqlx::Error> {
        sqlx::query("DELETE FROM jobs WHERE id = ?1").bind(id).execute(&self.pool).await?;
        Ok(())
    }

    pub async fn history(&self, id: &str) -> Result<Vec<Progress>, sqlx::Error> {
        self.history_from(id, 0).await
    }

    /// History rows from iteration `from` on.
    pub async fn history_from(&self, id: &str, from: usize) -> Result<Vec<Progress>, sqlx::Error> {
        let rows = sqlx::query("SELECT * FROM history WHERE job_id = ?1 AND iteration >= ?2 ORDER BY iteration")
            .bind(id)
            .bind(from as i64)
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
