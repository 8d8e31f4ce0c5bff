//! The job service (docs/user-guide.md, docs/cluster.md): axum routes
//! ([`routes`], one module per endpoint) over a job store (SQLite on one node,
//! PostgreSQL for many; [`store`]) and a fixed pool of worker threads
//! ([`worker`]). Routes: `POST /v1/jobs` (JSON or multipart), `GET /v1/jobs`,
//! `GET|DELETE /v1/jobs/{id}`, `POST /v1/jobs/{id}/cancel`, `GET
//! /v1/jobs/{id}/events` (SSE), `GET /v1/jobs/{id}/energy` (JSON or `?format=csv`),
//! `.../energy.svg`, `GET /v1/jobs/{id}/results` (manifest) and its files, `GET
//! /v1/jobs/{id}/checkpoints` and `.../checkpoints/{n}.glb`, `GET /healthz`, `GET
//! /v1/openapi.json`, and the viewer page (`/`, `/jobs/{id}`, `/ui/...`).

mod attempt;
pub mod blobs;
mod error;
pub mod history;
pub mod http;
pub mod isolation;
pub mod keys;
pub mod metrics;
pub(crate) mod min_rate;
pub(crate) mod part_headers;
mod recorder;
pub mod retention;
mod routes;
pub mod store;
mod wire;
pub mod worker;

use axum::Router;
pub use error::ApiError;
use isolation::{Budgets, Isolation};
pub use routes::{openapi_json, router, OPENAPI_YAML, ROUTES};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use store::{ClaimPolicy, Store};
use tokio::sync::{broadcast, Notify};
use worker::{Registry, Worker};

pub use crate::limits::{MAX_BODY_BYTES, MAX_UPLOAD_BYTES};

/// The evolution.glb of running jobs built last: (job, its newest checkpoint) and the bytes.
pub type BuiltEvolutions = std::collections::VecDeque<((String, i64), bytes::Bytes)>;

/// The default floor of free space on the data disk (`/readyz`).
pub const MIN_FREE_DISK: u64 = 512 << 20;

/// Shared state of the handlers.
#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub registry: Registry,
    pub wake: Arc<Notify>,
    /// Who a bearer key is (the token, stored keys): with either, every `/v1`
    /// route needs `Authorization: Bearer KEY`.
    pub keys: Arc<keys::Keys>,
    /// Jobs waiting at most on the whole service (`serve --max-queued`).
    pub max_queued: Option<i64>,
    /// What `/metrics` shows.
    pub metrics: Arc<metrics::Metrics>,
    /// Set when the server shuts down: open event streams end.
    pub closing: Arc<AtomicBool>,
    /// A job's id after each of its history batches and its outcome, from this
    /// node's workers and (PostgreSQL) other nodes' notifications; `"*"`: re-read.
    pub events: broadcast::Sender<Arc<str>>,
    /// Submissions validated at once (decoding their inputs), at most one per
    /// core: the others wait their turn.
    pub validations: Arc<tokio::sync::Semaphore>,
    /// Where submissions are validated and jobs run (validation in a process of
    /// its own under the job's memory budget with process isolation).
    pub isolation: Isolation,
    pub budgets: Budgets,
    /// This node's name (its leases, its readiness probe).
    pub node: String,
    /// The data directory, whose disk `/readyz` watches.
    pub data_dir: std::path::PathBuf,
    /// Below this many free bytes on the data disk, `/readyz` answers 503.
    pub min_free_disk: u64,
    /// The evolution.glb of running jobs last built, by job and checkpoint.
    pub evolutions: Arc<tokio::sync::Mutex<BuiltEvolutions>>,
    /// Origins other than the service's own that may call it from a browser
    /// (`serve --cors-origin`).
    pub cors_origins: Arc<[String]>,
}

/// How a node runs.
#[derive(Debug, Clone)]
pub struct ServiceConfig {
    /// A SQLite file path or `sqlite:` URL, or a `postgres://` URL ([`store::open`]).
    pub database: String,
    /// Where the blobs go: `s3://bucket/prefix`, or `None` for the directory
    /// `blobs` under `data_dir` ([`blobs::Blobs::open`]).
    pub object_store: Option<String>,
    pub data_dir: std::path::PathBuf,
    /// Worker threads (0: none, an API-only node).
    pub workers: usize,
    /// With a token, every route but `/healthz` and the viewer page's needs it.
    pub token: Option<String>,
    pub policy: ClaimPolicy,
    /// Where jobs run: in a process each (the default of `serve`) or on the
    /// workers' threads.
    pub isolation: Isolation,
    /// What each job may use.
    pub budgets: Budgets,
    /// Below this many free bytes on the data directory's disk the node is not
    /// ready (`/readyz`).
    pub min_free_disk: u64,
    /// Faults injected into jobs by submission number (`panic@N`, `abort@N`,
    /// `kill@N`, `grow@N`, `hang@N`, optionally `:once`): for the tests of
    /// isolation only.
    #[doc(hidden)]
    pub faults: Vec<(i64, String)>,
    /// Origins other than the service's own that may call it from a browser.
    pub cors_origins: Vec<String>,
    /// Jobs waiting (accepted) at most on the whole service; beyond, 503.
    pub max_queued: Option<i64>,
    /// Jobs that ended longer ago than this are deleted (`None`: kept).
    pub retain: Option<std::time::Duration>,
}

/// A running service: the HTTP state and the worker threads.
pub struct Service {
    pub state: AppState,
    shutdown: Arc<AtomicBool>,
    workers: Vec<std::thread::JoinHandle<()>>,
}

impl Service {
    /// [`Service::start_with`] on a SQLite file with `workers` (at least one) worker
    /// threads running jobs on themselves (thread isolation, no budgets) and the
    /// default leases; blobs in the directory `blobs` beside it.
    pub async fn start(
        database: &std::path::Path,
        workers: usize,
        token: Option<String>,
    ) -> Result<Self, store::StoreError> {
        let data_dir = database.parent().unwrap_or(std::path::Path::new(".")).to_path_buf();
        let database = database.to_string_lossy().into_owned();
        let policy = ClaimPolicy::default();
        Self::start_with(ServiceConfig {
            database,
            object_store: None,
            data_dir,
            workers: workers.max(1),
            token,
            policy,
            isolation: Isolation::Thread,
            budgets: Budgets::default(),
            min_free_disk: MIN_FREE_DISK,
            faults: Vec::new(),
            cors_origins: Vec::new(),
            max_queued: None,
            retain: None,
        })
        .await
    }

    /// Open the store (on SQLite, jobs left running by a stop or crash go back to
    /// the queue; on PostgreSQL their leases expire) and start the worker threads.
    /// Call from within a tokio runtime.
    pub async fn start_with(config: ServiceConfig) -> Result<Self, store::StoreError> {
        let blobs =
            blobs::Blobs::open(config.object_store.as_deref(), &config.data_dir).map_err(store::StoreError::from)?;
        let store = store::open(&config.database, blobs).await?;
        let requeued = store.requeue_running().await?;
        if requeued > 0 {
            tracing::info!(requeued, "jobs interrupted by a previous stop go back to the queue");
        }
        let (events, _) = broadcast::channel(1024);
        let node = format!("{}-{}", std::process::id(), &uuid::Uuid::new_v4().simple().to_string()[..8]);
        store.watch(events.clone());
        let state = AppState {
            store,
            registry: Arc::new(Mutex::new(HashMap::new())),
            wake: Arc::new(Notify::new()),
            keys: Arc::new(keys::Keys::new(config.token)),
            max_queued: config.max_queued,
            metrics: Arc::default(),
            closing: Arc::new(AtomicBool::new(false)),
            events,
            validations: Arc::new(tokio::sync::Semaphore::new(
                std::thread::available_parallelism().map_or(2, |n| n.get()),
            )),
            isolation: config.isolation.clone(),
            budgets: config.budgets,
            evolutions: Arc::default(),
            node: node.clone(),
            data_dir: config.data_dir.clone(),
            min_free_disk: config.min_free_disk,
            cors_origins: config.cors_origins.clone().into(),
        };
        // a job queued by another node (PostgreSQL's "queue" notification) wakes the
        // idle workers at once rather than at their next look at the store
        let (mut queued, wake) = (state.events.subscribe(), state.wake.clone());
        tokio::spawn(async move {
            loop {
                match queued.recv().await {
                    Ok(e) if &*e == "queue" => wake.notify_waiters(),
                    Err(broadcast::error::RecvError::Closed) => return,
                    _ => {}
                }
            }
        });
        tokio::spawn(retention::sweep_forever(state.store.clone(), config.retain, node.clone(), state.closing.clone()));
        let shutdown = Arc::new(AtomicBool::new(false));
        let rt = tokio::runtime::Handle::current();
        let faults = Arc::new(config.faults);
        let workers = (0..config.workers)
            .map(|k| {
                let w = Worker {
                    store: state.store.clone(),
                    rt: rt.clone(),
                    registry: state.registry.clone(),
                    wake: state.wake.clone(),
                    shutdown: shutdown.clone(),
                    events: state.events.clone(),
                    owner: format!("{node}/{k}"),
                    policy: config.policy,
                    isolation: config.isolation.clone(),
                    budgets: config.budgets,
                    faults: faults.clone(),
                    metrics: state.metrics.clone(),
                };
                std::thread::Builder::new()
                    .name(format!("worker-{k}"))
                    .spawn(move || w.run_forever())
                    .expect("spawn worker")
            })
            .collect();
        Ok(Service { state, shutdown, workers })
    }

    pub fn router(&self) -> Router {
        router(self.state.clone())
    }

    /// Stop the workers: running jobs stop at their next step and write a
    /// checkpoint; on SQLite they stay `running`, to resume at the next start, on
    /// PostgreSQL they go back to the queue for another node.
    pub async fn stop(self) {
        self.state.closing.store(true, Ordering::Relaxed);
        self.shutdown.store(true, Ordering::Relaxed);
        for flag in self.state.registry.lock().unwrap().values() {
            flag.store(true, Ordering::Relaxed);
        }
        self.state.wake.notify_waiters();
        let workers = self.workers;
        let _ = tokio::task::spawn_blocking(move || workers.into_iter().for_each(|w| drop(w.join()))).await;
    }
}
