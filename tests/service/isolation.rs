//! Jobs that cannot take the service down (docs/isolation.md): real `shapeflow
//! serve` processes on SQLite whose jobs run each in a process of their own and
//! are told to panic, abort, be killed, grow without end, hang or write without
//! end (faults injected by submission number through `SHAPEFLOW_TEST_FAULTS`,
//! which only debug builds read). Each test asserts the jobs' final status and
//! message, that `/healthz` answered within a second throughout, the server's
//! peak memory, that the other jobs' histories and checkpoints are complete and
//! that no job process is left.

use super::nodes::{Liveness, Node, STEADY};
use super::*;

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
    // a mesh whose run cannot fit the budget (163,842 vertices: about 400 MiB) is
    // refused before it is queued; the same mesh fits 1 GiB, a smaller one 128 MiB
    let sphere = |resolution: u32, limits: &str| {
        format!(
            r#"{{{limits}"problem": {{"type": "curvature_flow"}},
                "initial": {{"shape": "sphere", "radius": 1.0, "resolution": {resolution}}},
                "flow": {{"tau": 1e-4, "max_iterations": 1}}}}"#
        )
    };
    let (status, refused) = http_json(node.addr, "POST", "/v1/jobs", Some(&sphere(7, "")));
    assert_eq!(status, 422, "{refused}");
    assert_eq!(refused["errors"][0]["field"], "initial", "{refused}");
    let detail = refused["errors"][0]["detail"].as_str().unwrap();
    assert!(
        detail.contains("163842 vertices") && detail.ends_with("more than its memory budget of 256 MiB"),
        "{detail}"
    );
    let (status, refused) =
        http_json(node.addr, "POST", "/v1/jobs", Some(&sphere(6, r#""limits": {"memory": "64MiB"}, "#)));
    assert_eq!(status, 422, "{refused}");
    assert!(refused["errors"][0]["detail"].as_str().unwrap().ends_with("memory budget of 64 MiB"), "{refused}");
    let (status, accepted) = http_json(node.addr, "POST", "/v1/jobs", Some(&sphere(5, "")));
    assert_eq!(status, 201, "{accepted}");
    let fits = node.wait_final(accepted["id"].as_str().unwrap());
    assert_eq!(fits["status"], "successful", "{fits}");

    assert!(live.slowest() < 1000, "/healthz took {} ms", live.slowest());
    let peak = node.memory("VmHWM");
    assert!(peak < idle + (512 << 20), "the server grew from {idle} to {peak} bytes");
    assert_eq!(node.job_processes(), 0, "no job process is left");
    assert!(node.children() <= 2, "at most two processes wait for a job: {}", node.children());
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
    let spec = r#"{"problem": {"type": "curvature_flow"},
        "initial": {"shape": "circle", "radius": 1.0, "resolution": 20000},
        "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 10000000, "tolerance": 0},
        "mesh": {"adapt": false},
        "output": {"checkpoint_every": 1}}"#;
    let dir = tempfile::tempdir().unwrap();
    // the third is killed once at iteration 20: what its first attempt stored
    // counts against the budget of the second, which ends where the first did
    let node = Node::start(dir.path(), &["--workers", "2", "--job-disk", "64MiB"], "3=kill@20:once");
    let idle = node.memory("VmRSS");
    let live = Liveness::watch(node.addr);
    let (runaway, other) = (node.submit(spec), node.submit(STEADY));
    let done = node.wait_final(&runaway);
    assert_eq!(done["status"], "failed", "{done}");
    let msg = done["message"].as_str().unwrap();
    assert!(msg.starts_with("the job exceeded its disk budget of 64 MiB at iteration "), "{msg}");
    node.assert_complete(&other, 500, 11);
    let killed = node.submit(spec);
    let done = node.wait_final(&killed);
    assert_eq!(done["status"], "failed", "{done}");
    let msg = done["message"].as_str().unwrap();
    assert!(msg.starts_with("the job exceeded its disk budget of 64 MiB at iteration "), "{msg}");
    // (the iteration of the message is the run's, ahead of its frames)
    let stored = |id: &str| {
        let (_, list) = http_json(node.addr, "GET", &format!("/v1/jobs/{id}/checkpoints"), None);
        list["checkpoints"].as_array().unwrap().len() as i64
    };
    let (once, twice) = (stored(&runaway), stored(&killed));
    assert!(once > 20 && (twice - once).abs() <= 1, "killed once, it stored {twice} checkpoints, unkilled {once}");
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
