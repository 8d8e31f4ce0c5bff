//! Jobs that cannot take the service down (docs/isolation.md): real `shapeflow
//! serve` processes on SQLite whose jobs run each in a process of their own and
//! are told to panic, abort, be killed, grow without end, hang or write without
//! end (faults injected by submission number through `SHAPEFLOW_TEST_FAULTS`,
//! which only debug builds read). Each test asserts the jobs' final status and
//! message, that `/healthz` answered within a second throughout, the server's
//! peak memory, that the other jobs' histories and checkpoints are complete and
//! that no job process is left.

use super::*;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// 500 iterations, a checkpoint every 50.
const STEADY: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 128},
    "flow": {"tau": 1e-4, "end_time": 0.05, "max_iterations": 100000, "tolerance": 0},
    "output": {"checkpoint_every": 50}}"#;

/// A `shapeflow serve` process on a SQLite file in `dir`.
struct Node {
    child: Child,
    addr: SocketAddr,
}

impl Node {
    fn start(dir: &std::path::Path, args: &[&str], faults: &str) -> Node {
        let addr: SocketAddr = format!("127.0.0.1:{}", free_port()).parse().unwrap();
        let child = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
            .args(["serve", "--bind", &addr.to_string(), "--data-dir"])
            .arg(dir)
            .args(args)
            .env("SHAPEFLOW_TEST_FAULTS", faults)
            .env("RUST_BACKTRACE", "0")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut node = Node { child, addr };
        let start = Instant::now();
        // up, or already ended (a job that aborts its server at once)
        while TcpStream::connect(addr).is_err() && node.child.try_wait().unwrap().is_none() {
            assert!(start.elapsed() < Duration::from_secs(20), "the server did not come up");
            std::thread::sleep(Duration::from_millis(20));
        }
        node
    }

    /// `VmRSS` or `VmHWM` (peak) of the server process, in bytes.
    fn memory(&self, field: &str) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let line = status.lines().find(|l| l.starts_with(field)).unwrap();
        line.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() * 1024
    }

    /// The job processes the server has now.
    fn job_processes(&self) -> usize {
        let me = self.child.id().to_string();
        std::fs::read_dir("/proc")
            .unwrap()
            .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("stat")).ok())
            .filter(|stat| stat.rsplit(')').next().and_then(|r| r.split_whitespace().nth(1)) == Some(me.as_str()))
            .count()
    }

    fn submit(&self, spec: &str) -> String {
        let (status, job) = http_json(self.addr, "POST", "/v1/jobs", Some(spec));
        assert_eq!(status, 201, "{job}");
        job["id"].as_str().unwrap().to_string()
    }

    fn wait_final(&self, id: &str) -> Value {
        wait_for(self.addr, id, |j| j["status"] != "accepted" && j["status"] != "running")
    }

    /// A successful job's every iteration once, and its checkpoints.
    fn assert_complete(&self, id: &str, iterations: u64, checkpoints: usize) -> f64 {
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

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// Polls `/healthz` every 50 ms until dropped; the slowest answer in ms.
struct Liveness {
    stop: Arc<AtomicBool>,
    slowest: Arc<AtomicU64>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Liveness {
    fn watch(addr: SocketAddr) -> Liveness {
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
    fn slowest(&self) -> u64 {
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

#[test]
fn jobs_that_panic_abort_die_or_outgrow_their_memory_end_only_their_own_attempts() {
    let dir = tempfile::tempdir().unwrap();
    let faults = "2=panic@30,3=kill@150:once,4=abort@20,5=grow@3,7=grow@3";
    let node = Node::start(dir.path(), &["--workers", "2", "--job-memory", "256MiB"], faults);
    let idle = node.memory("VmRSS");
    let live = Liveness::watch(node.addr);
    let mut ids: Vec<String> = (0..6).map(|_| node.submit(STEADY)).collect();
    // a spec that asks for less memory than the server's budget gets less
    let asking = STEADY.replacen('{', r#"{"limits": {"memory": "128MiB"}, "#, 1);
    ids.push(node.submit(&asking));
    let healthy = node.assert_complete(&ids[0], 500, 11);
    assert_eq!(node.assert_complete(&ids[5], 500, 11), healthy);

    let panicked = node.wait_final(&ids[1]);
    assert_eq!(panicked["status"], "failed", "{panicked}");
    let msg = panicked["message"].as_str().unwrap();
    assert!(
        msg.contains("on each of its 4 attempts") && msg.contains("panicked: an injected fault at iteration 30"),
        "{msg}"
    );
    assert!(!msg.contains(".rs") && !msg.contains("::"), "no internal path or Rust name: {msg}");

    // killed once: resumed from its checkpoint at 150, to the same end as a run without a kill
    let resumed = node.assert_complete(&ids[2], 500, 11);
    assert!((resumed - healthy).abs() <= 1e-12 * healthy.abs(), "{resumed} against {healthy}");

    let aborted = node.wait_final(&ids[3]);
    let msg = aborted["message"].as_str().unwrap();
    assert_eq!(aborted["status"], "failed", "{aborted}");
    assert!(msg.contains("on each of its 4 attempts") && msg.contains("signal 6 (SIGABRT"), "{msg}");

    let grown = node.wait_final(&ids[4]);
    assert_eq!(grown["status"], "failed", "{grown}");
    assert_eq!(grown["message"], "the job exceeded its memory budget of 256 MiB at iteration 3", "{grown}");
    let grown = node.wait_final(&ids[6]);
    assert_eq!(grown["message"], "the job exceeded its memory budget of 128 MiB at iteration 3", "{grown}");
    // more than the server allows: refused, naming the field
    let greedy = STEADY.replacen('{', r#"{"limits": {"memory": "4GiB"}, "#, 1);
    let (status, refused) = http_json(node.addr, "POST", "/v1/jobs", Some(&greedy));
    assert_eq!(status, 422, "{refused}");
    assert_eq!(refused["errors"][0]["field"], "limits.memory", "{refused}");
    assert_eq!(refused["errors"][0]["detail"], "asks for 4 GiB, more than this server's budget of 256 MiB per job");

    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    let peak = node.memory("VmHWM");
    assert!(peak < idle + (512 << 20), "the server grew from {idle} to {peak} bytes");
    assert_eq!(node.job_processes(), 0, "no job process is left");
}

#[test]
fn cancel_and_the_time_budget_end_a_jobs_process() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "2", "--job-seconds", "8"], "1=hang@5,2=hang@5");
    let live = Liveness::watch(node.addr);
    let (cancelled, timed) = (node.submit(STEADY), node.submit(STEADY));
    wait_for(node.addr, &cancelled, |j| j["progress"]["iteration"].as_u64().unwrap_or(0) >= 5);
    let asked = Instant::now();
    assert_eq!(http(node.addr, "POST", &format!("/v1/jobs/{cancelled}/cancel"), None, "").0, 202);
    let done = node.wait_final(&cancelled);
    // a process deaf to the cancellation is killed after its grace of 5 s
    assert!(asked.elapsed() < Duration::from_secs(7), "{:?}", asked.elapsed());
    assert_eq!(done["status"], "dismissed", "{done}");
    let done = node.wait_final(&timed);
    assert_eq!(done["status"], "failed", "{done}");
    assert_eq!(done["message"], "the job exceeded its time budget of 8 s at iteration 5", "{done}");
    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    assert_eq!(node.job_processes(), 0, "no job process is left");
}

/// The runaway spec of the issue: 20,000 vertices, a checkpoint at every step.
/// Its frames go to the blob store as they come (the server holds none of
/// them) and its disk budget ends it.
#[test]
fn a_job_that_writes_without_end_is_stopped_by_its_disk_budget() {
    let runaway = r#"{"problem": {"type": "curvature_flow"},
        "initial": {"shape": "circle", "radius": 1.0, "resolution": 20000},
        "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0},
        "mesh": {"adapt": false},
        "output": {"checkpoint_every": 1}}"#;
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "2", "--job-disk", "64MiB"], "");
    let idle = node.memory("VmRSS");
    let live = Liveness::watch(node.addr);
    let (runaway, other) = (node.submit(runaway), node.submit(STEADY));
    let done = node.wait_final(&runaway);
    assert_eq!(done["status"], "failed", "{done}");
    let msg = done["message"].as_str().unwrap();
    assert!(msg.starts_with("the job exceeded its disk budget of 64 MiB at iteration "), "{msg}");
    node.assert_complete(&other, 500, 11);
    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    let peak = node.memory("VmHWM");
    assert!(peak < idle + (512 << 20), "the server grew from {idle} to {peak} bytes");
}

/// Thread isolation: a job that aborts takes the server with it; each restart
/// counts an attempt, and after the last the job is failed, not run again.
#[test]
fn a_job_that_kills_its_server_is_not_run_past_its_attempts() {
    let dir = tempfile::tempdir().unwrap();
    let mut node = Node::start(dir.path(), &["--isolation", "thread", "--workers", "1"], "1=abort@20");
    let id = node.submit(STEADY);
    let mut starts = 1;
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < Duration::from_secs(120), "timed out");
        if node.child.try_wait().unwrap().is_some() {
            assert!(starts <= 4, "the job ran past its attempts");
            node = Node::start(dir.path(), &["--isolation", "thread", "--workers", "1"], "1=abort@20");
            starts += 1;
        } else if status_if_up(node.addr, &id).is_some_and(|j| j["status"] == "failed") {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let done = node.wait_final(&id);
    assert_eq!(starts, 5, "four attempts, then the job is failed at its fifth claim");
    assert_eq!(done["status"], "failed", "{done}");
    let msg = done["message"].as_str().unwrap();
    assert!(
        msg.contains("on each of its 4 attempts") && msg.contains("the service stopped while the job ran"),
        "{msg}"
    );
    let other = node.submit(STEADY);
    node.assert_complete(&other, 500, 11);
}

/// A job's status, or `None` if the server went away meanwhile.
fn status_if_up(addr: SocketAddr, id: &str) -> Option<Value> {
    let path = format!("/v1/jobs/{id}");
    std::panic::catch_unwind(|| http_json(addr, "GET", &path, None).1).ok()
}

/// A PNG of `side`² black pixels: a few kB that decode to `side`² samples.
fn black_png(side: u32) -> Vec<u8> {
    let img = image::GrayImage::new(side, side);
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// The issue's stack: one small PNG named 64 times as the slices of a volume is
/// refused from the slices' headers, before any is decoded; an image within the
/// limits that needs more memory to prepare than the job's budget is refused by
/// its validation's own process. The server's memory stays near its idle size.
#[test]
fn inputs_cost_what_they_say_before_they_are_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1", "--job-memory", "100MiB"], "");
    let idle = node.memory("VmRSS");
    let live = Liveness::watch(node.addr);
    let png = black_png(4096);
    assert!(png.len() < 128 * 1024, "{} bytes", png.len());
    let names: Vec<String> = (0..64).map(|k| format!("s{k}")).collect();
    let refs: Vec<String> = names.iter().map(|n| format!("\"input:{n}\"")).collect();
    let spec = format!(r#"{{"problem": {{"type": "segmentation", "image": [{}]}}}}"#, refs.join(", "));
    let mut parts: Vec<(&str, Option<&str>, &[u8])> = vec![("spec", None, spec.as_bytes())];
    parts.extend(names.iter().map(|n| (n.as_str(), Some("s.png"), png.as_slice())));
    let (ctype, body) = multipart(&parts);
    let asked = Instant::now();
    let (status, _, answer) = post_bytes(node.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(status, 422, "{answer}");
    assert!(asked.elapsed() < Duration::from_secs(2), "{:?}", asked.elapsed());
    let answer: Value = serde_json::from_str(&answer).unwrap();
    assert_eq!(answer["errors"][0]["field"], "problem.image", "{answer}");
    assert!(answer["detail"].as_str().unwrap().contains("4096×4096×64"), "{answer}");

    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image"}}"#;
    let (ctype, body) = multipart(&[("spec", None, spec.as_bytes()), ("image", Some("i.png"), &png)]);
    let (status, _, answer) = post_bytes(node.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(status, 422, "{answer}");
    let answer: Value = serde_json::from_str(&answer).unwrap();
    assert_eq!(answer["errors"][0]["field"], "problem.image", "{answer}");
    let detail = "needs more memory to prepare than the job's memory budget of 100 MiB";
    assert_eq!(answer["errors"][0]["detail"], detail, "{answer}");

    // a job that fits its budget runs
    let id = node.submit(STEADY);
    node.assert_complete(&id, 500, 11);
    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    let peak = node.memory("VmHWM");
    assert!(peak < idle + (100 << 20), "the server grew from {idle} to {peak} bytes");
}

/// A job with a million history rows (written into its database directly, as
/// an older server kept them): its energy as JSON, as CSV and as a plot, each
/// streamed with memory that does not grow with the rows.
#[test]
fn a_million_history_rows_are_served_in_little_memory() {
    let dir = tempfile::tempdir().unwrap();
    let id = {
        let node = Node::start(dir.path(), &["--workers", "1"], "");
        let id = node.submit(STEADY);
        node.assert_complete(&id, 500, 11);
        id
    };
    const ROWS: i64 = 1_000_000;
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    rt.block_on(async {
        use sqlx::Connection;
        let url = format!("sqlite:{}", dir.path().join("shapeflow.db").display());
        let mut db = sqlx::SqliteConnection::connect(&url).await.unwrap();
        sqlx::query("DELETE FROM history WHERE job_id = ?1").bind(&id).execute(&mut db).await.unwrap();
        sqlx::query(
            "WITH RECURSIVE n(x) AS (SELECT 0 UNION ALL SELECT x + 1 FROM n WHERE x < ?2 - 1) \
             INSERT INTO history SELECT ?1, x, x * 1e-4, 1e-4, 6.0 / (1.0 + x * 1e-4), 128, 1 FROM n",
        )
        .bind(&id)
        .bind(ROWS)
        .execute(&mut db)
        .await
        .unwrap();
        db.close().await.unwrap();
    });
    let node = Node::start(dir.path(), &["--workers", "1"], "");
    let idle = node.memory("VmRSS");
    let (status, _, json) = download(node.addr, &format!("/v1/jobs/{id}/energy"));
    assert_eq!(status, 200);
    let json: Value = serde_json::from_slice(&json).unwrap();
    let rows = json["history"].as_array().unwrap();
    assert_eq!(rows.len() as i64, ROWS);
    assert_eq!(rows[999_999]["iteration"], 999_999);
    drop(json);
    let (status, _, csv) = download(node.addr, &format!("/v1/jobs/{id}/energy?format=csv"));
    assert_eq!(status, 200);
    assert_eq!(csv.iter().filter(|&&b| b == b'\n').count() as i64, ROWS + 1);
    let (status, _, svg) = download(node.addr, &format!("/v1/jobs/{id}/energy.svg"));
    assert_eq!(status, 200);
    assert!(svg.starts_with(b"<svg") && svg.len() < 2 << 20, "{} bytes of plot", svg.len());
    let grown = node.memory("VmHWM").saturating_sub(idle);
    assert!(grown < 64 << 20, "the server grew by {grown} bytes serving a million rows");
}

/// Another process holds the SQLite write lock for longer than the lease: the
/// node is not ready meanwhile (`/healthz` still answers), the running job is
/// not taken over (one attempt, every iteration once) and the node is ready
/// again once the lock is let go. A floor of free disk space above the disk's
/// says so in `/readyz`.
#[test]
fn a_held_write_lock_is_a_wait_not_a_takeover_and_readyz_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1", "--lease-seconds", "1"], "");
    assert_eq!(http(node.addr, "GET", "/readyz", None, "").0, 200);
    let id = node.submit(LONG);
    wait_for(node.addr, &id, |j| j["progress"]["iteration"].as_u64().unwrap_or(0) > 100);
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    rt.block_on(async {
        use sqlx::Connection;
        let url = format!("sqlite:{}", dir.path().join("shapeflow.db").display());
        let mut db = sqlx::SqliteConnection::connect(&url).await.unwrap();
        let lock = db.begin_with("BEGIN IMMEDIATE").await.unwrap();
        let t = Instant::now();
        let (status, _, body) = http(node.addr, "GET", "/readyz", None, "");
        assert_eq!(status, 503, "{body}");
        assert!(body.contains("the database"), "{body}");
        assert!(t.elapsed() < Duration::from_secs(4), "{:?}", t.elapsed());
        let t = Instant::now();
        assert_eq!(http(node.addr, "GET", "/healthz", None, "").0, 200);
        assert!(t.elapsed() < Duration::from_secs(1));
        tokio::time::sleep(Duration::from_secs(4)).await; // four leases
        lock.rollback().await.unwrap();
    });
    let t = Instant::now();
    while http(node.addr, "GET", "/readyz", None, "").0 != 200 {
        assert!(t.elapsed() < Duration::from_secs(10), "not ready again");
        std::thread::sleep(Duration::from_millis(100));
    }
    let done = node.wait_final(&id);
    assert_eq!(done["status"], "successful", "{done}");
    assert!(done["message"].is_null(), "no attempt was abandoned: {done}");
    let (_, hist) = http_json(node.addr, "GET", &format!("/v1/jobs/{id}/energy"), None);
    let its: Vec<u64> = hist["history"].as_array().unwrap().iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
    let last = done["progress"]["iteration"].as_u64().unwrap();
    assert_eq!(its, (0..=last).collect::<Vec<_>>(), "every iteration once");
    drop(node);

    let node = Node::start(dir.path(), &["--workers", "1", "--min-free-disk", "1000TiB"], "");
    let (status, _, body) = http(node.addr, "GET", "/readyz", None, "");
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("less than the floor of 1000 TiB"), "{body}");
}

/// A tmpfs of `mib` MiB mounted on a temporary directory, unmounted when dropped.
struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    fn mount(mib: u32) -> Tmpfs {
        let dir = tempfile::tempdir().unwrap();
        let done = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={mib}m"), "tmpfs"])
            .arg(dir.path())
            .status()
            .unwrap();
        assert!(done.success(), "cannot mount a tmpfs");
        Tmpfs { dir }
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(self.dir.path()).status();
    }
}

/// The data disk fills up while a job writes: that job fails with a message
/// that names no path, `/readyz` says so, the jobs stored before are intact,
/// and once the failed job is deleted the writer is not wedged: `/readyz` is 200
/// again and a new job runs to its end.
#[test]
#[cfg_attr(not(shapeflow_mount), ignore = "needs root with CAP_SYS_ADMIN to mount a small tmpfs as the data disk")]
fn a_full_disk_fails_the_job_that_fills_it_and_the_service_heals() {
    let disk = Tmpfs::mount(24);
    let node = Node::start(disk.dir.path(), &["--workers", "1", "--min-free-disk", "4MiB"], "");
    let before = node.submit(STEADY);
    node.assert_complete(&before, 500, 11);
    let runaway = r#"{"problem": {"type": "curvature_flow"},
        "initial": {"shape": "circle", "radius": 1.0, "resolution": 20000},
        "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0},
        "mesh": {"adapt": false}, "output": {"checkpoint_every": 1}}"#;
    let filler = node.submit(runaway);
    let done = node.wait_final(&filler);
    assert_eq!(done["status"], "failed", "{done}");
    let msg = done["message"].as_str().unwrap();
    assert!(msg.contains("could not be stored") && !msg.contains('/') && !msg.contains("::"), "{msg}");
    let (status, _, body) = http(node.addr, "GET", "/readyz", None, "");
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("the data disk has"), "{body}");
    assert_eq!(http(node.addr, "DELETE", &format!("/v1/jobs/{filler}"), None, "").0, 204);
    let t = Instant::now();
    while http(node.addr, "GET", "/readyz", None, "").0 != 200 {
        assert!(t.elapsed() < Duration::from_secs(10), "{}", http(node.addr, "GET", "/readyz", None, "").2);
        std::thread::sleep(Duration::from_millis(100));
    }
    let after = node.submit(STEADY);
    node.assert_complete(&after, 500, 11);
    node.assert_complete(&before, 500, 11);
}
