//! A fixed pool of worker threads that run jobs from the SQLite queue. Each worker
//! step ([`Worker::try_execute_next`]) claims the oldest accepted job, runs it
//! (resuming from its last checkpoint, if any), and records history rows,
//! checkpoints and the outcome.

use super::store::{JobRow, Store};
use crate::flow::{Checkpoint, Progress, StopReason};
use crate::jobs::{parse_spec, prepare, run_prepared, RunEvents};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::runtime::Handle;
use tokio::sync::Notify;

/// Cancellation flags of the running jobs, by id.
pub type Registry = Arc<Mutex<HashMap<String, Arc<AtomicBool>>>>;

/// What a worker step did.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Idle,
    Ran { id: String, status: String },
}

#[derive(Clone)]
pub struct Worker {
    pub store: Store,
    pub rt: Handle,
    pub registry: Registry,
    pub wake: Arc<Notify>,
    pub shutdown: Arc<AtomicBool>,
}

/// Buffers progress rows and writes them (with checkpoints) in transactions.
struct Recorder<'a> {
    w: &'a Worker,
    id: &'a str,
    rows: Vec<Progress>,
    last_flush: Instant,
    cancel: &'a AtomicBool,
    error: Option<String>,
}

impl Recorder<'_> {
    fn flush(&mut self, checkpoint: Option<&Checkpoint>) {
        let rows = std::mem::take(&mut self.rows);
        if let Err(e) = self.w.rt.block_on(self.w.store.record(self.id, &rows, checkpoint)) {
            self.error = Some(e.to_string());
            self.cancel.store(true, Ordering::Relaxed);
        }
        if let Ok(true) = self.w.rt.block_on(self.w.store.cancel_requested(self.id)) {
            self.cancel.store(true, Ordering::Relaxed);
        }
        self.last_flush = Instant::now();
    }
}

impl RunEvents for Recorder<'_> {
    fn progress(&mut self, p: &Progress) {
        self.rows.push(*p);
        if self.rows.len() >= 256 || self.last_flush.elapsed() > Duration::from_millis(250) {
            self.flush(None);
        }
    }
    fn checkpoint(&mut self, c: &Checkpoint) {
        self.flush(Some(c));
    }
}

impl Worker {
    /// Claim and run the next job, if there is one.
    pub fn try_execute_next(&self) -> Result<Outcome, sqlx::Error> {
        let Some(job) = self.rt.block_on(self.store.claim_next())? else { return Ok(Outcome::Idle) };
        let status = self.run(&job)?;
        Ok(Outcome::Ran { id: job.id, status })
    }

    /// Loop until shutdown, sleeping on the wake-up notification when idle.
    pub fn run_forever(&self) {
        while !self.shutdown.load(Ordering::Relaxed) {
            match self.try_execute_next() {
                Ok(Outcome::Ran { .. }) => {}
                Ok(Outcome::Idle) => {
                    let wake = self.wake.clone();
                    self.rt.block_on(async {
                        tokio::time::timeout(Duration::from_millis(500), wake.notified()).await.ok()
                    });
                }
                Err(e) => {
                    tracing::error!("worker: {e}");
                    std::thread::sleep(Duration::from_millis(500));
                }
            }
        }
    }

    fn run(&self, job: &JobRow) -> Result<String, sqlx::Error> {
        let finish = |status: &str, stop: Option<&str>, msg: Option<&str>| -> Result<String, sqlx::Error> {
            self.rt.block_on(self.store.finish(&job.id, status, stop, msg))?;
            Ok(status.to_string())
        };
        let inputs = self.rt.block_on(self.store.inputs(&job.id))?;
        let prepared = match parse_spec(&job.spec).and_then(|s| prepare(s, &inputs)) {
            Ok(p) => p,
            Err(e) => return finish("failed", None, Some(&e.to_string())),
        };
        let resume = self.rt.block_on(self.store.last_checkpoint(&job.id))?;
        if let Some(cp) = &resume {
            self.rt.block_on(self.store.truncate_history(&job.id, cp.iteration))?;
            tracing::info!(job = %job.id, iteration = cp.iteration, "resuming from checkpoint");
        }
        let cancel = Arc::new(AtomicBool::new(false));
        self.registry.lock().unwrap().insert(job.id.clone(), cancel.clone());
        let mut rec = Recorder {
            w: self,
            id: &job.id,
            rows: Vec::new(),
            last_flush: Instant::now(),
            cancel: &cancel,
            error: None,
        };
        let result = run_prepared(&prepared, resume.as_ref(), &cancel, &mut rec);
        rec.flush(None);
        self.registry.lock().unwrap().remove(&job.id);
        if let Some(e) = rec.error {
            return finish("failed", None, Some(&format!("storage error: {e}")));
        }
        match result {
            Ok(o) if o.stop == StopReason::Cancelled => {
                if self.shutdown.load(Ordering::Relaxed) && !self.rt.block_on(self.store.cancel_requested(&job.id))? {
                    // stopped by a server shutdown: stays running, resumes at the next start
                    return Ok("running".into());
                }
                finish("dismissed", Some("cancelled"), Some("cancelled by request"))
            }
            Ok(o) => finish("successful", Some(o.stop.as_str()), o.note),
            Err(f) => finish("failed", None, Some(&f.error.to_string())),
        }
    }
}
