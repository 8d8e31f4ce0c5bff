//! What process isolation costs (docs/isolation.md), on `shapeflow serve`
//! processes over a temporary SQLite file, real HTTP on 127.0.0.1:
//! - a job's fixed cost: the wall time from POST to `successful` of a job stopped
//!   after one step (median of 21), with `--isolation thread` and `process`;
//! - the server's peak memory (VmHWM above its idle size) and the data written
//!   while the runaway spec (20,000 vertices, a checkpoint per step) runs against
//!   a 1 GiB disk budget, and for the GETs of a job with a million history rows.
//!
//! `cargo bench --bench isolation` (`-- fixed`: the fixed cost only).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

#[path = "common/node.rs"]
mod node;
use node::Node;

const EXE: &str = env!("CARGO_BIN_EXE_shapeflow");

const ONE_STEP: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
  "flow": {"tau": 1e-4, "end_time": 0.1, "max_iterations": 1, "tolerance": 0}, "output": {"checkpoint_every": 100}}"#;

const RUNAWAY: &str = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 20000},
  "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0}, "mesh": {"adapt": false},
  "output": {"checkpoint_every": 1}}"#;

impl Node {
    fn memory(&self, field: &str) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let line = status.lines().find(|l| l.starts_with(field)).unwrap();
        line.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() * 1024
    }

    fn request(&self, method: &str, path: &str, body: &str) -> (u16, String) {
        let mut s = TcpStream::connect(self.addr).unwrap();
        let ctype = if body.is_empty() { "" } else { "Content-Type: application/json\r\n" };
        let req = format!(
            "{method} {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n{ctype}Content-Length: {}\r\n\r\n{body}",
            body.len()
        );
        s.write_all(req.as_bytes()).unwrap();
        let mut out = Vec::new();
        s.read_to_end(&mut out).unwrap();
        let text = String::from_utf8_lossy(&out).to_string();
        let status = text.split_whitespace().nth(1).unwrap().parse().unwrap();
        (status, text.split_once("\r\n\r\n").map(|(_, b)| b.to_string()).unwrap_or_default())
    }

    fn submit(&self, spec: &str) -> String {
        let (status, body) = self.request("POST", "/v1/jobs", spec);
        assert_eq!(status, 201, "{body}");
        let v: serde_json::Value = serde_json::from_str(&body).unwrap();
        v["id"].as_str().unwrap().to_string()
    }

    fn wait_final(&self, id: &str) -> serde_json::Value {
        loop {
            let (_, body) = self.request("GET", &format!("/v1/jobs/{id}"), "");
            let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
            if v["status"] != "accepted" && v["status"] != "running" && !v["status"].is_null() {
                return v;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1 << 20) as f64
}

fn fixed_cost() {
    println!("| isolation | POST → successful, one-step job (median of 21) |");
    println!("|---|---|");
    for isolation in ["thread", "process"] {
        let dir = tempfile::tempdir().unwrap();
        let node = Node::start(EXE, dir.path(), &["--workers", "1", "--isolation", isolation]);
        node.wait_final(&node.submit(ONE_STEP)); // warm up
        let times: Vec<f64> = (0..21)
            .map(|_| {
                let t = Instant::now();
                let done = node.wait_final(&node.submit(ONE_STEP));
                assert_eq!(done["status"], "successful", "{done}");
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        println!("| {isolation} | {:.1} ms |", median(times));
    }
}

fn runaway() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(EXE, dir.path(), &["--workers", "1", "--job-disk", "1GiB"]);
    let idle = node.memory("VmRSS");
    let t = Instant::now();
    let done = node.wait_final(&node.submit(RUNAWAY));
    let used: u64 = walk(dir.path());
    println!(
        "| runaway spec, 1 GiB disk budget | {:+.0} MiB | {:.0} MiB written in {:.1} s; {} |",
        mib(node.memory("VmHWM").saturating_sub(idle)),
        mib(used),
        t.elapsed().as_secs_f64(),
        done["message"].as_str().unwrap_or("")
    );
}

fn walk(dir: &std::path::Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| match e.metadata() {
                    Ok(m) if m.is_dir() => walk(&e.path()),
                    Ok(m) => m.len(),
                    Err(_) => 0,
                })
                .sum()
        })
        .unwrap_or(0)
}

fn million_rows() {
    let dir = tempfile::tempdir().unwrap();
    let id = {
        let node = Node::start(EXE, dir.path(), &["--workers", "1"]);
        let id = node.submit(ONE_STEP);
        node.wait_final(&id);
        id
    };
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    rt.block_on(async {
        use sqlx::Connection;
        let url = format!("sqlite:{}", dir.path().join("shapeflow.db").display());
        let mut db = sqlx::SqliteConnection::connect(&url).await.unwrap();
        sqlx::query("DELETE FROM history WHERE job_id = ?1").bind(&id).execute(&mut db).await.unwrap();
        sqlx::query(
            "WITH RECURSIVE n(x) AS (SELECT 0 UNION ALL SELECT x + 1 FROM n WHERE x < 999999) \
             INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components) SELECT ?1, x, x * 1e-4, 1e-4, 6.0 / (1.0 + x * 1e-4), 128, 1 FROM n",
        )
        .bind(&id)
        .execute(&mut db)
        .await
        .unwrap();
    });
    for (what, path) in [
        ("energy (JSON)", format!("/v1/jobs/{id}/energy")),
        ("energy (CSV)", format!("/v1/jobs/{id}/energy?format=csv")),
        ("energy.svg", format!("/v1/jobs/{id}/energy.svg")),
    ] {
        let node = Node::start(EXE, dir.path(), &["--workers", "1"]);
        let idle = node.memory("VmRSS");
        let t = Instant::now();
        let (status, body) = node.request("GET", &path, "");
        assert_eq!(status, 200);
        println!(
            "| GET {what}, a million rows | {:+.0} MiB | {:.0} MiB in {:.2} s |",
            mib(node.memory("VmHWM").saturating_sub(idle)),
            mib(body.len() as u64),
            t.elapsed().as_secs_f64()
        );
    }
}

fn main() {
    fixed_cost();
    if std::env::args().any(|a| a == "fixed") {
        return;
    }
    println!();
    println!("| what | server's peak memory above idle | |");
    println!("|---|---|---|");
    runaway();
    million_rows();
}
