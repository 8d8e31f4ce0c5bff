//! The sweep of deleted and expired jobs. `DELETE /v1/jobs/{id}` only marks a
//! job deleted (it is gone from every read at once); this sweep then deletes its
//! blobs and its rows a few thousand at a time, and with `serve --retain
//! DURATION` it first marks the jobs that ended longer ago than that. On SQLite
//! the space then goes back to the disk. One node of a cluster sweeps at a time
//! (it leads the task `sweep` in the store); a purge cut short (a crash) is taken
//! up again by the next sweep.

use super::store::{rfc3339_ago, Store, StoreError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Jobs marked or purged per batch of a sweep.
const BATCH: i64 = 100;

/// How often the store is looked at for deleted jobs.
const PERIOD: Duration = Duration::from_secs(1);

/// How long a node leads the sweep without renewing its lead.
const LEAD: Duration = Duration::from_secs(30);

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

/// Sweep every [`PERIOD`] until `closing`: the jobs marked deleted are purged,
/// and with `retain`, every `retain / 4` (at least a second, at most a minute)
/// the jobs that ended more than `retain` ago are marked first. `node` names
/// this node for the lead.
pub async fn sweep_forever(store: Store, retain: Option<Duration>, node: String, closing: Arc<AtomicBool>) {
    let expire_every = retain.map(|r| (r / 4).clamp(Duration::from_secs(1), Duration::from_secs(60)));
    let mut expired_at: Option<Instant> = None;
    // the space of a purge not all given back yet (a busy writer)
    let mut unreclaimed = false;
    while !closing.load(Ordering::Relaxed) {
        let expire = match (retain, expire_every) {
            (Some(r), Some(every)) if expired_at.is_none_or(|t| t.elapsed() >= every) => {
                expired_at = Some(Instant::now());
                Some(r)
            }
            _ => None,
        };
        match sweep(&store, expire, &node).await {
            Ok(Swept { expired: 0, purged: 0, .. }) => {}
            Ok(Swept { expired, purged, reclaimed }) => {
                unreclaimed = !reclaimed;
                tracing::info!(expired, purged, reclaimed, "sweep: deleted jobs purged");
            }
            Err(e) => tracing::warn!("sweep: {e}"),
        }
        if unreclaimed {
            match store.reclaim().await {
                Ok(done) => unreclaimed = !done,
                Err(e) => tracing::warn!("sweep: reclaim: {e}"),
            }
        }
        tokio::time::sleep(PERIOD).await;
    }
}

/// What one sweep did: jobs marked deleted for their age, jobs purged, and
/// whether the space of a purge all went back to the disk ([`Store::reclaim`];
/// true with nothing purged).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Swept {
    pub expired: usize,
    pub purged: usize,
    pub reclaimed: bool,
}

/// One sweep (see [`sweep_forever`]), if this node leads it: with `expire`, the
/// jobs that ended longer ago are marked deleted first.
pub async fn sweep(store: &Store, expire: Option<Duration>, node: &str) -> Result<Swept, StoreError> {
    let mut swept = Swept { expired: 0, purged: 0, reclaimed: true };
    let mut led = false;
    if let Some(retain) = expire {
        let before = rfc3339_ago(retain.as_secs_f64());
        loop {
            let ids = store.ended_before(&before, BATCH).await?;
            if ids.is_empty() || !leads(store, node, &mut led).await? {
                break;
            }
            for id in &ids {
                swept.expired += store.mark_deleted(id).await? as usize;
            }
        }
    }
    loop {
        let ids = store.deleted_jobs(BATCH).await?;
        if ids.is_empty() || !leads(store, node, &mut led).await? {
            break;
        }
        for id in &ids {
            store.purge(id).await?;
        }
        swept.purged += ids.len();
    }
    if swept.purged > 0 {
        swept.reclaimed = store.reclaim().await?;
    }
    Ok(swept)
}

/// Whether this node leads the sweep (asked once a sweep, when there is work).
async fn leads(store: &Store, node: &str, led: &mut bool) -> Result<bool, StoreError> {
    if !*led {
        *led = store.lead("sweep", node, LEAD).await?;
    }
    Ok(*led)
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
