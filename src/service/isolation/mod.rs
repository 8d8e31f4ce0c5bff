//! How a worker runs a job: in a process of its own (the default; Celery's
//! prefork pool, Kubernetes Jobs) or on its own thread (`serve --isolation
//! thread`, for tests and small setups). A job's process ([`child`], the same
//! binary as `shapeflow job-runner`) computes and reports over a pipe
//! ([`protocol`]); its worker ([`parent`]) keeps the database, the blob store and
//! the lease, and the kernel enforces the job's memory budget. A process that
//! panics, aborts or is killed ends its attempt; the job goes on from its last
//! checkpoint on the next one, up to the claim policy's limit.

pub mod child;
pub mod fault;
pub mod parent;
pub mod protocol;
pub mod runner;

use crate::jobs::Limits;
pub use crate::jobs::{format_size, parse_size};
pub use runner::Runner;
use std::time::Duration;

/// Where a worker runs its jobs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Isolation {
    /// On the worker's thread, in the service's process: a job that aborts the
    /// process (an allocation past the machine's memory) takes the service with it.
    Thread,
    /// In a process of its own: `exe job-runner` (the service's own binary),
    /// started by `runner`, some ahead of their jobs.
    Process { runner: Runner },
}

/// What one job may use; `None`: no limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Budgets {
    /// Bytes of data segment (heap and anonymous maps: `RLIMIT_DATA`), process
    /// isolation only.
    pub memory: Option<u64>,
    /// Wall-clock time of one attempt.
    pub seconds: Option<Duration>,
    /// Bytes the job stores: checkpoints, result files and history rows.
    pub disk: Option<u64>,
    /// Whether `disk` is what is left of its key's storage quota (`keys create
    /// --max-storage`) rather than a budget per job.
    pub disk_is_quota: bool,
}

impl Budgets {
    /// The defaults of a node with `workers` workers: each job three quarters of
    /// the machine's memory shared by the workers (at least 1 GiB), a day, and
    /// 16 GiB of storage.
    pub fn defaults(workers: usize) -> Budgets {
        let total = machine_memory().unwrap_or(8 << 30);
        let memory = (total / 4 * 3 / workers.max(1) as u64).max(1 << 30);
        Budgets {
            memory: Some(memory),
            seconds: Some(Duration::from_secs(86_400)),
            disk: Some(16 << 30),
            disk_is_quota: false,
        }
    }
}

impl Budgets {
    /// A node's budgets from its flags: `memory` (default [`Budgets::defaults`]),
    /// `seconds` (0: none) and `disk`, for `workers` workers; or why not.
    pub fn of_node(memory: Option<u64>, seconds: f64, disk: u64, workers: usize) -> Result<Budgets, String> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(format!("--job-seconds must be a number of seconds (0: none), got {seconds}"));
        }
        Ok(Budgets {
            memory: memory.or(Budgets::defaults(workers).memory),
            seconds: (seconds > 0.0).then(|| Duration::from_secs_f64(seconds)),
            disk: Some(disk),
            disk_is_quota: false,
        })
    }

    /// These budgets, with the disk budget lowered to `room`, what is left of the
    /// job's key's storage quota, if it has one.
    pub fn within_quota(self, room: Option<u64>) -> Budgets {
        match (room, self.disk) {
            (Some(r), d) if d.is_none_or(|d| r < d) => Budgets { disk: Some(r), disk_is_quota: true, ..self },
            _ => self,
        }
    }

    /// These budgets, lowered to what a job's `limits` ask for.
    pub fn within(self, asked: Limits) -> Budgets {
        let min = |a: Option<u64>, b: Option<u64>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let seconds = asked.seconds.map(Duration::from_secs_f64);
        Budgets {
            memory: min(self.memory, asked.memory),
            seconds: match (self.seconds, seconds) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
            disk: min(self.disk, asked.disk),
            disk_is_quota: false,
        }
    }

    /// The first of `asked` above these budgets: its field and why.
    pub fn refuse(self, asked: Limits) -> Option<(&'static str, String)> {
        let over = |field: &'static str, a: Option<u64>, b: Option<u64>| match (a, b) {
            (Some(a), Some(b)) if a > b => Some((
                field,
                format!("asks for {}, more than this server's budget of {} per job", format_size(a), format_size(b)),
            )),
            _ => None,
        };
        let secs = |d: Option<Duration>| d.map(|d| d.as_secs_f64());
        over("limits.memory", asked.memory, self.memory)
            .or_else(|| match (asked.seconds, secs(self.seconds)) {
                (Some(a), Some(b)) if a > b => {
                    Some(("limits.seconds", format!("asks for {a} s, more than this server's budget of {b} s per job")))
                }
                _ => None,
            })
            .or_else(|| over("limits.disk", asked.disk, self.disk))
    }
}

/// The machine's memory in bytes (Linux: `/proc/meminfo`).
fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_budgets_share_the_machine() {
        let one = Budgets::defaults(1).memory.unwrap();
        let four = Budgets::defaults(4).memory.unwrap();
        assert!(one >= four && four >= 1 << 30);
    }
}
