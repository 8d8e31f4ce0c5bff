//! What a running job writes: its history rows (batched: 256 rows or 250 ms;
//! thinned past [`super::history::HISTORY_ROWS`]) and
//! checkpoints, in fenced transactions ([`super::store::JobStore::record`]) made
//! by a writer task in submission order, so that the engine computes on while the
//! database commits (at most [`QUEUE`] batches wait; beyond that the engine waits).
//! The batches that wait are written together, in one transaction.
//! A checkpoint is stored as a [`Frame`]: its per-vertex fields are computed once,
//! by the writer, on the blocking pool, with its drawing for the glb files while
//! the frames fit in evolution.glb ([`FrameMaker`]), so that the result files need
//! little work when the run ends.
//! The writer first stores the job's glb context, which the checkpoints' glb files
//! need, while the run starts. Under process isolation the job's process makes
//! the frames and the context, and the recorder only stores them
//! ([`Recorder::made_checkpoint`]).
//! A lost lease or a storage error stops the run (through its cancel flag) and is
//! reported when the recorder is closed.

use super::history::Thinning;
use super::store::{Lease, MadeFrame, Store, StoreError};
use crate::flow::{Checkpoint, Progress};
use crate::jobs::{FrameMaker, GlbContext, KeptFrames, PreparedJob, RunEvents};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::runtime::Handle;
use tokio::sync::{broadcast, mpsc};

/// How long history rows wait to be written at most while steps come.
const BATCH_TIME: Duration = Duration::from_millis(250);

/// Batches that may wait for the writer.
const QUEUE: usize = 4;

/// How long a write is retried while the database cannot be reached.
const RETRY_FOR: Duration = Duration::from_secs(60);

/// Why a run's writes stopped.
#[derive(Debug, Default)]
pub(super) struct WriteState {
    /// The lease moved on: another worker has the job.
    pub lost: bool,
    /// Another storage error.
    pub error: Option<String>,
    /// The frames written (those the writer made), in order, as many as
    /// evolution.glb may show ([`KeptFrames`]).
    pub frames: KeptFrames,
}

/// `op` until it succeeds, fails for a reason other than an unreachable database,
/// or [`RETRY_FOR`] has passed.
pub(super) async fn retrying<T, F: std::future::Future<Output = Result<T, StoreError>>>(
    mut op: impl FnMut() -> F,
) -> Result<T, StoreError> {
    let start = Instant::now();
    loop {
        match op().await {
            Err(e) if e.is_transient() && start.elapsed() < RETRY_FOR => {
                tracing::warn!("database unreachable ({e}); retrying");
                tokio::time::sleep(Duration::from_millis(250)).await;
            }
            other => return other,
        }
    }
}

struct Batch {
    rows: Vec<Progress>,
    checkpoint: Option<Pending>,
}

/// A checkpoint to store: a state whose frame the writer makes, or a frame made.
enum Pending {
    State(Checkpoint),
    Made(MadeFrame),
}

/// The [`RunEvents`] of a job run by a worker.
pub(super) struct Recorder {
    rt: Handle,
    rows: Vec<Progress>,
    thinning: Thinning,
    last_flush: Instant,
    queue: Option<mpsc::Sender<Batch>>,
    writer: Option<tokio::task::JoinHandle<WriteState>>,
}

impl Recorder {
    /// Start the writer of job `id` under `lease`, which makes the frames of the
    /// checkpoints of `job` (if given; it stores the job's glb context first) or
    /// stores frames already made; `cancel` is raised when the run must stop
    /// (cancellation requested, lease lost, storage error); every written batch is
    /// announced on `events` (unless the store announces it to every node).
    pub(super) fn start(
        rt: &Handle,
        job: Option<Arc<PreparedJob>>,
        store: Store,
        id: &str,
        lease: &Lease,
        cancel: Arc<AtomicBool>,
        events: broadcast::Sender<Arc<str>>,
    ) -> Recorder {
        let (tx, mut rx) = mpsc::channel::<Batch>(QUEUE);
        let (id, lease) = (id.to_string(), lease.clone());
        let writer = rt.spawn(async move {
            let mut state = WriteState::default();
            let mut maker = FrameMaker::default();
            if let Some(job) = &job {
                let context = serde_json::to_vec(&GlbContext::of(job)).expect("contexts serialize");
                if let Err(e) = retrying(|| store.put_context(&id, context.clone())).await {
                    state.error = Some(e.to_string());
                    cancel.store(true, Ordering::Relaxed);
                }
            }
            while let Some(first) = rx.recv().await {
                // the batches that queued while the last one was written go together,
                // in one transaction: a writer that falls behind catches up
                let mut rows = first.rows;
                let mut pending: Vec<Pending> = first.checkpoint.into_iter().collect();
                while let Ok(b) = rx.try_recv() {
                    rows.extend(b.rows);
                    pending.extend(b.checkpoint);
                }
                if state.lost || state.error.is_some() {
                    continue; // drain: nothing more is written
                }
                let (mut made, mut states) = (Vec::new(), Vec::new());
                for p in pending {
                    match p {
                        Pending::Made(m) => made.push(m),
                        Pending::State(c) => states.push(c),
                    }
                }
                let mut frames = Vec::new();
                if let (Some(job), false) = (&job, states.is_empty()) {
                    let (job, mut making) = (job.clone(), std::mem::take(&mut maker));
                    let fields = move || {
                        let frames = states.iter().map(|cp| making.make(&job, cp)).collect::<Vec<_>>();
                        (frames, making)
                    };
                    match tokio::task::spawn_blocking(fields).await {
                        Ok((f, made_by)) => {
                            maker = made_by;
                            frames = f;
                        }
                        Err(e) => {
                            state.error = Some(format!("the fields of a checkpoint: {e}"));
                            cancel.store(true, Ordering::Relaxed);
                            continue;
                        }
                    }
                }
                made.extend(frames.iter().map(MadeFrame::of));
                match retrying(|| store.record_made(&id, &lease, &rows, &made)).await {
                    Ok(cancelled) => {
                        frames.into_iter().for_each(|f| state.frames.push(f));
                        if !store.announces() {
                            let _ = events.send(Arc::from(id.as_str()));
                        }
                        if cancelled {
                            cancel.store(true, Ordering::Relaxed);
                        }
                    }
                    Err(StoreError::LeaseLost(_)) => {
                        state.lost = true;
                        cancel.store(true, Ordering::Relaxed);
                    }
                    Err(e) => {
                        state.error = Some(e.to_string());
                        cancel.store(true, Ordering::Relaxed);
                    }
                }
            }
            state
        });
        Recorder {
            rt: rt.clone(),
            rows: Vec::new(),
            thinning: Thinning::default(),
            last_flush: Instant::now(),
            queue: Some(tx),
            writer: Some(writer),
        }
    }

    /// Write the rows that wait, if the last write is older than a batch's time.
    pub(super) fn flush_due(&mut self) {
        if !self.rows.is_empty() && self.last_flush.elapsed() > BATCH_TIME {
            self.flush(None);
        }
    }

    /// A checkpoint whose frame the job's process made.
    pub(super) fn made_checkpoint(&mut self, frame: MadeFrame) {
        self.flush(Some(Pending::Made(frame)));
    }

    fn flush(&mut self, checkpoint: Option<Pending>) {
        let rows = std::mem::take(&mut self.rows);
        if let Some(q) = &self.queue {
            // fails only if the writer ended, which it does not before `close`
            let _ = q.blocking_send(Batch { rows, checkpoint });
        }
        self.last_flush = Instant::now();
    }

    /// Write what is left, wait for the writer, and say how the writes went.
    pub(super) fn close(mut self) -> WriteState {
        self.rows.extend(self.thinning.last_skipped());
        if !self.rows.is_empty() {
            self.flush(None);
        }
        self.queue = None;
        let writer = self.writer.take().expect("closed once");
        self.rt
            .block_on(writer)
            .unwrap_or_else(|e| WriteState { error: Some(format!("the writer stopped: {e}")), ..WriteState::default() })
    }
}

impl RunEvents for Recorder {
    fn progress(&mut self, p: &Progress) {
        if self.thinning.keep(p) {
            self.rows.push(*p);
        }
        if self.rows.len() >= 256 || self.last_flush.elapsed() > BATCH_TIME {
            self.flush(None);
        }
    }
    fn checkpoint(&mut self, c: &Checkpoint) {
        self.flush(Some(Pending::State(c.clone())));
    }
}
