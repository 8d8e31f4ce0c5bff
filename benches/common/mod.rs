//! Helpers shared by the bench binaries (included with `#[path]`).

use std::time::Instant;

/// Repeat `f` until at least `budget` seconds and 3 runs, after one warm-up run
/// (symbolic factorizations, allocations); mean seconds per run.
#[allow(dead_code)]
pub fn time_it(budget: f64, mut f: impl FnMut()) -> f64 {
    f();
    let start = Instant::now();
    let mut n = 0;
    while n < 3 || start.elapsed().as_secs_f64() < budget {
        f();
        n += 1;
    }
    start.elapsed().as_secs_f64() / n as f64
}

/// Peak resident set size of this process so far, in MiB (Linux; NaN elsewhere).
#[allow(dead_code)]
pub fn peak_rss_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|k| k.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}
