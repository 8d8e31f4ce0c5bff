//! What operators read and set (docs/operations.md): `/metrics` in the
//! OpenMetrics text format with job counts that match the jobs submitted,
//! settings from `SHAPEFLOW_*` variables and a token file, and JSON log lines
//! with a request id.

use super::nodes::{Liveness, Node, STEADY};
use super::*;
use std::collections::HashMap;
use std::process::{Command, Stdio};

/// The samples of an OpenMetrics text: `name{labels}` → value; every line a
/// comment (`# TYPE`, `# HELP`, `# UNIT`, `# EOF`) or a sample.
fn samples(text: &str) -> HashMap<String, f64> {
    assert!(text.ends_with("# EOF\n"), "{text}");
    let mut out = HashMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let (name, value) = line.rsplit_once(' ').unwrap_or_else(|| panic!("not a sample: {line:?}"));
        out.insert(name.to_string(), value.parse::<f64>().unwrap_or_else(|_| panic!("{line:?}")));
    }
    out
}

#[test]
fn metrics_count_the_jobs_requests_and_attempts() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1"], "");
    let ids: Vec<String> = (0..3).map(|_| node.submit(STEADY)).collect();
    ids.iter().for_each(|id| drop(node.wait_final(id)));
    let (status, _) = http_json(node.addr, "POST", "/v1/jobs", Some(r#"{"problem": {}}"#));
    assert_eq!(status, 422);
    let (status, head, text) = http(node.addr, "GET", "/metrics", None, "");
    assert_eq!(status, 200);
    assert!(head.to_ascii_lowercase().contains("content-type: application/openmetrics-text"), "{head}");
    let m = samples(&text);
    assert_eq!(m["shapeflow_jobs{status=\"successful\"}"], 3.0, "{text}");
    assert_eq!(m["shapeflow_jobs{status=\"accepted\"}"], 0.0, "{text}");
    assert_eq!(m["shapeflow_job_attempts_total"], 3.0, "{text}");
    assert_eq!(m["shapeflow_job_takeovers_total"], 0.0, "{text}");
    assert_eq!(m["shapeflow_job_run_seconds_count"], 3.0, "{text}");
    assert_eq!(m["shapeflow_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"201\"}"], 3.0, "{text}");
    assert_eq!(m["shapeflow_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"422\"}"], 1.0, "{text}");
    assert!(m["shapeflow_http_request_seconds_count{route=\"/v1/jobs/{id}\"}"] >= 3.0, "{text}");
}

#[test]
fn settings_come_from_the_environment_and_logs_can_be_json() {
    let dir = tempfile::tempdir().unwrap();
    let port = super::nodes::free_port();
    std::fs::write(dir.path().join("token"), "from-a-file\n").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
        .arg("serve")
        .env("SHAPEFLOW_BIND", format!("127.0.0.1:{port}"))
        .env("SHAPEFLOW_DATA_DIR", dir.path())
        .env("SHAPEFLOW_WORKERS", "1")
        .env("SHAPEFLOW_LOG_FORMAT", "json")
        .env("SHAPEFLOW_TOKEN_FILE", dir.path().join("token"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let start = Instant::now();
    while TcpStream::connect(addr).is_err() {
        assert!(start.elapsed() < Duration::from_secs(20), "the server did not come up");
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(http(addr, "GET", "/v1/jobs", None, "").0, 401);
    let (status, head, _) = http(addr, "GET", "/v1/jobs", None, "Authorization: Bearer from-a-file\r\n");
    assert_eq!(status, 200);
    let id = head.lines().find_map(|l| l.to_ascii_lowercase().strip_prefix("x-request-id: ").map(str::to_string));
    let id = id.unwrap_or_else(|| panic!("no request id: {head}"));
    child.kill().unwrap();
    let mut logs = String::new();
    child.stderr.take().unwrap().read_to_string(&mut logs).unwrap();
    child.wait().unwrap();
    let lines: Vec<Value> = logs.lines().map(|l| serde_json::from_str(l).unwrap_or_else(|_| panic!("{l:?}"))).collect();
    assert!(lines.iter().any(|l| l["message"] == "shapeflow serving"), "{logs}");
    assert!(
        lines.iter().any(|l| l["span"]["request_id"] == id.as_str() && l["span"]["uri"] == "/v1/jobs"),
        "a log line of the request with its id {id}: {logs}"
    );
}

/// `--retain 2s`: a job that ended is gone a few seconds later with its rows and
/// blobs, and the SQLite file gives the space back; a job still running stays.
#[test]
fn retention_deletes_ended_jobs_and_the_database_shrinks() {
    let dir = tempfile::tempdir().unwrap();
    let id = {
        let node = Node::start(dir.path(), &["--workers", "1"], "");
        let id = node.submit(STEADY);
        node.assert_complete(&id, 500, 11);
        id
    };
    // 300,000 more history rows: a file of some megabytes
    let db = dir.path().join("shapeflow.db");
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    rt.block_on(async {
        use sqlx::Connection;
        let mut conn = sqlx::SqliteConnection::connect(&format!("sqlite:{}", db.display())).await.unwrap();
        sqlx::query(
            "WITH RECURSIVE n(x) AS (SELECT 501 UNION ALL SELECT x + 1 FROM n WHERE x < 300500) \
             INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components) SELECT ?1, x, x * 1e-4, 1e-4, 1.0, 128, 1 FROM n",
        )
        .bind(&id)
        .execute(&mut conn)
        .await
        .unwrap();
        sqlx::query("PRAGMA wal_checkpoint(TRUNCATE)").execute(&mut conn).await.unwrap();
        conn.close().await.unwrap();
    });
    let full = std::fs::metadata(&db).unwrap().len();
    assert!(full > 8 << 20, "{full} bytes");
    assert!(dir.path().join("blobs/jobs").join(&id).exists());

    let node = Node::start(dir.path(), &["--workers", "1", "--retain", "2s"], "");
    // a job that runs on (a sphere: some hundred steps a second; a job writing
    // tens of thousands of history rows a second keeps SQLite's checkpoint from
    // giving the space back until it pauses, docs/operations.md)
    let running = node.submit(
        r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "sphere", "radius": 1.0, "resolution": 4},
            "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 1000000, "tolerance": 0},
            "output": {"checkpoint_every": 100000}}"#,
    );
    let start = Instant::now();
    while http_json(node.addr, "GET", &format!("/v1/jobs/{id}"), None).0 != 404 {
        assert!(start.elapsed() < Duration::from_secs(20), "the ended job is still there");
        std::thread::sleep(Duration::from_millis(100));
    }
    // its blobs after its rows, and the space after the batch
    let gone = || !dir.path().join("blobs/jobs").join(&id).exists() && std::fs::metadata(&db).unwrap().len() < full / 4;
    while !gone() && start.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(!dir.path().join("blobs/jobs").join(&id).exists(), "its blobs are gone");
    let (_, energy) = http_json(node.addr, "GET", &format!("/v1/jobs/{id}/energy"), None);
    assert_eq!(energy["status"], 404, "{energy}");
    let shrunk = std::fs::metadata(&db).unwrap().len();
    assert!(shrunk < full / 4, "the database file went from {full} to {shrunk} bytes");
    let (status, job) = http_json(node.addr, "GET", &format!("/v1/jobs/{running}"), None);
    assert_eq!(status, 200, "a running job is kept: {job}");
    assert_eq!(http(node.addr, "POST", &format!("/v1/jobs/{running}/cancel"), None, "").0, 202);
}

/// A DELETE answers at once: the job is gone from every read right away, and its
/// rows (here a million history rows) and blobs go in the background, a few
/// thousand rows a statement, while the service answers.
#[test]
fn a_delete_answers_at_once_and_the_rows_go_in_the_background() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("shapeflow.db");
    let node = Node::start(dir.path(), &["--workers", "1"], "");
    let id = node.submit(STEADY);
    node.assert_complete(&id, 500, 11);
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    // one query on a connection of its own: a count, or (`insert`) the rows it adds
    let query = |sql: &'static str, insert: bool| {
        rt.block_on(async {
            use sqlx::Connection;
            let mut conn = sqlx::SqliteConnection::connect(&format!("sqlite:{}", db.display())).await.unwrap();
            let n = match insert {
                true => sqlx::query(sql).bind(&id).execute(&mut conn).await.unwrap().rows_affected() as i64,
                false => sqlx::query_scalar(sql).bind(&id).fetch_one(&mut conn).await.unwrap(),
            };
            conn.close().await.unwrap();
            n
        })
    };
    let rows = |sql| query(sql, false);
    query(
        "WITH RECURSIVE n(x) AS (SELECT 501 UNION ALL SELECT x + 1 FROM n WHERE x < 1000500) \
         INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components) SELECT ?1, x, x * 1e-4, 1e-4, 1.0, 128, 1 FROM n",
        true,
    );
    assert!(rows("SELECT COUNT(*) FROM history WHERE job_id = ?1") > 1_000_000);

    let liveness = Liveness::watch(node.addr);
    assert_eq!(http(node.addr, "DELETE", &format!("/v1/jobs/{id}"), None, "").0, 204);
    assert_eq!(http_json(node.addr, "GET", &format!("/v1/jobs/{id}"), None).0, 404, "gone from reads at once");
    assert_eq!(http(node.addr, "DELETE", &format!("/v1/jobs/{id}"), None, "").0, 404);
    let (_, list) = http_json(node.addr, "GET", "/v1/jobs", None);
    assert!(list["jobs"].as_array().unwrap().is_empty(), "{list}");
    let start = Instant::now();
    while rows("SELECT COUNT(*) FROM jobs WHERE id = ?1") > 0 {
        assert!(start.elapsed() < Duration::from_secs(60), "the deleted job's rows are still there");
        std::thread::sleep(Duration::from_millis(200));
    }
    assert_eq!(rows("SELECT COUNT(*) FROM history WHERE job_id = ?1"), 0);
    assert_eq!(rows("SELECT COUNT(*) FROM checkpoints WHERE job_id = ?1"), 0);
    assert!(!dir.path().join("blobs/jobs").join(&id).exists(), "its blobs are gone");
    let slowest = liveness.slowest();
    assert!(slowest < 5_000, "/healthz answered within {slowest} ms while the rows went");
}
