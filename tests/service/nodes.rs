//! Real `shapeflow serve` processes on a SQLite file for the tests of isolation
//! and storage: start one with its flags and injected faults
//! (`SHAPEFLOW_TEST_FAULTS`, read by debug builds only), its memory, its job
//! processes, and a watch of `/healthz`'s answers.

use super::*;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// 500 iterations, a checkpoint every 50.
pub(super) const STEADY: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 128},
    "flow": {"tau": 1e-4, "end_time": 0.05, "max_iterations": 100000, "tolerance": 0},
    "output": {"checkpoint_every": 50}}"#;

/// A `shapeflow serve` process on a SQLite file in `dir`.
pub(super) struct Node {
    pub child: Child,
    pub addr: SocketAddr,
}

impl Node {
    /// The server listens on a port the system gives it (`--bind 127.0.0.1:0`),
    /// read from its log line `shapeflow serving address=…`: a port picked by
    /// the test and freed before the server binds it could be taken meanwhile
    /// by another test's server, which this test would then talk to.
    pub(super) fn start(dir: &std::path::Path, args: &[&str], faults: &str) -> Node {
        let mut child = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
            .args(["serve", "--bind", "127.0.0.1:0", "--data-dir"])
            .arg(dir)
            .args(args)
            .env("SHAPEFLOW_TEST_FAULTS", faults)
            .env("RUST_BACKTRACE", "0")
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // the log read to its end, so that the server never waits on a full pipe
        let logs = child.stderr.take().unwrap();
        let (found, address) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            use std::io::BufRead;
            let (mut logs, mut bytes) = (std::io::BufReader::new(logs), Vec::new());
            while logs.read_until(b'\n', &mut bytes).is_ok_and(|n| n > 0) {
                let line = String::from_utf8_lossy(&bytes).into_owned();
                bytes.clear();
                if let Some(at) = line.find("shapeflow serving").and_then(|i| line[i..].find("address=").map(|j| i + j))
                {
                    let addr = line[at + "address=".len()..].split_whitespace().next().unwrap_or("").to_string();
                    let _ = found.send(addr);
                }
            }
        });
        // up, or already ended (a job that aborts its server at once: nothing
        // listens on a freed port)
        let addr = match address.recv_timeout(Duration::from_secs(20)) {
            Ok(a) => a.parse().unwrap_or_else(|e| panic!("the server's address {a:?}: {e}")),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                format!("127.0.0.1:{}", free_port()).parse().unwrap()
            }
            Err(e) => panic!("the server did not come up: {e}"),
        };
        Node { child, addr }
    }

    /// `VmRSS` or `VmHWM` (peak) of the server process, in bytes.
    pub(super) fn memory(&self, field: &str) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let line = status.lines().find(|l| l.starts_with(field)).unwrap();
        line.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() * 1024
    }

    /// The job processes the server has now (named `shapeflow-job` once they
    /// have a job; those started ahead of their jobs are not counted).
    pub(super) fn job_processes(&self) -> usize {
        let me = self.child.id().to_string();
        std::fs::read_dir("/proc")
            .unwrap()
            .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("stat")).ok())
            .filter(|stat| stat.contains("(shapeflow-job)"))
            .filter(|stat| stat.rsplit(')').next().and_then(|r| r.split_whitespace().nth(1)) == Some(me.as_str()))
            .count()
    }

    /// The server's child processes, job processes and those waiting for a job.
    pub(super) fn children(&self) -> usize {
        let me = self.child.id().to_string();
        std::fs::read_dir("/proc")
            .unwrap()
            .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("stat")).ok())
            .filter(|stat| stat.rsplit(')').next().and_then(|r| r.split_whitespace().nth(1)) == Some(me.as_str()))
            .count()
    }

    pub(super) fn submit(&self, spec: &str) -> String {
        let (status, job) = http_json(self.addr, "POST", "/v1/jobs", Some(spec));
        assert_eq!(status, 201, "{job}");
        job["id"].as_str().unwrap().to_string()
    }

    pub(super) fn wait_final(&self, id: &str) -> Value {
        wait_for(self.addr, id, |j| j["status"] != "accepted" && j["status"] != "running")
    }

    /// A successful job's every iteration once, and its checkpoints.
    pub(super) fn assert_complete(&self, id: &str, iterations: u64, checkpoints: usize) -> f64 {
        let done = self.wait_final(id);
        assert_eq!(done["status"], "successful", "{done}");
        let (_, hist) = http_json(self.addr, "GET", &format!("/v1/jobs/{id}/energy"), None);
        let rows = hist["history"].as_array().unwrap();
        let its: Vec<u64> = rows.iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
        assert_eq!(its, (0..=iterations).collect::<Vec<_>>(), "job {id}: every iteration once");
        let (_, cps) = http_json(self.addr, "GET", &format!("/v1/jobs/{id}/checkpoints"), None);
        assert_eq!(cps["checkpoints"].as_array().unwrap().len(), checkpoints, "job {id}: {cps}");
        rows.last().unwrap()["energy"].as_f64().unwrap()
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub(super) fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// Polls `/healthz` every 50 ms until dropped; the slowest answer in ms.
pub(super) struct Liveness {
    stop: Arc<AtomicBool>,
    slowest: Arc<AtomicU64>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Liveness {
    pub(super) fn watch(addr: SocketAddr) -> Liveness {
        let (stop, slowest) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicU64::new(0)));
        let (s, w) = (stop.clone(), slowest.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                let t = Instant::now();
                let ok = http(addr, "GET", "/healthz", None, "").0 == 200;
                let ms = if ok { t.elapsed().as_millis() as u64 } else { u64::MAX };
                w.fetch_max(ms, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(50));
            }
        });
        Liveness { stop, slowest, thread: Some(thread) }
    }

    /// The slowest answer so far, in ms.
    pub(super) fn slowest(&self) -> u64 {
        self.slowest.load(Ordering::Relaxed)
    }
}

impl Drop for Liveness {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
