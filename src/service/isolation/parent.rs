//! A worker's side of a job's process: start it (`shapeflow job-runner`), send
//! it the job, read its reports, watch its budgets and cancellation, and say how
//! it ended. The worker keeps the database, the blob store and the lease; the
//! process only computes.

use super::protocol::{read_message, write_message, Control, Report, Request, RunEnd};
use super::runner::Runner;
use super::Budgets;
use crate::flow::Progress;
use crate::service::store::HISTORY_ROW_BYTES;
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, BufWriter};
use std::process::{ChildStdin, ChildStdout, ExitStatus};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How long a cancelled process has to write its last checkpoint and result
/// files before it is killed.
const CANCEL_GRACE: Duration = Duration::from_secs(5);

/// The lines of the process's standard error kept to tell why it ended.
const STDERR_LINES: usize = 20;

/// Why the worker killed a job's process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kill {
    Cancelled,
    Time,
    Disk,
}

/// What [`JobProcess::next`] found.
pub enum Next {
    Report(Report, Vec<u8>),
    /// Nothing for a while: the process is in a long step.
    Quiet,
    /// The process has stopped reporting.
    End,
}

/// A job's running process.
pub struct JobProcess {
    child: std::process::Child,
    reports: std::sync::mpsc::Receiver<(Report, Vec<u8>)>,
    shared: Arc<Shared>,
    /// Dropped when the process has ended: the watchdog stops at once.
    ended: Option<std::sync::mpsc::Sender<()>>,
    watchdog: Option<std::thread::JoinHandle<()>>,
    stderr: Option<std::thread::JoinHandle<VecDeque<String>>>,
    budgets: Budgets,
    last_iteration: usize,
}

/// What the watchdog and the reader share.
struct Shared {
    stdin: Mutex<Option<BufWriter<ChildStdin>>>,
    cancel: Arc<AtomicBool>,
    disk: AtomicU64,
    killed: Mutex<Option<Kill>>,
}

impl Shared {
    /// Kill the process `pid` for `why`, unless it was killed already. Called
    /// only before the process is waited for (by the watchdog, which runs until
    /// then, and by [`JobProcess::next`]), so that its pid cannot be reused.
    fn kill(&self, pid: u32, why: Kill) {
        let mut killed = self.killed.lock().unwrap();
        if killed.is_none() {
            *killed = Some(why);
            #[cfg(unix)]
            // SAFETY: kill(2) of our own child, not yet waited for (see above).
            unsafe {
                libc::kill(pid as libc::pid_t, libc::SIGKILL);
            }
        }
    }
}

/// How a job's process ended.
#[derive(Debug, Clone, PartialEq)]
pub enum ProcessEnd {
    /// It reported how its run ended.
    Reported(RunEnd),
    /// It was stopped by a cancellation before it reported.
    Cancelled,
    /// It went past a budget: the job fails with this message.
    OverBudget(String),
    /// It died without reporting (a signal, an abort): this attempt ends.
    Died(String),
}

impl JobProcess {
    /// Start `exe job-runner` under `budgets`, its log lines forwarded to this
    /// process's log under `job`, `stored` bytes of the job already stored by its
    /// earlier attempts (counted against its disk budget); `cancel` (the job's
    /// flag) stops it.
    pub fn start(
        runner: &Runner,
        budgets: Budgets,
        job: &str,
        stored: u64,
        cancel: Arc<AtomicBool>,
    ) -> std::io::Result<JobProcess> {
        let mut child = runner.start()?;
        let stdin = BufWriter::with_capacity(1 << 16, child.stdin.take().expect("piped"));
        let stdout = BufReader::with_capacity(1 << 16, child.stdout.take().expect("piped"));
        let reports = read_reports(stdout)?;
        let stderr = child.stderr.take().expect("piped");
        let id = job.to_string();
        let stderr = std::thread::Builder::new().name("job-stderr".into()).spawn(move || {
            let mut tail = VecDeque::new();
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                tracing::info!(job = %id, "{line}");
                if tail.len() == STDERR_LINES {
                    tail.pop_front();
                }
                tail.push_back(line);
            }
            tail
        })?;
        let shared = Arc::new(Shared {
            stdin: Mutex::new(Some(stdin)),
            cancel,
            disk: AtomicU64::new(stored),
            killed: Mutex::new(None),
        });
        let (ended, wait) = std::sync::mpsc::channel();
        let watchdog = {
            let (shared, pid) = (shared.clone(), child.id());
            std::thread::Builder::new().name("job-watchdog".into()).spawn(move || watch(&shared, pid, budgets, wait))?
        };
        Ok(JobProcess {
            child,
            reports,
            shared,
            ended: Some(ended),
            watchdog: Some(watchdog),
            stderr: Some(stderr),
            budgets,
            last_iteration: 0,
        })
    }

    /// Send the request and its payloads (each from `payloads`, in order). An
    /// error means the process is gone; [`JobProcess::finish`] says why.
    pub fn send(&self, request: &Request, payloads: &mut dyn FnMut() -> Option<Vec<u8>>) -> std::io::Result<()> {
        let mut stdin = self.shared.stdin.lock().unwrap();
        let w = stdin.as_mut().expect("open until the end");
        // the process limits its memory to the budget as it reads this
        write_message(w, &Request { memory: self.budgets.memory, ..request.clone() }, &[])?;
        while let Some(p) = payloads() {
            write_message(w, &(), &p)?;
        }
        Ok(())
    }

    /// The next report, waiting at most `quiet` for it.
    pub fn next(&mut self, quiet: Duration) -> Next {
        let (report, payload) = match self.reports.recv_timeout(quiet) {
            Ok(m) => m,
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => return Next::Quiet,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return Next::End,
        };
        let bytes = match &report {
            Report::Progress(Progress { iteration, .. }) => {
                self.last_iteration = *iteration;
                HISTORY_ROW_BYTES
            }
            _ => payload.len() as u64,
        };
        let stored = self.shared.disk.fetch_add(bytes, Ordering::Relaxed) + bytes;
        // over the disk budget: killed now, this report not kept (a cancelled
        // process ends as cancelled, with its last files)
        if self.budgets.disk.is_some_and(|d| stored > d) && !self.shared.cancel.load(Ordering::Relaxed) {
            self.shared.kill(self.child.id(), Kill::Disk);
            return Next::End;
        }
        Next::Report(report, payload)
    }

    /// The bytes the job stored or tried to store: what it stored before, and
    /// what it reported since (the report that passed its disk budget too).
    pub fn stored(&self) -> u64 {
        self.shared.disk.load(Ordering::Relaxed)
    }

    /// Wait for the process to end and say how it did; `reported`: its outcome,
    /// if it sent one.
    pub fn finish(mut self, reported: Option<RunEnd>) -> ProcessEnd {
        // the end of its input: a process still running sees a cancellation
        self.shared.stdin.lock().unwrap().take();
        let status = self.child.wait();
        self.ended.take();
        if let Some(w) = self.watchdog.take() {
            let _ = w.join();
        }
        let tail = self.stderr.take().and_then(|t| t.join().ok()).unwrap_or_default();
        let killed = *self.shared.killed.lock().unwrap();
        let at = self.last_iteration;
        let b = self.budgets;
        match (killed, reported) {
            (Some(Kill::Time), _) => ProcessEnd::OverBudget(format!(
                "exceeded its time budget of {} s at iteration {at}",
                b.seconds.map_or(0.0, |s| s.as_secs_f64())
            )),
            (Some(Kill::Disk), _) if b.disk_is_quota => ProcessEnd::OverBudget(format!(
                "reached its key's storage quota at iteration {at} ({} were left of it for this job)",
                super::format_size(b.disk.unwrap_or(0))
            )),
            (Some(Kill::Disk), _) => ProcessEnd::OverBudget(format!(
                "exceeded its disk budget of {} at iteration {at}",
                super::format_size(b.disk.unwrap_or(0))
            )),
            (_, Some(end)) => ProcessEnd::Reported(end),
            (Some(Kill::Cancelled), None) => ProcessEnd::Cancelled,
            (None, None) => {
                if tail.iter().any(|l| l.contains("memory allocation of")) {
                    let budget = b.memory.map_or("its memory budget".into(), |m| {
                        format!("its memory budget of {}", super::format_size(m))
                    });
                    return ProcessEnd::OverBudget(format!("exceeded {budget} at iteration {at}"));
                }
                ProcessEnd::Died(died(status, at))
            }
        }
    }
}

/// A thread reading the process's reports as they come (a few wait, then the
/// process waits for its worker).
fn read_reports(mut stdout: BufReader<ChildStdout>) -> std::io::Result<std::sync::mpsc::Receiver<(Report, Vec<u8>)>> {
    let (tx, rx) = std::sync::mpsc::sync_channel(16);
    std::thread::Builder::new().name("job-reports".into()).spawn(move || loop {
        match read_message::<Report>(&mut stdout) {
            Ok(Some(m)) => {
                if tx.send(m).is_err() {
                    return;
                }
            }
            Ok(None) => return,
            Err(e) => {
                tracing::debug!("a job's reports ended: {e}");
                return;
            }
        }
    })?;
    Ok(rx)
}

/// Why a process that did not report ended.
fn died(status: std::io::Result<ExitStatus>, at: usize) -> String {
    let status = match status {
        Ok(s) => s,
        Err(e) => return format!("the job's process could not be waited for ({e}) at iteration {at}"),
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            let name = match sig {
                libc::SIGKILL => " (SIGKILL)",
                libc::SIGABRT => " (SIGABRT, an abort)",
                libc::SIGSEGV => " (SIGSEGV)",
                libc::SIGTERM => " (SIGTERM)",
                libc::SIGBUS => " (SIGBUS)",
                _ => "",
            };
            return format!("the job's process was killed by signal {sig}{name} at iteration {at}");
        }
    }
    match status.code() {
        Some(0) | None => format!("the job's process ended without reporting an outcome at iteration {at}"),
        Some(c) => format!("the job's process exited with status {c} at iteration {at}"),
    }
}

/// Every 50 ms until the process ends (`ended` closes): pass on a cancellation
/// (and kill the process if it is still there [`CANCEL_GRACE`] later), and kill
/// it past its time or disk budget.
fn watch(shared: &Shared, pid: u32, budgets: Budgets, ended: std::sync::mpsc::Receiver<()>) {
    let started = Instant::now();
    let mut cancelled_at: Option<Instant> = None;
    let kill = |why: Kill| shared.kill(pid, why);
    while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = ended.recv_timeout(Duration::from_millis(50)) {
        // a cancelled process is not killed for its budgets: it ends as cancelled
        if cancelled_at.is_none() && budgets.seconds.is_some_and(|s| started.elapsed() > s) {
            kill(Kill::Time);
        }
        if cancelled_at.is_none() && budgets.disk.is_some_and(|d| shared.disk.load(Ordering::Relaxed) > d) {
            kill(Kill::Disk);
        }
        if shared.cancel.load(Ordering::Relaxed) {
            match cancelled_at {
                None => {
                    cancelled_at = Some(Instant::now());
                    if let Some(w) = shared.stdin.lock().unwrap().as_mut() {
                        let _ = write_message(w, &Control::Cancel, &[]);
                    }
                }
                Some(t) if t.elapsed() > CANCEL_GRACE => kill(Kill::Cancelled),
                Some(_) => {}
            }
        }
    }
}

impl Drop for JobProcess {
    fn drop(&mut self) {
        // not finished (a panic of the worker): no process is left behind
        if self.watchdog.is_some() {
            let _ = self.child.kill();
            let _ = self.child.wait();
            self.ended.take();
        }
    }
}

/// Why a submission is refused by its validation in a process of its own.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    pub field: String,
    pub message: String,
}

/// Validate a submission (`spec`, its `inputs`) in a process of its own under
/// `budgets.memory`: `Ok` if the job prepares. An input that needs more memory
/// to prepare than the budget is refused naming `problem.image` (or the first
/// input) and the budget.
pub fn validate(
    runner: &Runner,
    budgets: Budgets,
    spec: &str,
    inputs: &std::collections::HashMap<String, Vec<u8>>,
) -> std::io::Result<Result<(), Refusal>> {
    let budgets = Budgets { disk: None, ..budgets };
    let mut process = JobProcess::start(runner, budgets, "(validation)", 0, Arc::new(AtomicBool::new(false)))?;
    let names: Vec<&String> = inputs.keys().collect();
    let request = Request {
        spec: spec.to_string(),
        inputs: names.iter().map(|n| n.to_string()).collect(),
        resume: false,
        prior_frames: 0,
        validate_only: true,
        memory: None,
        fault: None,
    };
    let mut queue = names.iter();
    let _ = process.send(&request, &mut || queue.next().map(|n| inputs[*n].clone()));
    let mut reported = None;
    let end = loop {
        match process.next(Duration::from_secs(1)) {
            // the answer: the process ends (and is waited for) on its own
            Next::Report(Report::Outcome(end @ (RunEnd::Valid | RunEnd::Invalid { .. })), _) => {
                std::thread::spawn(move || drop(process.finish(None)));
                break ProcessEnd::Reported(end);
            }
            Next::Report(Report::Outcome(end), _) => reported = Some(end),
            Next::Report(..) | Next::Quiet => {}
            Next::End => break process.finish(reported),
        }
    };
    match end {
        ProcessEnd::Reported(RunEnd::Valid) => Ok(Ok(())),
        ProcessEnd::Reported(RunEnd::Invalid { field, message }) => Ok(Err(Refusal { field, message })),
        ProcessEnd::OverBudget(_) => {
            let field = if inputs.is_empty() { "initial" } else { "problem.image" };
            let budget = budgets.memory.map_or("the memory budget".into(), |m| {
                format!("the job's memory budget of {}", super::format_size(m))
            });
            Ok(Err(Refusal { field: field.into(), message: format!("needs more memory to prepare than {budget}") }))
        }
        other => Err(std::io::Error::other(format!("the validation ended unexpectedly: {other:?}"))),
    }
}
