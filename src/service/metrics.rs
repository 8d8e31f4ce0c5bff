//! What operators read at `GET /metrics`, in Prometheus' text format
//! (docs/operations.md, "Metrics"), from an explicit registry (the
//! `prometheus-client` crate): HTTP requests by route, method and status with
//! their latency, attempts and takeovers of this node's workers and the run time
//! of their attempts; and, read from the store when scraped, the jobs by status
//! (the queue is `accepted`) and the bytes the blob store holds (listed at most
//! once a minute).

use prometheus_client::encoding::text::encode;
use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{exponential_buckets, Histogram};
use prometheus_client::registry::Registry;
use std::sync::atomic::AtomicU64;
use std::sync::Mutex;
use std::time::{Duration, Instant};

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct RequestLabels {
    pub route: String,
    pub method: String,
    pub status: u16,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct RouteLabels {
    pub route: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct StatusLabels {
    pub status: String,
}

/// How often the blob store's size is listed at most.
const STORED_BYTES_EVERY: Duration = Duration::from_secs(60);

/// A node's metrics (see the module).
pub struct Metrics {
    registry: Registry,
    pub requests: Family<RequestLabels, Counter>,
    pub request_seconds: Family<RouteLabels, Histogram>,
    pub attempts: Counter,
    pub takeovers: Counter,
    pub run_seconds: Histogram,
    jobs: Family<StatusLabels, Gauge>,
    stored_bytes: Gauge<u64, AtomicU64>,
    stored_at: Mutex<Option<Instant>>,
}

impl Default for Metrics {
    fn default() -> Self {
        let mut registry = Registry::with_prefix("shapeflow");
        let requests = Family::<RequestLabels, Counter>::default();
        let request_seconds = Family::<RouteLabels, Histogram>::new_with_constructor(|| {
            Histogram::new(exponential_buckets(0.0005, 2.0, 16))
        });
        let (attempts, takeovers) = (Counter::default(), Counter::default());
        let run_seconds = Histogram::new(exponential_buckets(0.01, 4.0, 12));
        let jobs = Family::<StatusLabels, Gauge>::default();
        let stored_bytes = Gauge::<u64, AtomicU64>::default();
        registry.register("http_requests", "HTTP requests answered, by route, method and status", requests.clone());
        registry.register("http_request_seconds", "Time to answer an HTTP request, by route", request_seconds.clone());
        registry.register("job_attempts", "Attempts at jobs started by this node's workers", attempts.clone());
        registry.register("job_takeovers", "Attempts that took a job over from a given-up attempt", takeovers.clone());
        registry.register("job_run_seconds", "Wall time of the attempts of this node's workers", run_seconds.clone());
        registry.register("jobs", "Jobs in the store by status (the queue: accepted)", jobs.clone());
        registry.register(
            "stored_bytes",
            "Bytes in the blob store (inputs, checkpoints, results)",
            stored_bytes.clone(),
        );
        Metrics {
            registry,
            requests,
            request_seconds,
            attempts,
            takeovers,
            run_seconds,
            jobs,
            stored_bytes,
            stored_at: Mutex::new(None),
        }
    }
}

impl Metrics {
    /// The job counts by status as the store has them now.
    pub fn set_jobs(&self, counts: &[(String, i64)]) {
        for status in crate::service::store::JobStatus::ALL {
            let n = counts.iter().find(|(s, _)| s == status.as_str()).map_or(0, |c| c.1);
            self.jobs.get_or_create(&StatusLabels { status: status.as_str().into() }).set(n);
        }
    }

    /// Whether the stored bytes are due to be listed again (and, if so, not
    /// again for a minute).
    pub fn stored_bytes_due(&self) -> bool {
        let mut at = self.stored_at.lock().unwrap();
        let due = at.is_none_or(|t| t.elapsed() >= STORED_BYTES_EVERY);
        if due {
            *at = Some(Instant::now());
        }
        due
    }

    pub fn set_stored_bytes(&self, bytes: u64) {
        self.stored_bytes.set(bytes);
    }

    /// The text format of every metric.
    pub fn render(&self) -> String {
        let mut text = String::new();
        encode(&mut text, &self.registry).expect("a String takes every write");
        text
    }
}
