//! The `shapeflow` command: `run` a job spec offline, or `serve` the HTTP API.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use shapeflow::flow::{Checkpoint, Progress};
use shapeflow::jobs::{output_files, parse_spec, prepare, run_with_frames, RunEvents};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

#[derive(Parser)]
#[command(name = "shapeflow", version, about = "Shape optimization by discrete gradient flows")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
struct HttpArgs {
    /// Seconds a client has to send a request's headers, and to start its next
    /// request on a kept-alive connection.
    #[arg(long, env = "SHAPEFLOW_HEADER_TIMEOUT", default_value_t = 10.0)]
    header_timeout: f64,
    /// Bytes a second a request body must arrive at on average, once
    /// --body-grace seconds have passed; slower, the request ends with 408.
    #[arg(long, env = "SHAPEFLOW_BODY_MIN_RATE", value_parser = shapeflow::jobs::parse_size, default_value = "1KiB")]
    body_min_rate: u64,
    /// Seconds a body may take before the minimum rate applies.
    #[arg(long, env = "SHAPEFLOW_BODY_GRACE", default_value_t = 10.0)]
    body_grace: f64,
    /// Open connections at most (the last 32 serve only /healthz and /readyz);
    /// at most the open-file limit less 256.
    #[arg(long, env = "SHAPEFLOW_MAX_CONNECTIONS", default_value_t = 1024)]
    max_connections: usize,
}

impl HttpArgs {
    fn limits(&self) -> Result<shapeflow::service::http::HttpLimits> {
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
struct StoreArgs {
    /// The job store: a SQLite file (created if missing; a relative path is taken
    /// inside --data-dir), a `sqlite:` URL, or a `postgres://user@host/db` URL
    /// shared by the nodes of a cluster.
    #[arg(long, global = true, env = "SHAPEFLOW_DATABASE", default_value = "shapeflow.db")]
    database: String,
    /// Directory for the service's data (a SQLite database, with its WAL files,
    /// and the folder `blobs` of inputs, checkpoints and results unless
    /// --object-store is given); created if missing.
    #[arg(long, global = true, env = "SHAPEFLOW_DATA_DIR", default_value = ".")]
    data_dir: PathBuf,
    /// Keep inputs, checkpoints and result files in an S3-compatible bucket,
    /// `s3://bucket` or `s3://bucket/prefix`, shared by the nodes of a cluster
    /// (credentials and endpoint from AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY,
    /// AWS_REGION, AWS_ENDPOINT, AWS_ALLOW_HTTP).
    #[arg(long, global = true, env = "SHAPEFLOW_OBJECT_STORE")]
    object_store: Option<String>,
}

impl StoreArgs {
    /// The database URL or file (a relative file inside the data directory,
    /// which is created).
    fn database(&self) -> Result<String> {
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
enum KeysAction {
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
struct NodeArgs {
    #[command(flatten)]
    store: StoreArgs,
    /// Worker threads running jobs (default: number of cores).
    #[arg(long, env = "SHAPEFLOW_WORKERS")]
    workers: Option<usize>,
    /// Length of a running job's lease in seconds (renewed every third of it); a
    /// job whose node stops renewing is taken over after it.
    #[arg(long, env = "SHAPEFLOW_LEASE_SECONDS", default_value_t = 15.0)]
    lease_seconds: f64,
    /// Where each job runs: `process` (a process of its own, with its budgets
    /// enforced by the kernel; a job that crashes ends only its own attempt) or
    /// `thread` (on its worker's thread in this process: no memory budget).
    #[arg(long, env = "SHAPEFLOW_ISOLATION", value_enum, default_value_t = IsolationArg::Process)]
    isolation: IsolationArg,
    /// Each job's memory budget (bytes, or with a suffix: 512MiB, 2GiB); default:
    /// three quarters of the machine's memory shared by the workers, at least 1 GiB.
    #[arg(long, env = "SHAPEFLOW_JOB_MEMORY", value_parser = shapeflow::jobs::parse_size)]
    job_memory: Option<u64>,
    /// Each attempt's wall-clock budget in seconds (0: none).
    #[arg(long, env = "SHAPEFLOW_JOB_SECONDS", default_value_t = 86_400.0)]
    job_seconds: f64,
    /// What each job may store: checkpoints, result files and history (bytes,
    /// or with a suffix).
    #[arg(long, env = "SHAPEFLOW_JOB_DISK", value_parser = shapeflow::jobs::parse_size, default_value = "16GiB")]
    job_disk: u64,
    /// Below this much free space on the data directory's disk, /readyz answers
    /// 503 (bytes, or with a suffix).
    #[arg(long, env = "SHAPEFLOW_MIN_FREE_DISK", value_parser = shapeflow::jobs::parse_size, default_value = "512MiB")]
    min_free_disk: u64,
    /// Jobs waiting at most on the whole service (0: no limit); beyond, a POST
    /// is 503 with Retry-After.
    #[arg(long, env = "SHAPEFLOW_MAX_QUEUED", default_value_t = 10_000)]
    max_queued: u64,
    /// Delete jobs that ended longer ago than this (`30d`, `12h`, `90s`), with
    /// their history, checkpoints and files; default: keep them.
    #[arg(long, env = "SHAPEFLOW_RETAIN", value_parser = shapeflow::service::retention::parse_duration)]
    retain: Option<std::time::Duration>,
    /// Log lines as `text` or `json` (one object a line, with each request's id).
    #[arg(long, env = "SHAPEFLOW_LOG_FORMAT", value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum LogFormat {
    Text,
    Json,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum IsolationArg {
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
    fn config(self, token: Option<String>, api: bool) -> Result<shapeflow::service::ServiceConfig> {
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

/// Log lines on standard error: text (colored on a terminal) or one JSON object a line.
fn init_logs(format: LogFormat) {
    use std::io::IsTerminal;
    let filter = tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into());
    let logs = tracing_subscriber::fmt().with_writer(std::io::stderr).with_env_filter(filter);
    match format {
        LogFormat::Text => logs.with_ansi(std::io::stderr().is_terminal()).init(),
        LogFormat::Json => logs.json().flatten_event(true).with_current_span(true).init(),
    }
}

fn main() -> ExitCode {
    shapeflow::tune_allocator();
    let cli = Cli::parse();
    init_logs(match &cli.command {
        Command::Serve { node, .. } | Command::Worker { node } => node.log_format,
        _ => LogFormat::Text,
    });
    match cli.command {
        Command::JobRunner { memory } => shapeflow::service::isolation::child::job_runner(memory),
        Command::Run { spec, out, inputs, resume } => match run(&spec, &out, &inputs, resume.as_deref()) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(2)
            }
        },
        Command::Schema { markdown } => {
            let schema = shapeflow::jobs::job_spec_schema();
            if markdown {
                say(format_args!("{}", shapeflow::jobs::job_spec_reference(&schema).trim_end()));
            } else {
                let text = serde_json::to_string_pretty(&schema).expect("a schema is JSON");
                say(format_args!("{text}"));
            }
            ExitCode::SUCCESS
        }
        Command::Serve { bind, node, token, token_file, cors_origins, http } => {
            let config = token_from(token, token_file.as_deref()).and_then(|t| node.config(t, true));
            let result = config.and_then(|config| {
                let config = shapeflow::service::ServiceConfig { cors_origins, ..config };
                let limits = http.limits()?;
                let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
                rt.block_on(serve(Some((&bind, limits)), config))
            });
            match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Keys { action, store } => match keys(action, &store) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        Command::Health { url } => {
            let url = url.trim_start_matches("http://");
            let (addr, path) = url.find('/').map_or((url, "/readyz"), |i| (&url[..i], &url[i..]));
            match shapeflow::service::http::probe(addr, path, std::time::Duration::from_secs(5)) {
                Ok(200) => ExitCode::SUCCESS,
                Ok(status) => {
                    eprintln!("{url}: {status}");
                    ExitCode::from(1)
                }
                Err(e) => {
                    eprintln!("{url}: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Worker { node } => {
            let result = node.config(None, false).and_then(|config| {
                let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
                rt.block_on(serve(None, config))
            });
            match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
    }
}

/// `shapeflow keys ...` on the store of `args`.
fn keys(action: KeysAction, args: &StoreArgs) -> Result<()> {
    use shapeflow::service::keys;
    let database = args.database()?;
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    rt.block_on(async {
        let blobs = shapeflow::service::blobs::Blobs::open(args.object_store.as_deref(), &args.data_dir)?;
        let store = shapeflow::service::store::open(&database, blobs)
            .await
            .with_context(|| format!("cannot open database {}", redact(&database)))?;
        match action {
            KeysAction::Create { name, admin, max_active, max_storage } => {
                let grant = keys::Grant {
                    admin,
                    max_active: max_active.map(i64::from),
                    max_storage: max_storage.map(|b| b.min(i64::MAX as u64) as i64),
                };
                let key = keys::create(&store, &name, grant).await?;
                println!("created the key {name:?}; it is shown only now:");
                println!("{key}");
            }
            KeysAction::List => {
                for k in store.keys().await? {
                    let quota = k.max_active.map_or("-".to_string(), |n| n.to_string());
                    let storage = k.max_storage.map_or("-".to_string(), |n| shapeflow::jobs::format_size(n as u64));
                    let state = if k.revoked { "revoked" } else { "active" };
                    println!(
                        "{}\t{}\tmax-active {quota}\tmax-storage {storage}\t{}\t{state}",
                        k.name,
                        if k.admin { "admin" } else { "user" },
                        k.created_at
                    );
                }
            }
            KeysAction::Revoke { name } => {
                anyhow::ensure!(store.revoke_key(&name).await?, "no key {name:?} to revoke (or it is revoked already)");
                println!("revoked the key {name:?}");
            }
        }
        Ok(())
    })
}

/// The admin token: given, or the first line of `file`.
fn token_from(token: Option<String>, file: Option<&Path>) -> Result<Option<String>> {
    let Some(file) = file else { return Ok(token) };
    let text = std::fs::read_to_string(file).with_context(|| format!("--token-file {}", file.display()))?;
    let line = text.lines().next().unwrap_or("").trim().to_string();
    anyhow::ensure!(!line.is_empty(), "--token-file {}: the file has no token on its first line", file.display());
    Ok(Some(line))
}

/// Run a node: the HTTP API on `bind` (none: workers only) and the workers, until
/// SIGINT/SIGTERM.
async fn serve(
    bind: Option<(&str, shapeflow::service::http::HttpLimits)>,
    config: shapeflow::service::ServiceConfig,
) -> Result<()> {
    let shown = redact(&config.database);
    let workers = config.workers;
    let service = shapeflow::service::Service::start_with(config)
        .await
        .with_context(|| format!("cannot open database {shown}"))?;
    match bind {
        Some((bind, limits)) => {
            let listener =
                tokio::net::TcpListener::bind(bind).await.with_context(|| format!("cannot listen on {bind}"))?;
            tracing::info!(address = %listener.local_addr()?, database = %shown, workers, "shapeflow serving");
            let closing = service.state.closing.clone();
            let shutdown = async move {
                shutdown_signal().await;
                // end open event streams, or graceful shutdown would wait for them
                closing.store(true, std::sync::atomic::Ordering::Relaxed);
            };
            let drain = std::time::Duration::from_secs(10);
            shapeflow::service::http::serve(listener, service.router(), limits, shutdown, drain).await?;
        }
        None => {
            tracing::info!(database = %shown, workers, "shapeflow worker running");
            shutdown_signal().await;
        }
    }
    tracing::info!("shutting down: running jobs checkpoint and resume later");
    service.stop().await;
    Ok(())
}

/// A database URL without its password, for messages.
fn redact(database: &str) -> String {
    match (database.find("://"), database.rfind('@')) {
        (Some(scheme), Some(at)) if at > scheme => {
            let userinfo = &database[scheme + 3..at];
            let user = userinfo.split(':').next().unwrap_or("");
            format!("{}{user}:***{}", &database[..scheme + 3], &database[at..])
        }
        _ => database.to_string(),
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        if let Ok(mut s) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            s.recv().await;
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}

struct Reporter {
    bar: ProgressBar,
    history: Vec<Progress>,
    end_time: Option<f64>,
}

impl RunEvents for Reporter {
    fn progress(&mut self, p: &Progress) {
        self.history.push(*p);
        match self.end_time {
            Some(t) => self.bar.set_position((1000.0 * p.time / t).round() as u64),
            None => self.bar.set_position(p.iteration as u64),
        }
        self.bar.set_message(format!("J={:.6e} τ={:.2e} t={:.4e} n={}", p.energy, p.tau, p.time, p.vertices));
    }
}

fn run(spec_path: &Path, out: &Path, inputs: &[String], resume: Option<&Path>) -> Result<ExitCode> {
    let text =
        std::fs::read_to_string(spec_path).with_context(|| format!("cannot read spec {}", spec_path.display()))?;
    let spec = parse_spec(&text).with_context(|| format!("invalid spec {}", spec_path.display()))?;
    let mut files = HashMap::new();
    for item in inputs {
        let (name, path) = item.split_once('=').with_context(|| format!("--input {item:?}: expected NAME=PATH"))?;
        let bytes = std::fs::read(path).with_context(|| format!("--input {name}: cannot read {path}"))?;
        files.insert(name.to_string(), bytes);
    }
    let started = std::time::Instant::now();
    let job = prepare(spec, &files).with_context(|| format!("invalid spec {}", spec_path.display()))?;
    let prepared = started.elapsed();
    let checkpoint: Option<Checkpoint> = match resume {
        Some(p) => {
            let t = std::fs::read_to_string(p).with_context(|| format!("cannot read checkpoint {}", p.display()))?;
            Some(serde_json::from_str(&t).with_context(|| format!("invalid checkpoint {}", p.display()))?)
        }
        None => None,
    };
    std::fs::create_dir_all(out).with_context(|| format!("cannot create output directory {}", out.display()))?;
    let s = &job.settings;
    let len = if s.end_time.is_some() { 1000 } else { s.max_iterations as u64 };
    let bar = ProgressBar::new(len);
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} {msg} [{elapsed}]").expect("template"));
    let cancel = AtomicBool::new(false);
    let ran = std::time::Instant::now();
    // the checkpoints' frames (their fields and drawing) are made on a second thread
    // while the run goes on
    let mut rep = Reporter { bar, history: Vec::new(), end_time: s.end_time };
    let (result, frames) = run_with_frames(&job, checkpoint.as_ref(), &cancel, &mut rep);
    rep.bar.finish_and_clear();
    let ran = ran.elapsed();
    let (last, code) = match result {
        Ok(o) => {
            say(format_args!(
                "stopped: {} after {} iterations (time {:.6e}, energy {:.9e})",
                o.stop.as_str(),
                o.last.iteration,
                o.last.time,
                o.last.energy
            ));
            if let Some(note) = o.note {
                say(format_args!("  {note}"));
            }
            (o.last, ExitCode::SUCCESS)
        }
        Err(f) => {
            eprintln!("failed: {}", f.error);
            (f.last, ExitCode::from(1))
        }
    };
    let writing = std::time::Instant::now();
    // the result files of the run's frames (the last one its final state), the VTK
    // time series unpacked beside its zip, the history, and checkpoint.json with
    // the flow's state for --resume
    let mut written = Vec::new();
    for (name, bytes) in output_files(&job, &frames, &rep.history, &last, &spec_path.display().to_string()) {
        let p = out.join(&name);
        if let Some(dir) = p.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        std::fs::write(&p, bytes).with_context(|| format!("cannot write {}", p.display()))?;
        if !name.starts_with("evolution/") {
            written.push(name);
        }
    }
    say(format_args!("wrote {} in {}", written.join(", "), out.display()));
    say(format_args!(
        "took {:.3} s to prepare (inputs decoded, preprocessed, initial shape), {:.3} s to run, {:.3} s to write the results",
        prepared.as_secs_f64(),
        ran.as_secs_f64(),
        writing.elapsed().as_secs_f64()
    ));
    Ok(code)
}

/// A line on stdout; a closed pipe (`shapeflow run … | head -1`) is not an error
/// (the results are written whatever happens to the report).
fn say(line: std::fmt::Arguments) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout(), "{line}");
}
