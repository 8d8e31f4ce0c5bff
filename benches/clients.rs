//! What the layers that hold clients cost (docs/operations.md, docs/keys.md):
//! `GET /v1/jobs/{id}` and `POST /v1/jobs` latency (p50, p99) on one kept-alive
//! connection to `shapeflow serve` processes (release, SQLite, no workers: the
//! POSTs only validate and store), without a key, with the `--token`, and with a
//! stored key; beside the binary `SHAPEFLOW_BENCH_OLD_EXE` names (a build from
//! before these layers) when it is set; and GET latency while 1,000 idle
//! connections are open.
//!
//! `cargo bench --bench clients`.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::Command;
use std::time::Instant;

#[path = "common/node.rs"]
mod node;
use node::Node;

const SPEC: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
  "flow": {"tau": 1e-4, "max_iterations": 10}}"#;

/// One request on a kept-alive connection: its status and body.
fn request(conn: &mut BufReader<TcpStream>, method: &str, path: &str, auth: &str, body: &str) -> (u16, String) {
    let ctype = if body.is_empty() { "" } else { "Content-Type: application/json\r\n" };
    let req =
        format!("{method} {path} HTTP/1.1\r\nHost: x\r\n{auth}{ctype}Content-Length: {}\r\n\r\n{body}", body.len());
    conn.get_mut().write_all(req.as_bytes()).unwrap();
    let mut line = String::new();
    conn.read_line(&mut line).unwrap();
    let status = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let mut length = 0;
    loop {
        line.clear();
        conn.read_line(&mut line).unwrap();
        if line == "\r\n" {
            break;
        }
        if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
            length = v.trim().parse().unwrap();
        }
    }
    let mut body = vec![0; length];
    conn.read_exact(&mut body).unwrap();
    (status, String::from_utf8_lossy(&body).into_owned())
}

fn percentiles(mut ms: Vec<f64>) -> (f64, f64) {
    ms.sort_by(f64::total_cmp);
    (ms[ms.len() / 2], ms[ms.len() * 99 / 100])
}

/// p50 and p99 of GET and POST, in ms.
fn latencies(node: &Node, auth: &str) -> ((f64, f64), (f64, f64)) {
    let mut conn = BufReader::new(TcpStream::connect(node.addr).unwrap());
    conn.get_mut().set_nodelay(true).unwrap();
    let (status, body) = request(&mut conn, "POST", "/v1/jobs", auth, SPEC);
    assert_eq!(status, 201, "{body}");
    let id = serde_json::from_str::<serde_json::Value>(&body).unwrap()["id"].as_str().unwrap().to_string();
    let path = format!("/v1/jobs/{id}");
    let get: Vec<f64> = (0..3000)
        .map(|_| {
            let t = Instant::now();
            assert_eq!(request(&mut conn, "GET", &path, auth, "").0, 200);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let post: Vec<f64> = (0..200)
        .map(|_| {
            let t = Instant::now();
            assert_eq!(request(&mut conn, "POST", "/v1/jobs", auth, SPEC).0, 201);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    (percentiles(get[500..].to_vec()), percentiles(post[20..].to_vec()))
}

fn row(what: &str, ((g50, g99), (p50, p99)): ((f64, f64), (f64, f64))) {
    println!("| {what} | {g50:.3} / {g99:.3} ms | {p50:.2} / {p99:.2} ms |");
}

fn main() {
    rlimit::increase_nofile_limit(4096).unwrap();
    let new = env!("CARGO_BIN_EXE_shapeflow");
    println!("| server | GET /v1/jobs/{{id}} p50 / p99 | POST /v1/jobs p50 / p99 |");
    println!("|---|---|---|");
    if let Ok(old) = std::env::var("SHAPEFLOW_BENCH_OLD_EXE") {
        let dir = tempfile::tempdir().unwrap();
        row(
            "before (axum::serve, one shared token at most), no token",
            latencies(&Node::start(&old, dir.path(), &["--workers", "0"]), ""),
        );
        let dir = tempfile::tempdir().unwrap();
        let node = Node::start(&old, dir.path(), &["--workers", "0", "--token", "t0ken"]);
        row("before, with --token", latencies(&node, "Authorization: Bearer t0ken\r\n"));
    }
    let dir = tempfile::tempdir().unwrap();
    row("now, no key", latencies(&Node::start(new, dir.path(), &["--workers", "0"]), ""));
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(new, dir.path(), &["--workers", "0", "--token", "t0ken"]);
    row("now, with --token", latencies(&node, "Authorization: Bearer t0ken\r\n"));
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(new).args(["keys", "create", "bench", "--data-dir"]).arg(dir.path()).output().unwrap();
    let key = String::from_utf8(out.stdout).unwrap().lines().last().unwrap().to_string();
    let node = Node::start(new, dir.path(), &["--workers", "0"]);
    row("now, a stored key", latencies(&node, &format!("Authorization: Bearer {key}\r\n")));

    // 1,000 idle connections open (within the header timeout of 10 s)
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(new, dir.path(), &["--workers", "0", "--max-connections", "2000"]);
    let idle: Vec<TcpStream> = (0..1000).map(|_| TcpStream::connect(node.addr).unwrap()).collect();
    row("now, no key, 1,000 idle connections open", latencies(&node, ""));
    drop(idle);
}
