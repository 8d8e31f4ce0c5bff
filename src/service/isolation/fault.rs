//! Faults a job's run can be told to commit, for the tests of isolation only: a
//! service's configuration names them by the job's submission number
//! ([`crate::service::ServiceConfig::faults`]; `shapeflow serve` reads them from
//! `SHAPEFLOW_TEST_FAULTS` in debug builds only); no route, spec or flag reaches
//! them, so no client can crash a job on purpose.

/// `WHAT@N`: at iteration `N` (at least), do `WHAT`; `WHAT@N:once`: only in a
/// run from the start (not in one resumed from a checkpoint).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fault {
    what: What,
    at: usize,
    pub once: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum What {
    /// `panic!`.
    Panic,
    /// `std::process::abort()`.
    Abort,
    /// SIGKILL to itself (as the kernel's OOM killer or an operator would).
    Kill,
    /// Allocate and touch memory without end (until the budget stops it).
    Grow,
    /// Stop making progress (sleep forever, deaf to cancellation).
    Hang,
}

/// `SEQ=FAULT,...`: the faults to inject, by submission number (unreadable items
/// are left out).
pub fn by_submission(text: &str) -> Vec<(i64, String)> {
    text.split(',')
        .filter_map(|item| item.split_once('='))
        .filter_map(|(seq, fault)| Some((seq.trim().parse().ok()?, fault.trim().to_string())))
        .collect()
}

impl Fault {
    /// `panic@N`, `abort@N`, `kill@N`, `grow@N` or `hang@N`, each optionally
    /// followed by `:once`.
    pub fn parse(text: &str) -> Option<Fault> {
        let (text, once) = match text.strip_suffix(":once") {
            Some(t) => (t, true),
            None => (text, false),
        };
        let (what, at) = text.split_once('@')?;
        let what = match what {
            "panic" => What::Panic,
            "abort" => What::Abort,
            "kill" => What::Kill,
            "grow" => What::Grow,
            "hang" => What::Hang,
            _ => return None,
        };
        Some(Fault { what, at: at.parse().ok()?, once })
    }

    /// Whether the run is at the fault's iteration.
    pub fn due(&self, iteration: usize) -> bool {
        iteration >= self.at
    }

    /// Commit the fault if the run is at its iteration.
    pub fn strike(&self, iteration: usize) {
        if !self.due(iteration) {
            return;
        }
        match self.what {
            What::Panic => panic!("an injected fault at iteration {iteration}"),
            What::Abort => std::process::abort(),
            What::Kill => {
                #[cfg(unix)]
                // SAFETY: kill(2) of this process with SIGKILL.
                unsafe {
                    libc::kill(libc::getpid(), libc::SIGKILL);
                }
                std::process::abort();
            }
            What::Grow => {
                let mut held: Vec<Vec<u8>> = Vec::new();
                loop {
                    held.push(vec![1u8; 16 << 20]);
                    std::hint::black_box(&held);
                }
            }
            What::Hang => loop {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse_or_are_refused() {
        assert_eq!(Fault::parse("panic@3"), Some(Fault { what: What::Panic, at: 3, once: false }));
        assert_eq!(Fault::parse("kill@20:once"), Some(Fault { what: What::Kill, at: 20, once: true }));
        assert_eq!(Fault::parse("explode@3"), None);
        assert_eq!(Fault::parse("panic"), None);
        assert_eq!(by_submission("2=panic@3, 5=grow@0,x=kill@1"), vec![(2, "panic@3".into()), (5, "grow@0".into())]);
    }
}
