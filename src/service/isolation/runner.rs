//! Job processes started ahead: starting `shapeflow job-runner` (exec, the
//! loader, the runtime) costs about 1.7 ms, twice per job (its validation and
//! its run). A [`Runner`] keeps up to two processes started and waiting for
//! their request on standard input, so that a job takes one at once; a thread of
//! its own starts the next. The waiting processes hold no budget yet: each
//! limits its memory when its request says how much ([`Request::memory`]).
//!
//! The starting thread lives as long as the runner: the kernel's parent-death
//! signal (`PR_SET_PDEATHSIG`) follows the thread that started a process, so a
//! process started by a short-lived thread would be killed when that thread ends.
//!
//! [`Request::memory`]: super::protocol::Request::memory

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::{Arc, Mutex};

/// Starts job processes of `exe`, some of them ahead (see the module).
#[derive(Clone)]
pub struct Runner {
    exe: PathBuf,
    ready: Arc<Mutex<Option<Receiver<Child>>>>,
}

impl std::fmt::Debug for Runner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Runner({})", self.exe.display())
    }
}

impl PartialEq for Runner {
    fn eq(&self, other: &Runner) -> bool {
        self.exe == other.exe
    }
}

impl Eq for Runner {}

impl Runner {
    /// A runner of `exe job-runner`; processes are started ahead only once
    /// [`Runner::ahead`] is called (a service's workers and validations).
    pub fn new(exe: PathBuf) -> Runner {
        Runner { exe, ready: Arc::new(Mutex::new(None)) }
    }

    pub fn exe(&self) -> &Path {
        &self.exe
    }

    /// Start keeping processes ready, on a thread that lives as long as this
    /// runner's clones do (it ends, and kills the process it holds, when the last
    /// one is dropped).
    pub fn ahead(&self) -> std::io::Result<()> {
        let mut ready = self.ready.lock().unwrap_or_else(|e| e.into_inner());
        if ready.is_some() {
            return Ok(());
        }
        // one waiting in the channel, one more held by the thread
        let (send, receive) = sync_channel::<Child>(1);
        let exe = self.exe.clone();
        std::thread::Builder::new().name("job-runner-ahead".into()).spawn(move || loop {
            let child = match spawn(&exe) {
                Ok(c) => c,
                Err(e) => {
                    tracing::warn!("cannot start a job process ahead: {e}");
                    return;
                }
            };
            if let Err(refused) = send.send(child) {
                let mut child = refused.0;
                let _ = child.kill();
                let _ = child.wait();
                return;
            }
        })?;
        *ready = Some(receive);
        Ok(())
    }

    /// A job process waiting for its request: one started ahead if there is one,
    /// else one started now.
    pub fn start(&self) -> std::io::Result<Child> {
        let ahead = self.ready.lock().unwrap_or_else(|e| e.into_inner()).as_ref().and_then(|r| r.try_recv().ok());
        match ahead {
            // (one that has ended meanwhile is not used)
            Some(mut child) => match child.try_wait() {
                Ok(None) => Ok(child),
                _ => spawn(&self.exe),
            },
            None => spawn(&self.exe),
        }
    }
}

fn spawn(exe: &Path) -> std::io::Result<Child> {
    Command::new(exe).arg("job-runner").stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn()
}
