//! The command line: its subcommands and their options (clap), and a node's
//! configuration from them.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(name = "shapeflow", version, about = "Shape optimization by discrete gradient flows")]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Run a job spec offline and write its results to a directory.
    Run {
        /// The job spec (JSON; see docs/job-spec.md).
        spec: PathBuf,
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// An input file for "input:NAME" references, as NAME=PATH (repeatable).
        #[arg(long = "input", value_name = "NAME=PATH")]
        inputs: Vec<String>,
        /// Continue from a checkpoint.json written by an earlier run of the same spec.
        #[arg(long)]
        resume: Option<PathBuf>,
    },
    /// Start the HTTP job service (API and workers).
    Serve {
        /// Address to listen on.
        #[arg(long, env = "SHAPEFLOW_BIND", default_value = "127.0.0.1:8080")]
        bind: String,
        #[command(flatten)]
        node: NodeArgs,
        /// Require `Authorization: Bearer TOKEN` on every route but /healthz and
        /// the viewer page (an admin key: see `shapeflow keys`). Prefer
        /// SHAPEFLOW_TOKEN or --token-file: a flag shows in `ps`.
        #[arg(long, env = "SHAPEFLOW_TOKEN", hide_env_values = true)]
        token: Option<String>,
        /// An origin (`https://app.example`) whose pages may call this service
        /// from a browser: CORS headers for it, and its POSTs and DELETEs
        /// allowed (repeatable; the service's own pages always are).
        #[arg(long = "cors-origin", env = "SHAPEFLOW_CORS_ORIGINS", value_delimiter = ',', value_name = "ORIGIN")]
        cors_origins: Vec<String>,
        #[command(flatten)]
        http: HttpArgs,
        /// Read the token from this file (its first line).
        #[arg(long, env = "SHAPEFLOW_TOKEN_FILE", conflicts_with = "token")]
        token_file: Option<PathBuf>,
    },
    /// Run workers only (no HTTP), against the shared database of a cluster.
    Worker {
        #[command(flatten)]
        node: NodeArgs,
    },
    /// Create, list or revoke the API keys of a service (docs/keys.md), in the
    /// store of its --database and --data-dir.
    Keys {
        #[command(subcommand)]
        action: KeysAction,
        #[command(flatten)]
        store: StoreArgs,
    },
    /// Exit 0 if a service answers 200 at `--url` (a container's health check:
    /// `GET /readyz`), 1 otherwise.
    Health {
        /// host:port and path of the check.
        #[arg(long, default_value = "127.0.0.1:8080/readyz")]
        url: String,
    },
    /// Run one job sent on standard input (the process a worker starts for each
    /// job under process isolation; not for use by hand).
    #[command(hide = true)]
    JobRunner {
        /// The job's memory budget in bytes (RLIMIT_DATA).
        #[arg(long)]
        memory: Option<u64>,
    },
    /// Print the JSON Schema of the job spec (api/job-spec.schema.json).
    Schema {
        /// Print the reference page generated from it instead
        /// (docs/job-spec-reference.md).
        #[arg(long)]
        markdown: bool,
    },
}

/// What HTTP clients may take of the service (docs/operations.md).
#[derive(clap::Args)]
pub(crate) struct HttpArgs {
    /// Seconds a client has to send a request's headers, and to start its next
    /// request on a kept-alive connection.
    #[arg(long, env = "SHAPEFLOW_HEADER_TIMEOUT", default_value_t = 10.0)]
    pub(crate) header_timeout: f64,
    /// Bytes a second a request body must arrive at on average, once
    /// --body-grace seconds have passed; slower, the request ends with 408.
    #[arg(long, env = "SHAPEFLOW_BODY_MIN_RATE", value_parser = shapeflow::jobs::parse_size, default_value = "1KiB")]
    pub(crate) body_min_rate: u64,
    /// Seconds a body may take before the minimum rate applies.
    #[arg(long, env = "SHAPEFLOW_BODY_GRACE", default_value_t = 10.0)]
    pub(crate) body_grace: f64,
    /// Open connections at most (the last 32 serve only /healthz and /readyz);
    /// at most the open-file limit less 256.
    #[arg(long, env = "SHAPEFLOW_MAX_CONNECTIONS", default_value_t = 1024)]
    pub(crate) max_connections: usize,
}

impl HttpArgs {
    pub(crate) fn limits(&self) -> Result<shapeflow::service::http::HttpLimits> {
        let seconds = |flag: &str, s: f64| {
            anyhow::ensure!(s.is_finite() && s > 0.0, "{flag} must be a positive number of seconds, got {s}");
            Ok(std::time::Duration::from_secs_f64(s))
        };
        // as many files as the system lets this process open, less what the
        // store, the blobs and the job processes' pipes need
        let files = rlimit::increase_nofile_limit(u64::MAX).unwrap_or(1024) as usize;
        let max_connections = self.max_connections.min(files.saturating_sub(256)).max(64);
        Ok(shapeflow::service::http::HttpLimits {
            header_timeout: seconds("--header-timeout", self.header_timeout)?,
            body_min_rate: self.body_min_rate,
            body_grace: seconds("--body-grace", self.body_grace)?,
            max_connections,
            reserve: 32,
        })
    }
}

/// Where the jobs are.
#[derive(clap::Args)]
pub(crate) struct StoreArgs {
    /// The job store: a SQLite file (created if missing; a relative path is taken
    /// inside --data-dir), a `sqlite:` URL, or a `postgres://user@host/db` URL
    /// shared by the nodes of a cluster.
    #[arg(long, global = true, env = "SHAPEFLOW_DATABASE", default_value = "shapeflow.db")]
    pub(crate) database: String,
    /// Directory for the service's data (a SQLite database, with its WAL files,
    /// and the folder `blobs` of inputs, checkpoints and results unless
    /// --object-store is given); created if missing.
    #[arg(long, global = true, env = "SHAPEFLOW_DATA_DIR", default_value = ".")]
    pub(crate) data_dir: PathBuf,
    /// Keep inputs, checkpoints and result files in an S3-compatible bucket,
    /// `s3://bucket` or `s3://bucket/prefix`, shared by the nodes of a cluster
    /// (credentials and endpoint from AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY,
    /// AWS_REGION, AWS_ENDPOINT, AWS_ALLOW_HTTP).
    #[arg(long, global = true, env = "SHAPEFLOW_OBJECT_STORE")]
    pub(crate) object_store: Option<String>,
}

impl StoreArgs {
    /// The database URL or file (a relative file inside the data directory,
    /// which is created).
    pub(crate) fn database(&self) -> Result<String> {
        let shared = self.database.contains("://") && !self.database.starts_with("sqlite:");
        if let Some(url) = &self.object_store {
            anyhow::ensure!(url.starts_with("s3://"), "--object-store must be an s3://bucket/prefix URL, got {url:?}");
        }
        std::fs::create_dir_all(&self.data_dir)
            .with_context(|| format!("cannot create data directory {}", self.data_dir.display()))?;
        Ok(if shared || self.database.starts_with("sqlite:") {
            self.database.clone()
        } else {
            self.data_dir.join(&self.database).to_string_lossy().into_owned()
        })
    }
}

#[derive(Subcommand)]
pub(crate) enum KeysAction {
    /// Make a new key and print it, once, on the last line.
    Create {
        /// The key's name (letters, digits, `-`, `_`, `.`).
        name: String,
        /// The key sees and manages every job.
        #[arg(long)]
        admin: bool,
        /// Jobs accepted or running at most at a time; the next POST is 429.
        #[arg(long)]
        max_active: Option<u32>,
        /// Bytes its jobs keep at most (checkpoints, result files, history;
        /// `500MB`, `2GiB`): no new job once they keep that much (429), and a
        /// running job stops at what is left.
        #[arg(long, value_parser = shapeflow::jobs::parse_size)]
        max_storage: Option<u64>,
    },
    /// The keys, one a line: name, admin or not, quota, created, revoked.
    List,
    /// Revoke a key: requests with it are 401 (within a second on every node).
    Revoke { name: String },
}

/// What a node of the service needs: where the jobs are and how many it runs.
#[derive(clap::Args)]
pub(crate) struct NodeArgs {
    #[command(flatten)]
    pub(crate) store: StoreArgs,
    /// Worker threads running jobs (default: number of cores).
    #[arg(long, env = "SHAPEFLOW_WORKERS")]
    pub(crate) workers: Option<usize>,
    /// Length of a running job's lease in seconds (renewed every third of it); a
    /// job whose node stops renewing is taken over after it.
    #[arg(long, env = "SHAPEFLOW_LEASE_SECONDS", default_value_t = 15.0)]
    pub(crate) lease_seconds: f64,
    /// Where each job runs: `process` (a process of its own, with its budgets
    /// enforced by the kernel; a job that crashes ends only its own attempt) or
    /// `thread` (on its worker's thread in this process: no memory budget).
    #[arg(long, env = "SHAPEFLOW_ISOLATION", value_enum, default_value_t = IsolationArg::Process)]
    pub(crate) isolation: IsolationArg,
    /// Each job's memory budget (bytes, or with a suffix: 512MiB, 2GiB); default:
    /// three quarters of the machine's memory shared by the workers, at least 1 GiB.
    #[arg(long, env = "SHAPEFLOW_JOB_MEMORY", value_parser = shapeflow::jobs::parse_size)]
    pub(crate) job_memory: Option<u64>,
    /// Each attempt's wall-clock budget in seconds (0: none).
    #[arg(long, env = "SHAPEFLOW_JOB_SECONDS", default_value_t = 86_400.0)]
    pub(crate) job_seconds: f64,
    /// What each job may store: checkpoints, result files and history (bytes,
    /// or with a suffix).
    #[arg(long, env = "SHAPEFLOW_JOB_DISK", value_parser = shapeflow::jobs::parse_size, default_value = "16GiB")]
    pub(crate) job_disk: u64,
    /// Below this much free space on the data directory's disk, /readyz answers
    /// 503 (bytes, or with a suffix).
    #[arg(long, env = "SHAPEFLOW_MIN_FREE_DISK", value_parser = shapeflow::jobs::parse_size, default_value = "512MiB")]
    pub(crate) min_free_disk: u64,
    /// Jobs waiting at most on the whole service (0: no limit); beyond, a POST
    /// is 503 with Retry-After.
    #[arg(long, env = "SHAPEFLOW_MAX_QUEUED", default_value_t = 10_000)]
    pub(crate) max_queued: u64,
    /// Delete jobs that ended longer ago than this (`30d`, `12h`, `90s`), with
    /// their history, checkpoints and files; default: keep them.
    #[arg(long, env = "SHAPEFLOW_RETAIN", value_parser = shapeflow::service::retention::parse_duration)]
    pub(crate) retain: Option<std::time::Duration>,
    /// Log lines as `text` or `json` (one object a line, with each request's id).
    #[arg(long, env = "SHAPEFLOW_LOG_FORMAT", value_enum, default_value_t = LogFormat::Text)]
    pub(crate) log_format: LogFormat,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum LogFormat {
    Text,
    Json,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum IsolationArg {
    Process,
    Thread,
}

/// Faults to inject from `SHAPEFLOW_TEST_FAULTS`: debug builds only (the tests
/// of isolation), never a release.
fn test_faults() -> Vec<(i64, String)> {
    let text = std::env::var("SHAPEFLOW_TEST_FAULTS").ok().filter(|_| cfg!(debug_assertions));
    shapeflow::service::isolation::fault::by_submission(&text.unwrap_or_default())
}

impl NodeArgs {
    /// The configuration of a node, or why not.
    pub(crate) fn config(self, token: Option<String>, api: bool) -> Result<shapeflow::service::ServiceConfig> {
        use shapeflow::service::isolation::{Budgets, Isolation, Runner};
        use shapeflow::service::store::ClaimPolicy;
        anyhow::ensure!(
            self.lease_seconds.is_finite() && (1.0..=30.0).contains(&self.lease_seconds),
            "--lease-seconds must be between 1 and 30, got {}",
            self.lease_seconds
        );
        let database = self.store.database()?;
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        let workers = self.workers.unwrap_or(cores);
        anyhow::ensure!(api || workers > 0, "a worker node needs --workers of at least 1");
        let policy =
            ClaimPolicy { lease: std::time::Duration::from_secs_f64(self.lease_seconds), ..ClaimPolicy::default() };
        let isolation = match self.isolation {
            IsolationArg::Thread => Isolation::Thread,
            IsolationArg::Process => {
                let runner =
                    Runner::new(std::env::current_exe().context("cannot find this program's file to run jobs with")?);
                runner.ahead().context("cannot start the thread that starts job processes")?;
                Isolation::Process { runner }
            }
        };
        let budgets =
            Budgets::of_node(self.job_memory, self.job_seconds, self.job_disk, workers).map_err(anyhow::Error::msg)?;
        Ok(shapeflow::service::ServiceConfig {
            database,
            object_store: self.store.object_store,
            data_dir: self.store.data_dir,
            workers: workers.max(!api as usize),
            token,
            policy,
            isolation,
            budgets,
            min_free_disk: self.min_free_disk,
            faults: test_faults(),
            cors_origins: Vec::new(),
            max_queued: (self.max_queued > 0).then_some(self.max_queued as i64),
            retain: self.retain,
        })
    }
}
