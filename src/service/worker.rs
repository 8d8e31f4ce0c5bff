//! Worker threads that run jobs from the store's queue. Each worker step
//! ([`Worker::try_execute_next`]) claims the oldest accepted job (or one whose
//! lease expired), keeps its lease alive with heartbeats, runs it (resuming from
//! its last checkpoint, if any), and records history rows, checkpoints and the
//! outcome, every write fenced by the lease. A worker that loses its lease stops
//! the run and writes nothing more.

use super::store::{ClaimPolicy, Claimed, JobStatus, Lease, Store, StoreError};
use crate::flow::{Checkpoint, Progress, StopReason};
use crate::jobs::{parse_spec, prepare, run_prepared, RunEvents};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::runtime::Handle;
use tokio::sync::{broadcast, Notify};

/// Cancellation flags of the running jobs, by id.
pub type Registry = Arc<Mutex<HashMap<String, Arc<AtomicBool>>>>;

/// What a worker step did.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Idle,
    /// The job ended with `status`, or stopped still `running` (the node stops).
    Ran {
        id: String,
        status: JobStatus,
    },
    /// Another worker took the job over; this run's results were dropped.
    Lost {
        id: String,
    },
}

#[derive(Clone)]
pub struct Worker {
    pub store: Store,
    pub rt: Handle,
    pub registry: Registry,
    pub wake: Arc<Notify>,
    pub shutdown: Arc<AtomicBool>,
    /// Where each history batch and outcome is announced (the job's id).
    pub events: broadcast::Sender<Arc<str>>,
    /// This node's name in the leases it holds.
    pub owner: String,
    pub policy: ClaimPolicy,
}

/// Why a run's writes stopped.
#[derive(Default)]
struct WriteState {
    /// The lease moved on: another worker has the job.
    lost: bool,
    /// Another storage error.
    error: Option<String>,
}

/// Buffers progress rows and writes them (with checkpoints) in fenced transactions.
struct Recorder<'a> {
    w: &'a Worker,
    id: &'a str,
    lease: &'a Lease,
    rows: Vec<Progress>,
    last_flush: Instant,
    cancel: &'a AtomicBool,
    state: WriteState,
}

/// How long a write is retried while the database cannot be reached.
const RETRY_FOR: Duration = Duration::from_secs(60);

/// `op` until it succeeds, fails for a reason other than an unreachable database,
/// or [`RETRY_FOR`] has passed.
fn retrying<T, F: std::future::Future<Output = Result<T, StoreError>>>(
    rt: &Handle,
    mut op: impl FnMut() -> F,
) -> Result<T, StoreError> {
    let start = Instant::now();
    loop {
        match rt.block_on(op()) {
            Err(e) if e.is_transient() && start.elapsed() < RETRY_FOR => {
                tracing::warn!("database unreachable ({e}); retrying");
                std::thread::sleep(Duration::from_millis(250));
            }
            other => return other,
        }
    }
}

impl Recorder<'_> {
    fn flush(&mut self, checkpoint: Option<&Checkpoint>) {
        if self.state.lost || self.state.error.is_some() {
            return;
        }
        let rows = std::mem::take(&mut self.rows);
        let (store, id, lease) = (&self.w.store, self.id, self.lease);
        match retrying(&self.w.rt, || store.record(id, lease, &rows, checkpoint)) {
            Ok(()) => {
                let _ = self.w.events.send(Arc::from(self.id));
            }
            Err(StoreError::LeaseLost(_)) => {
                self.state.lost = true;
                self.cancel.store(true, Ordering::Relaxed);
            }
            Err(e) => {
                self.state.error = Some(e.to_string());
                self.cancel.store(true, Ordering::Relaxed);
            }
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
    pub fn try_execute_next(&self) -> Result<Outcome, StoreError> {
        let Some(claimed) = self.rt.block_on(self.store.claim_next(&self.owner, &self.policy))? else {
            return Ok(Outcome::Idle);
        };
        let id = claimed.job.id.clone();
        match self.run(&claimed) {
            Ok(status) => Ok(Outcome::Ran { id, status }),
            Err(StoreError::LeaseLost(_)) => Ok(Outcome::Lost { id }),
            Err(e) => Err(e),
        }
    }

    /// Loop until shutdown, sleeping on the wake-up notification when idle (at
    /// most half a second: jobs of other nodes' queues and expired leases are
    /// seen by polling the store).
    pub fn run_forever(&self) {
        while !self.shutdown.load(Ordering::Relaxed) {
            match self.try_execute_next() {
                Ok(Outcome::Ran { .. } | Outcome::Lost { .. }) => {}
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

    /// Renew `lease` every third of its length until `done`; on a lost lease set
    /// `lost` and `cancel` (the run stops at its next step).
    fn heartbeat(&self, id: &str, lease: &Lease, done: Arc<Notify>, lost: Arc<AtomicBool>, cancel: Arc<AtomicBool>) {
        let (store, policy, id, lease) = (self.store.clone(), self.policy, id.to_string(), lease.clone());
        self.rt.spawn(async move {
            let period = policy.lease / 3;
            loop {
                tokio::select! {
                    _ = done.notified() => return,
                    _ = tokio::time::sleep(period) => {}
                }
                match store.renew(&id, &lease, &policy).await {
                    Ok(true) => {}
                    Ok(false) => {
                        tracing::warn!(job = %id, "lease lost to another worker: stopping the run");
                        lost.store(true, Ordering::Relaxed);
                        cancel.store(true, Ordering::Relaxed);
                        return;
                    }
                    // the database is away: keep trying; the writes are fenced anyway
                    Err(e) => tracing::warn!(job = %id, "lease renewal: {e}"),
                }
            }
        });
    }

    fn run(&self, claimed: &Claimed) -> Result<JobStatus, StoreError> {
        let (job, lease) = (&claimed.job, &claimed.lease);
        let finish = |status: JobStatus, stop: Option<&str>, msg: Option<&str>| -> Result<JobStatus, StoreError> {
            retrying(&self.rt, || self.store.finish(&job.id, Some(lease), status, stop, msg))?;
            let _ = self.events.send(Arc::from(job.id.as_str()));
            Ok(status)
        };
        if claimed.takeover {
            tracing::info!(job = %job.id, "taking over a job whose lease expired");
        }
        let inputs = self.rt.block_on(self.store.inputs(&job.id))?;
        let prepared = match parse_spec(&job.spec).and_then(|s| prepare(s, &inputs)) {
            Ok(p) => p,
            Err(e) => return finish(JobStatus::Failed, None, Some(&e.to_string())),
        };
        let resume = self.rt.block_on(self.store.last_checkpoint(&job.id))?;
        if let Some(cp) = &resume {
            self.rt.block_on(self.store.truncate_history(&job.id, lease, cp.iteration))?;
            tracing::info!(job = %job.id, iteration = cp.iteration, "resuming from checkpoint");
        }
        let cancel = Arc::new(AtomicBool::new(false));
        let lost = Arc::new(AtomicBool::new(false));
        let done = Arc::new(Notify::new());
        self.heartbeat(&job.id, lease, done.clone(), lost.clone(), cancel.clone());
        self.registry.lock().unwrap().insert(job.id.clone(), cancel.clone());
        let mut rec = Recorder {
            w: self,
            id: &job.id,
            lease,
            rows: Vec::new(),
            last_flush: Instant::now(),
            cancel: &cancel,
            state: WriteState::default(),
        };
        let result = run_prepared(&prepared, resume.as_ref(), &cancel, &mut rec);
        rec.flush(None);
        done.notify_one();
        self.registry.lock().unwrap().remove(&job.id);
        if rec.state.lost || lost.load(Ordering::Relaxed) {
            tracing::warn!(job = %job.id, "the job was taken over by another worker; this run's results are dropped");
            return Err(StoreError::LeaseLost(job.id.clone()));
        }
        if let Some(e) = rec.state.error {
            return finish(JobStatus::Failed, None, Some(&format!("storage error: {e}")));
        }
        match result {
            Ok(o) if o.stop == StopReason::Cancelled => {
                if self.shutdown.load(Ordering::Relaxed) && !self.rt.block_on(self.store.cancel_requested(&job.id))? {
                    // stopped by a node shutdown: the job goes back to the queue
                    // (PostgreSQL) or stays running to resume at the next start (SQLite)
                    self.rt.block_on(self.store.release(&job.id, lease))?;
                    return Ok(JobStatus::Running);
                }
                finish(JobStatus::Dismissed, Some("cancelled"), Some("cancelled by request"))
            }
            Ok(o) => finish(JobStatus::Successful, Some(o.stop.as_str()), o.note),
            Err(f) => finish(JobStatus::Failed, None, Some(&f.error.to_string())),
        }
    }
}
