//! Worker threads that run jobs from the store's queue. Each worker step
//! ([`Worker::try_execute_next`]) claims the oldest accepted job (or one whose
//! lease expired), keeps its lease alive with heartbeats, runs it (resuming from
//! its last checkpoint, if any), and records history rows, checkpoints, the
//! result files and the outcome, every write fenced by the lease. A worker that
//! loses its lease stops the run and writes nothing more. The result files are
//! computed once, when the run ends ([`result_files`]), from the frames stored;
//! their blobs are written first, and the row points to them in the transaction
//! that records the outcome. The run itself happens on the worker's thread or in
//! a process of its own ([`Isolation`]; the attempts are in `attempt.rs`); an attempt
//! that ends abnormally (a panic, its process killed) is abandoned: the job goes
//! on from its last checkpoint at its next claim, up to the policy's limit.

use super::isolation::{Budgets, Isolation};
use super::recorder::{retrying, WriteState};
use super::store::{ClaimPolicy, Claimed, JobStatus, Lease, Store, StoreError, StoredResults};
use crate::jobs::{result_files, Frame, PreparedJob, ResultFile};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
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
    /// Where each outcome is announced (the job's id), and each history batch
    /// unless the store announces it itself
    /// ([`crate::service::store::JobStore::announces`]).
    pub events: broadcast::Sender<Arc<str>>,
    /// This node's name in the leases it holds.
    pub owner: String,
    pub policy: ClaimPolicy,
    pub isolation: Isolation,
    pub budgets: Budgets,
    /// Faults injected into jobs by submission number (tests of isolation only).
    pub faults: Arc<Vec<(i64, String)>>,
    /// Where attempts, takeovers and run times are counted.
    pub metrics: Arc<super::metrics::Metrics>,
}

impl Worker {
    /// Claim and run the next job, if there is one.
    pub fn try_execute_next(&self) -> Result<Outcome, StoreError> {
        let Some(claimed) = self.rt.block_on(self.store.claim_next(&self.owner, &self.policy))? else {
            return Ok(Outcome::Idle);
        };
        let id = claimed.job.id.clone();
        self.metrics.attempts.inc();
        if claimed.takeover {
            self.metrics.takeovers.inc();
        }
        let started = std::time::Instant::now();
        // a panic in the worker's own work (the result files, say) ends the attempt,
        // not the worker: the job goes on at its next claim
        let ran =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.run(&claimed))).unwrap_or_else(|panic| {
                let why = format!("panicked: {}", super::isolation::child::panic_text(panic.as_ref()));
                tracing::error!(job = %id, "attempt ended: {why}");
                self.rt.block_on(retrying(|| self.store.abandon(&id, &claimed.lease, &why)))?;
                Ok(JobStatus::Running)
            });
        self.metrics.run_seconds.observe(started.elapsed().as_secs_f64());
        match ran {
            Ok(status) => Ok(Outcome::Ran { id, status }),
            Err(StoreError::LeaseLost(_)) => Ok(Outcome::Lost { id }),
            Err(e) => Err(e),
        }
    }

    /// Loop until shutdown, sleeping on the wake-up notification when idle (a
    /// submission on this node, or another node's "queue" notification), at most
    /// half a second: expired leases are seen by looking at the store.
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

    /// Note in the job's row what it keeps now, or `needed` if more (a job stopped
    /// at its key's storage quota uses the quota up): its key's `max_storage`
    /// counts it.
    fn note_stored(&self, id: &str, needed: u64) {
        let noted =
            self.rt.block_on(async { self.store.set_stored(id, self.store.stored_bytes(id).await?.max(needed)).await });
        if let Err(e) = noted {
            tracing::warn!(job = %id, "cannot note the bytes the job keeps: {e}");
        }
    }

    /// What is left of the storage quota of the job's key for it (the bytes the
    /// key's other jobs keep taken off), if its key has one.
    pub(super) fn key_room(&self, job: &super::store::JobRow) -> Result<Option<u64>, StoreError> {
        let Some(owner) = &job.owner else { return Ok(None) };
        let keys = self.rt.block_on(self.store.keys())?;
        let Some(max) = keys.iter().find(|k| &k.name == owner).and_then(|k| k.max_storage) else { return Ok(None) };
        let others = self.rt.block_on(self.store.owner_storage(owner, &job.id))?;
        Ok(Some((max.max(0) as u64).saturating_sub(others)))
    }

    fn run(&self, claimed: &Claimed) -> Result<JobStatus, StoreError> {
        let (job, lease) = (&claimed.job, &claimed.lease);
        let needed = std::cell::Cell::new(0);
        // the outcome, with the row pointed to the result files in the same transaction
        let finish_with = |status: JobStatus,
                           stop: Option<&str>,
                           msg: Option<&str>,
                           stored: Option<&StoredResults>|
         -> Result<JobStatus, StoreError> {
            let index = stored.map(|s| s.index.as_str());
            // before the outcome: a client that sees it sees the bytes counted
            self.note_stored(&job.id, needed.get());
            let ended =
                self.rt.block_on(retrying(|| self.store.finish(&job.id, Some(lease), status, stop, msg, index)));
            // the folder no longer pointed to: the old one, or ours if the lease was lost
            // (after another error the row may point to either: both are kept)
            let pointed = match &ended {
                Ok(()) => Some(true),
                Err(StoreError::LeaseLost(_)) => Some(false),
                Err(_) => None,
            };
            if let (Some(s), Some(pointed)) = (stored, pointed) {
                if let Err(e) = self.rt.block_on(self.store.drop_results(&job.id, s, pointed)) {
                    tracing::warn!(job = %job.id, "cannot drop old result files: {e}");
                }
            }
            ended?;
            // at once, without waiting for the store's notification: a stream that
            // reads the outcome ends, so the notification wakes it no more
            let _ = self.events.send(Arc::from(job.id.as_str()));
            Ok(status)
        };
        if claimed.takeover {
            tracing::info!(job = %job.id, "taking over a job whose lease expired");
        }
        let cancel = Arc::new(AtomicBool::new(false));
        let lost = Arc::new(AtomicBool::new(false));
        let done = Arc::new(Notify::new());
        self.heartbeat(&job.id, lease, done.clone(), lost.clone(), cancel.clone());
        self.registry.lock().unwrap().insert(job.id.clone(), cancel.clone());
        // the heartbeat stops and the job leaves the registry however this ends
        let _running = Running { registry: &self.registry, id: &job.id, done: &done };
        let fault = self.faults.iter().find(|(seq, _)| *seq == job.seq).map(|(_, f)| f.clone());
        let attempt = match &self.isolation {
            Isolation::Thread => self.in_thread(job, lease, &cancel, fault),
            Isolation::Process { runner } => self.in_process(runner, job, lease, &cancel, fault),
        };
        drop(_running);
        let attempt = attempt?;
        needed.set(attempt.needed);
        if attempt.written.lost || lost.load(Ordering::Relaxed) {
            tracing::warn!(job = %job.id, "the job was taken over by another worker; this run's results are dropped");
            return Err(StoreError::LeaseLost(job.id.clone()));
        }
        if let Some(e) = attempt.written.error {
            tracing::error!(job = %job.id, "storage error: {e}");
            let msg = "the job's history or checkpoints could not be stored (the data disk or the database failed); its checkpoints so far are kept";
            return finish_with(JobStatus::Failed, None, Some(msg), None);
        }
        let end = attempt.end;
        if let AttemptEnd::Crashed(why) = &end {
            tracing::warn!(job = %job.id, "attempt ended: {why}");
            self.rt.block_on(retrying(|| self.store.abandon(&job.id, lease, why)))?;
            self.note_stored(&job.id, attempt.needed);
            let _ = self.events.send(Arc::from(job.id.as_str()));
            return Ok(JobStatus::Running);
        }
        let stopping = end == AttemptEnd::Cancelled
            && self.shutdown.load(Ordering::Relaxed)
            && !self.rt.block_on(self.store.cancel_requested(&job.id))?;
        let mut stored = None;
        if !stopping {
            let files = match attempt.results {
                Results::None => Vec::new(),
                Results::Files(files) => files,
                Results::Frames(prepared, frames) => result_files(&prepared, &frames),
            };
            if !files.is_empty() {
                match self.rt.block_on(retrying(|| self.store.store_results(&job.id, Some(lease), &files))) {
                    Ok(s) => stored = Some(s),
                    // written on the first request instead
                    Err(e) => tracing::warn!(job = %job.id, "cannot store the result files: {e}"),
                }
            }
        }
        let stored = stored.as_ref();
        match end {
            AttemptEnd::Cancelled if stopping => {
                // stopped by a node shutdown: the job goes back to the queue
                self.rt.block_on(self.store.release(&job.id, lease))?;
                Ok(JobStatus::Running)
            }
            AttemptEnd::Cancelled => {
                finish_with(JobStatus::Dismissed, Some("cancelled"), Some("cancelled by request"), stored)
            }
            AttemptEnd::Stopped { stop, note } => {
                finish_with(JobStatus::Successful, Some(&stop), note.as_deref(), stored)
            }
            AttemptEnd::Failed(msg) => finish_with(JobStatus::Failed, None, Some(&msg), stored),
            AttemptEnd::Crashed(_) => unreachable!("abandoned above"),
        }
    }
}

/// A job running on a worker: when dropped (the attempt over, or a panic), its
/// heartbeat stops and it leaves the registry.
struct Running<'a> {
    registry: &'a Registry,
    id: &'a str,
    done: &'a Notify,
}

impl Drop for Running<'_> {
    fn drop(&mut self) {
        self.done.notify_one();
        self.registry.lock().unwrap_or_else(|e| e.into_inner()).remove(self.id);
    }
}

/// How an attempt ended.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum AttemptEnd {
    /// The run stopped by its rules.
    Stopped { stop: String, note: Option<String> },
    /// Cancelled (by request, or by the node stopping).
    Cancelled,
    /// The job fails: a numeric failure, a spec that no longer prepares, a budget.
    Failed(String),
    /// The attempt ended abnormally (a panic, its process killed): the job is
    /// tried again from its last checkpoint.
    Crashed(String),
}

/// What the result files are made of.
pub(super) enum Results {
    None,
    /// Made by the job's process.
    Files(Vec<ResultFile>),
    /// To be made from the frames of the run (thread isolation).
    Frames(Arc<PreparedJob>, Vec<Frame>),
}

pub(super) struct Attempt {
    pub end: AttemptEnd,
    pub written: WriteState,
    pub results: Results,
    /// The bytes the job's process stored or tried to store (process isolation):
    /// past its disk budget, more than the store keeps.
    pub needed: u64,
}

impl Attempt {
    pub(super) fn ended(end: AttemptEnd) -> Attempt {
        Attempt { end, written: WriteState::default(), results: Results::None, needed: 0 }
    }
}
