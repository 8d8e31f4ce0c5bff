//! Retention (`serve --retain DURATION`): jobs that ended longer ago than that
//! are deleted with their rows and blobs, a batch at a time, and (SQLite) the
//! space goes back to the disk. Every node with the setting sweeps; deleting a
//! job twice is harmless, so nodes of a cluster need no coordination.

use super::store::{rfc3339_ago, Store};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Jobs deleted per batch of a sweep.
const BATCH: i64 = 100;

/// A duration: a number of seconds, or a number and a unit (`s`, `m`, `h`, `d`):
/// `90`, `2s`, `30m`, `12h`, `30d`.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let scale = match unit {
        "" | "s" => 1.0,
        "m" => 60.0,
        "h" => 3600.0,
        "d" => 86_400.0,
        _ => return Err(format!("unknown unit {unit:?} in {text:?} (s, m, h or d)")),
    };
    match number.trim().parse::<f64>() {
        Ok(n) if n.is_finite() && n > 0.0 && n * scale < 1e11 => Ok(Duration::from_secs_f64(n * scale)),
        _ => Err(format!("not a positive duration: {text:?} (e.g. 30d, 12h, 90s)")),
    }
}

/// Sweep every `retain / 4` (at least a second, at most a minute) until
/// `closing`, deleting the jobs that ended more than `retain` ago.
pub async fn sweep_forever(store: Store, retain: Duration, closing: Arc<AtomicBool>) {
    let period = (retain / 4).clamp(Duration::from_secs(1), Duration::from_secs(60));
    while !closing.load(Ordering::Relaxed) {
        match sweep(&store, retain).await {
            Ok(0) => {}
            Ok(n) => tracing::info!(deleted = n, "retention: jobs that ended more than {retain:?} ago deleted"),
            Err(e) => tracing::warn!("retention: {e}"),
        }
        tokio::time::sleep(period).await;
    }
}

/// One sweep: the number of jobs deleted.
pub async fn sweep(store: &Store, retain: Duration) -> Result<usize, super::store::StoreError> {
    let before = rfc3339_ago(retain.as_secs_f64());
    let mut deleted = 0;
    loop {
        let ids = store.ended_before(&before, BATCH).await?;
        for id in &ids {
            store.delete(id).await?;
        }
        deleted += ids.len();
        if (ids.len() as i64) < BATCH {
            break;
        }
    }
    if deleted > 0 {
        store.reclaim().await?;
    }
    Ok(deleted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_with_their_units() {
        assert_eq!(parse_duration("2s"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_duration("90"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_duration("12h"), Ok(Duration::from_secs(43_200)));
        assert_eq!(parse_duration("30d"), Ok(Duration::from_secs(2_592_000)));
        assert!(parse_duration("3w").is_err() && parse_duration("-1d").is_err() && parse_duration("").is_err());
    }
}
