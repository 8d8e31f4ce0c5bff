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

use std::path::PathBuf;
use std::time::Duration;

/// Where a worker runs its jobs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Isolation {
    /// On the worker's thread, in the service's process: a job that aborts the
    /// process (an allocation past the machine's memory) takes the service with it.
    Thread,
    /// In a process of its own: `exe job-runner` (the service's own binary).
    Process { exe: PathBuf },
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
}

impl Budgets {
    /// The defaults of a node with `workers` workers: each job three quarters of
    /// the machine's memory shared by the workers (at least 1 GiB), a day, and
    /// 16 GiB of storage.
    pub fn defaults(workers: usize) -> Budgets {
        let total = machine_memory().unwrap_or(8 << 30);
        let memory = (total / 4 * 3 / workers.max(1) as u64).max(1 << 30);
        Budgets { memory: Some(memory), seconds: Some(Duration::from_secs(86_400)), disk: Some(16 << 30) }
    }
}

/// The machine's memory in bytes (Linux: `/proc/meminfo`).
fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// A size in bytes, with an optional binary (`KiB`, `MiB`, `GiB`, `TiB`) or
/// decimal (`kB`, `MB`, `GB`, `TB`) suffix: `512MiB`, `2GiB`, `1000000`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, unit) = (&t[..split], t[split..].trim());
    let n: f64 = number.parse().map_err(|_| format!("expected a size such as 512MiB or 2GiB, got {text:?}"))?;
    let scale: u64 = match unit {
        "" | "B" => 1,
        "KiB" | "K" => 1 << 10,
        "MiB" | "M" => 1 << 20,
        "GiB" | "G" => 1 << 30,
        "TiB" | "T" => 1 << 40,
        "kB" | "KB" => 1_000,
        "MB" => 1_000_000,
        "GB" => 1_000_000_000,
        "TB" => 1_000_000_000_000,
        _ => return Err(format!("unknown unit {unit:?} in {text:?} (use B, KiB, MiB, GiB, TiB, kB, MB, GB or TB)")),
    };
    let bytes = n * scale as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes > u64::MAX as f64 {
        return Err(format!("expected a positive size, got {text:?}"));
    }
    Ok(bytes as u64)
}

/// A size for messages: `2 GiB`, `512 MiB`, `1.5 GiB`, `1000 B`.
pub fn format_size(bytes: u64) -> String {
    const UNITS: [(&str, u64); 4] = [("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (name, scale) in UNITS {
        if bytes >= scale {
            let v = bytes as f64 / scale as f64;
            return if (v - v.round()).abs() < 0.005 {
                format!("{} {name}", v.round())
            } else {
                format!("{v:.2} {name}")
            };
        }
    }
    format!("{bytes} B")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("1.5 GiB"), Ok(3 << 29));
        assert_eq!(parse_size("1000000"), Ok(1_000_000));
        assert_eq!(parse_size("3MB"), Ok(3_000_000));
        assert!(parse_size("12 parsecs").unwrap_err().contains("unknown unit"));
        assert!(parse_size("-3MiB").is_err());
        assert!(parse_size("0").is_err());
        assert_eq!(format_size(2 << 30), "2 GiB");
        assert_eq!(format_size(3 << 29), "1.50 GiB");
        assert_eq!(format_size(512 << 20), "512 MiB");
        assert_eq!(format_size(1000), "1000 B");
    }

    #[test]
    fn default_budgets_share_the_machine() {
        let one = Budgets::defaults(1).memory.unwrap();
        let four = Budgets::defaults(4).memory.unwrap();
        assert!(one >= four && four >= 1 << 30);
    }
}
