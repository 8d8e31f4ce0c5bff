//! Storage that cannot take the service down (docs/isolation.md): inputs that
//! cost what they say, a million history rows served in little memory, a write
//! lock held by another process, a free-space floor, and a data disk that fills
//! up; on real `shapeflow serve` processes over SQLite, each asserting `/healthz`
//! and the server's peak memory where it matters.

use super::nodes::{Liveness, Node, STEADY};
use super::*;
use std::process::Command;

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

/// A job with a million history rows and 200,000 checkpoints (written into its
/// database directly, as an older server kept them): its energy as JSON, as CSV
/// and as a plot, and its list of checkpoints, each streamed with memory that
/// does not grow with the rows.
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
    const CHECKPOINTS: i64 = 200_000;
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    rt.block_on(async {
        use sqlx::Connection;
        let url = format!("sqlite:{}", dir.path().join("shapeflow.db").display());
        let mut db = sqlx::SqliteConnection::connect(&url).await.unwrap();
        sqlx::query("DELETE FROM history WHERE job_id = ?1").bind(&id).execute(&mut db).await.unwrap();
        sqlx::query(
            "WITH RECURSIVE n(x) AS (SELECT 0 UNION ALL SELECT x + 1 FROM n WHERE x < ?2 - 1) \
             INSERT INTO history (job_id, iteration, time, tau, energy, vertices, components) SELECT ?1, x, x * 1e-4, 1e-4, 6.0 / (1.0 + x * 1e-4), 128, 1 FROM n",
        )
        .bind(&id)
        .bind(ROWS)
        .execute(&mut db)
        .await
        .unwrap();
        // every added checkpoint row shares the frame of the last one
        sqlx::query(
            "WITH RECURSIVE n(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM n WHERE x < ?2) \
             INSERT INTO checkpoints (job_id, iteration, time, data, blob) \
             SELECT ?1, 500 + x, 0.05 + x * 1e-4, data, blob FROM n, \
             (SELECT data, blob FROM checkpoints WHERE job_id = ?1 AND iteration = 500)",
        )
        .bind(&id)
        .bind(CHECKPOINTS)
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
    let (status, _, list) = download(node.addr, &format!("/v1/jobs/{id}/checkpoints"));
    assert_eq!(status, 200);
    let list: Value = serde_json::from_slice(&list).unwrap();
    let list = list["checkpoints"].as_array().unwrap();
    assert_eq!(list.len() as i64, 11 + CHECKPOINTS);
    let last = &list[list.len() - 1];
    assert_eq!(last["iteration"], 500 + CHECKPOINTS);
    assert_eq!(last["href"], format!("/v1/jobs/{id}/checkpoints/{}.glb", 500 + CHECKPOINTS));
    let (status, _, glb) = download(node.addr, last["href"].as_str().unwrap());
    assert_eq!((status, &glb[..4]), (200, &b"glTF"[..]));
    let grown = node.memory("VmHWM").saturating_sub(idle);
    assert!(grown < 64 << 20, "the server grew by {grown} bytes serving a million rows and 200,000 checkpoints");
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
