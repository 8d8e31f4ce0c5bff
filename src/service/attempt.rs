//! One attempt at a claimed job: on the worker's thread (a panic caught and
//! turned into an abandoned attempt) or in a process of its own
//! ([`super::isolation`]), its history and checkpoints written by a
//! [`Recorder`] either way. What the worker does with the end is in
//! [`super::worker`].

use super::isolation::child::panic_text;
use super::isolation::fault::Fault;
use super::isolation::parent::{JobProcess, Next, ProcessEnd};
use super::isolation::protocol::{Report, Request, RunEnd};
use super::isolation::Runner;
use super::recorder::{retrying, Recorder};
use super::store::{JobRow, Lease, MadeFrame, StoreError, Which};
use super::worker::{Attempt, AttemptEnd, Results, Worker};
use crate::flow::{Checkpoint, Progress, StopReason};
use crate::jobs::{parse_spec, prepare, run_prepared, ResultFile, RunEvents};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// How long a job's process may be quiet before the rows it reported are written.
const QUIET: std::time::Duration = std::time::Duration::from_millis(250);

impl Worker {
    /// The attempt on this thread.
    pub(super) fn in_thread(
        &self,
        job: &JobRow,
        lease: &Lease,
        cancel: &Arc<AtomicBool>,
        fault: Option<String>,
    ) -> Result<Attempt, StoreError> {
        let inputs = self.rt.block_on(self.store.inputs(&job.id))?;
        let prepared = match parse_spec(&job.spec).and_then(|s| prepare(s, &inputs)) {
            Ok(p) => Arc::new(p),
            Err(e) => return Ok(Attempt::ended(AttemptEnd::Failed(e.to_string()))),
        };
        drop(inputs);
        // the frames stored so far (a takeover), for evolution.glb, read one at a time
        let mut kept = self.rt.block_on(self.store.kept_frames(&job.id))?;
        let resume = kept.last().map(|f| f.state.clone());
        if let Some(cp) = &resume {
            self.rt.block_on(self.store.truncate_history(&job.id, lease, cp.iteration))?;
            tracing::info!(job = %job.id, iteration = cp.iteration, "resuming from checkpoint");
        }
        let mut rec = Recorder::start(
            &self.rt,
            Some(prepared.clone()),
            self.store.clone(),
            &job.id,
            lease,
            cancel.clone(),
            self.events.clone(),
        );
        let fault = fault.as_deref().and_then(Fault::parse).filter(|f| !(f.once && resume.is_some()));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match fault {
            Some(fault) => run_prepared(&prepared, resume.as_ref(), cancel, &mut Faulty { events: &mut rec, fault }),
            None => run_prepared(&prepared, resume.as_ref(), cancel, &mut rec),
        }));
        let mut written = rec.close();
        let end = match result {
            Err(panic) => AttemptEnd::Crashed(format!("panicked: {}", panic_text(panic.as_ref()))),
            Ok(Ok(o)) if o.stop == StopReason::Cancelled => AttemptEnd::Cancelled,
            Ok(Ok(o)) => AttemptEnd::Stopped { stop: o.stop.as_str().into(), note: o.note.map(String::from) },
            Ok(Err(f)) => AttemptEnd::Failed(f.error.to_string()),
        };
        // a resumed run's first frame repeats the last one stored before
        let resumed_at = resume.map(|c| c.iteration);
        let frames = std::mem::take(&mut written.frames).into_frames();
        frames.into_iter().filter(|f| Some(f.state.iteration) != resumed_at).for_each(|f| kept.push(f));
        Ok(Attempt { end, written, results: Results::Frames(prepared, kept.into_frames()), needed: 0 })
    }

    /// The attempt in a process of its own (`exe job-runner`).
    pub(super) fn in_process(
        &self,
        runner: &Runner,
        job: &JobRow,
        lease: &Lease,
        cancel: &Arc<AtomicBool>,
        fault: Option<String>,
    ) -> Result<Attempt, StoreError> {
        let store = &self.store;
        let inputs = self.rt.block_on(store.input_rows(&job.id))?;
        let stored = self.rt.block_on(store.checkpoint_count(&job.id))?;
        if let Some(last) = self.rt.block_on(store.checkpoint_rows(&job.id, Which::Last))?.pop() {
            self.rt.block_on(store.truncate_history(&job.id, lease, last.iteration as usize))?;
            tracing::info!(job = %job.id, iteration = last.iteration, "resuming from checkpoint");
        }
        let request = Request {
            spec: job.spec.clone(),
            inputs: inputs.iter().map(|r| r.name.clone()).collect(),
            resume: stored > 0,
            prior_frames: stored,
            validate_only: false,
            memory: None,
            fault,
        };
        // the server's budgets, lowered to what the spec's `limits` ask for
        let asked = parse_spec(&job.spec).ok().and_then(|s| s.limits.resolve().ok()).unwrap_or_default();
        // what the earlier attempts stored counts against the disk budget too
        let stored = self.rt.block_on(store.stored_bytes(&job.id))?;
        let budgets = self.budgets.within(asked).within_quota(self.key_room(job)?);
        let mut process = match JobProcess::start(runner, budgets, &job.id, stored, cancel.clone()) {
            Ok(p) => p,
            Err(e) => return Ok(Attempt::ended(AttemptEnd::Crashed(format!("the job's process cannot start: {e}")))),
        };
        // the payloads one at a time, read from the store as they are sent (the
        // checkpoints a page of rows at a time)
        let mut inputs = inputs.into_iter();
        let (mut page, mut after) = (Vec::new().into_iter(), -1);
        let mut failed_read = None;
        let mut payloads = || -> Option<Vec<u8>> {
            let got = if let Some(row) = inputs.next() {
                match row.in_blob {
                    true => self
                        .rt
                        .block_on(store.blobs().get_existing(&super::blobs::input_key(&job.id, &row.name)))
                        .map_err(StoreError::from),
                    false => Ok(row.data),
                }
            } else {
                if page.len() == 0 {
                    match self.rt.block_on(store.checkpoint_rows(&job.id, Which::After(after))) {
                        Ok(rows) => page = rows.into_iter(),
                        Err(e) => {
                            failed_read = Some(e);
                            return None;
                        }
                    }
                }
                let row = page.next()?;
                after = row.iteration;
                self.rt.block_on(store.frame_json(&job.id, row))
            };
            got.map_err(|e| failed_read = Some(e)).ok()
        };
        let sent = process.send(&request, &mut payloads);
        if let Some(e) = failed_read {
            drop(process);
            return Err(e);
        }
        if let Err(e) = sent {
            tracing::debug!(job = %job.id, "the job's process took no request: {e}");
        }
        let mut rec =
            Recorder::start(&self.rt, None, store.clone(), &job.id, lease, cancel.clone(), self.events.clone());
        let (mut files, mut reported, mut context_error) = (Vec::new(), None, None);
        loop {
            let (report, payload) = match process.next(QUIET) {
                Next::Report(r, p) => (r, p),
                // a long step: the rows of the steps before it go now
                Next::Quiet => {
                    rec.flush_due();
                    continue;
                }
                Next::End => break,
            };
            match report {
                Report::Context => {
                    if let Err(e) = self.rt.block_on(retrying(|| store.put_context(&job.id, payload.clone()))) {
                        context_error = Some(e.to_string());
                        cancel.store(true, std::sync::atomic::Ordering::Relaxed);
                    }
                }
                Report::Progress(p) => rec.progress(&p),
                Report::Checkpoint { iteration, time } => {
                    rec.made_checkpoint(MadeFrame { iteration, time, json: payload })
                }
                Report::File { name, media_type } => {
                    files.push(ResultFile { name: name.into(), media_type: media_type.into(), bytes: payload })
                }
                Report::Outcome(end) => reported = Some(end),
            }
        }
        let mut written = rec.close();
        if written.error.is_none() {
            written.error = context_error;
        }
        let needed = process.stored();
        let end = match process.finish(reported) {
            ProcessEnd::Reported(RunEnd::Stopped { stop, note }) => AttemptEnd::Stopped { stop, note },
            ProcessEnd::Reported(RunEnd::Cancelled) | ProcessEnd::Cancelled => AttemptEnd::Cancelled,
            ProcessEnd::Reported(RunEnd::Failed { message }) => AttemptEnd::Failed(message),
            ProcessEnd::Reported(RunEnd::Panicked { message }) => AttemptEnd::Crashed(format!("panicked: {message}")),
            ProcessEnd::OverBudget(why) => AttemptEnd::Failed(format!("the job {why}")),
            ProcessEnd::Died(why) => AttemptEnd::Crashed(why),
            ProcessEnd::Reported(other @ (RunEnd::Valid | RunEnd::Invalid { .. })) => {
                AttemptEnd::Crashed(format!("the job's process answered as a validation: {other:?}"))
            }
        };
        Ok(Attempt { end, written, results: Results::Files(files), needed })
    }
}

/// Events passed on, with a fault committed on the way (tests of isolation).
struct Faulty<'a> {
    events: &'a mut dyn RunEvents,
    fault: Fault,
}

impl RunEvents for Faulty<'_> {
    fn progress(&mut self, p: &Progress) {
        self.events.progress(p);
        self.fault.strike(p.iteration);
    }
    fn checkpoint(&mut self, c: &Checkpoint) {
        self.events.checkpoint(c);
    }
}
