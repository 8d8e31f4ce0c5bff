//! The process of one job (`shapeflow job-runner`, started by a worker under
//! process isolation): it reads its [`Request`] from standard input, limits its
//! own data segment to the job's memory budget (`RLIMIT_DATA`, which the kernel
//! enforces: an allocation past it fails and the process aborts), prepares and
//! runs the job, and reports its history rows, checkpoints (each made into its
//! frame on a second thread), result files and outcome on standard output
//! ([`super::protocol`]). A [`Control::Cancel`], or the end of its standard input
//! (the worker is gone), stops the run at its next step; the kernel ends the
//! process with its parent's (`PR_SET_PDEATHSIG`). Nothing else is written to
//! standard output; logs go to standard error, which the worker reads.

use super::fault::Fault;
use super::protocol::{read_message, write_message, Control, Report, Request, RunEnd};
use crate::flow::{Checkpoint, Progress};
use crate::jobs::{
    parse_spec, prepare, result_files, run_prepared, Frame, FrameMaker, GlbContext, KeptFrames, MemoryEstimate,
    RunEvents, FRAMES_AHEAD,
};
use std::collections::HashMap;
use std::io::{BufWriter, Read, Stdout};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// Run the job the worker sends on standard input; `memory`: its budget in bytes.
pub fn job_runner(memory: Option<u64>) -> ExitCode {
    die_with_parent();
    if let Err(e) = limit_memory(memory) {
        eprintln!("cannot set the memory budget: {e}");
        return ExitCode::from(3);
    }
    warm_up();
    let mut stdin = std::io::stdin();
    let (mut request, inputs, resume, prior) = match read_request(&mut stdin) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("cannot read the job's request: {e}");
            return ExitCode::from(3);
        }
    };
    request.memory = request.memory.or(memory);
    name_process();
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    std::thread::spawn(move || {
        // a cancel, or the worker gone: stop at the next step
        let _ = read_message::<Control>(&mut stdin);
        flag.store(true, Ordering::Relaxed);
    });
    let out = Reports { out: Mutex::new(BufWriter::new(std::io::stdout())), cancel: cancel.clone() };
    let fault = request.fault.as_deref().and_then(Fault::parse).filter(|f| !(f.once && resume.is_some()));
    let end = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run(&request, &inputs, resume, prior, &cancel, &out, fault)
    }))
    .unwrap_or_else(|panic| RunEnd::Panicked { message: panic_text(panic.as_ref()) });
    out.send(&Report::Outcome(end), &[]);
    ExitCode::SUCCESS
}

/// Named `shapeflow-job` once it has its job (`ps`, `/proc/PID/comm`), apart
/// from the processes started ahead that wait for theirs.
fn name_process() {
    #[cfg(target_os = "linux")]
    // SAFETY: prctl(PR_SET_NAME) copies at most 16 bytes of the NUL-ended name.
    unsafe {
        libc::prctl(libc::PR_SET_NAME, c"shapeflow-job".as_ptr());
    }
}

/// The kernel ends this process with the worker's (Linux); if the worker is
/// already gone, end now.
fn die_with_parent() {
    #[cfg(target_os = "linux")]
    // SAFETY: prctl(PR_SET_PDEATHSIG) only sets this process's parent-death signal.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
    }
    #[cfg(unix)]
    if std::os::unix::process::parent_id() == 1 {
        std::process::exit(3);
    }
}

type Inputs = HashMap<String, Vec<u8>>;

/// A small job prepared and run for one step while the process waits for its
/// own (it is started ahead of its job: `super::runner`), so that the code and
/// the allocator's first pages are in place when the job comes.
fn warm_up() {
    const SPEC: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0,
        "resolution": 16}, "flow": {"tau": 1e-3, "max_iterations": 1}}"#;
    if let Ok(job) = parse_spec(SPEC).and_then(|s| prepare(s, &HashMap::new())) {
        if let Ok(outcome) = run_prepared(&job, None, &AtomicBool::new(false), &mut ()) {
            let frame = FrameMaker::default().make(&job, &outcome.last);
            let _ = serde_json::to_vec(&frame);
            let _ = result_files(&job, &[frame]);
        }
    }
}

/// This process's data segment limited to `bytes` (the kernel enforces it: an
/// allocation past it fails and the process aborts).
fn limit_memory(bytes: Option<u64>) -> std::io::Result<()> {
    match bytes {
        Some(b) => rlimit::setrlimit(rlimit::Resource::DATA, b, b),
        None => Ok(()),
    }
}

/// The request, under its memory budget from then on; its inputs; the stored
/// frames, read into [`KeptFrames`] one at a time; the checkpoint to resume from.
fn read_request(r: &mut impl Read) -> std::io::Result<(Request, Inputs, Option<Checkpoint>, KeptFrames)> {
    let bad = |what: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string());
    let (request, _): (Request, _) = read_message(r)?.ok_or_else(|| bad("no request"))?;
    limit_memory(request.memory)?;
    let mut next = || -> std::io::Result<Vec<u8>> {
        read_message::<()>(r)?.map(|(_, payload)| payload).ok_or_else(|| bad("the request ended early"))
    };
    let mut inputs = HashMap::new();
    for name in &request.inputs {
        inputs.insert(name.clone(), next()?);
    }
    let mut prior = KeptFrames::default();
    for _ in 0..request.prior_frames {
        prior.push(serde_json::from_slice(&next()?).map_err(|e| bad(&format!("a stored frame: {e}")))?);
    }
    let resume = prior.last().filter(|_| request.resume).map(|f| f.state.clone());
    Ok((request, inputs, resume, prior))
}

/// The reports, written one message at a time by the run's threads; a write that
/// fails (the worker is gone) stops the run.
struct Reports {
    out: Mutex<BufWriter<Stdout>>,
    cancel: Arc<AtomicBool>,
}

impl Reports {
    fn send(&self, report: &Report, payload: &[u8]) {
        let mut out = self.out.lock().unwrap_or_else(|e| e.into_inner());
        if write_message(&mut *out, report, payload).is_err() {
            self.cancel.store(true, Ordering::Relaxed);
        }
    }
}

fn run(
    request: &Request,
    inputs: &Inputs,
    resume: Option<Checkpoint>,
    prior: KeptFrames,
    cancel: &AtomicBool,
    out: &Reports,
    fault: Option<Fault>,
) -> RunEnd {
    let job = match parse_spec(&request.spec).and_then(|s| prepare(s, inputs)) {
        Ok(job) if request.validate_only => {
            return match request.memory.map(|budget| MemoryEstimate::of(&job).check(budget)) {
                Some(Err((field, message))) => RunEnd::Invalid { field: field.into(), message },
                _ => RunEnd::Valid,
            }
        }
        Ok(job) => job,
        Err(e) if request.validate_only => return RunEnd::Invalid { field: e.field, message: e.message },
        Err(e) => return RunEnd::Failed { message: e.to_string() },
    };
    out.send(&Report::Context, &serde_json::to_vec(&GlbContext::of(&job)).expect("contexts serialize"));
    let mut kept = prior;
    // a resumed run's first checkpoint repeats the last one stored before
    let resumed_at = kept.last().map(|f| f.state.iteration);
    let sent = std::sync::atomic::AtomicUsize::new(0);
    let (result, mut kept) = std::thread::scope(|scope| {
        let (send, receive) = std::sync::mpsc::sync_channel::<Checkpoint>(FRAMES_AHEAD);
        let sent = &sent;
        let job = &job;
        let maker = scope.spawn(move || {
            let mut maker = FrameMaker::default();
            for c in receive {
                let frame = maker.make(job, &c);
                let json = serde_json::to_vec(&frame).expect("frames serialize");
                out.send(&Report::Checkpoint { iteration: c.iteration, time: c.time }, &json);
                sent.fetch_add(1, Ordering::Release);
                if Some(c.iteration) != resumed_at {
                    kept.push(frame);
                }
            }
            kept
        });
        let mut events = Events { out, frames: send, fault, handed: 0, sent };
        let result = run_prepared(job, resume.as_ref(), cancel, &mut events);
        drop(events);
        (result, maker.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
    });
    let last = match &result {
        Ok(o) => &o.last,
        Err(f) => &f.last,
    };
    if kept.last().map(|f| &f.state) != Some(last) {
        kept.push(Frame::of_run(&job, last).with_fill());
    }
    for file in result_files(&job, &kept.into_frames()) {
        out.send(&Report::File { name: file.name.into(), media_type: file.media_type.into() }, &file.bytes);
    }
    match result {
        Ok(o) if o.stop == crate::flow::StopReason::Cancelled => RunEnd::Cancelled,
        Ok(o) => RunEnd::Stopped { stop: o.stop.as_str().into(), note: o.note.map(String::from) },
        Err(f) => RunEnd::Failed { message: f.error.to_string() },
    }
}

struct Events<'a> {
    out: &'a Reports,
    frames: std::sync::mpsc::SyncSender<Checkpoint>,
    fault: Option<Fault>,
    /// Checkpoints handed to the frame maker, and those it has sent.
    handed: usize,
    sent: &'a std::sync::atomic::AtomicUsize,
}

impl RunEvents for Events<'_> {
    fn progress(&mut self, p: &Progress) {
        self.out.send(&Report::Progress(*p), &[]);
        if let Some(f) = self.fault.as_ref().filter(|f| f.due(p.iteration)) {
            // the checkpoints before the fault sent first (as a run that has
            // gone on for a while would have), so that a `:once` fault's
            // attempt after it resumes from them whatever the machine's load
            let waited = std::time::Instant::now();
            while self.sent.load(Ordering::Acquire) < self.handed && waited.elapsed().as_secs() < 30 {
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
            f.strike(p.iteration);
        }
    }

    fn checkpoint(&mut self, c: &Checkpoint) {
        if self.frames.send(c.clone()).is_ok() {
            self.handed += 1;
        }
    }
}

/// The message of a panic's payload.
pub(crate) fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}
