//! A job's life through the API: submit, poll, download, cancel, delete; restarts
//! and kill -9 of the server; many jobs on two workers.

use super::*;

#[test]
fn submit_poll_download_delete() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 2);
    let (status, head, body) = srv.request("POST", "/v1/jobs", Some(("application/json", CIRCLE)));
    assert_eq!(status, 201, "{body}");
    let job: Value = serde_json::from_str(&body).unwrap();
    let id = job["id"].as_str().unwrap().to_string();
    assert!(head.to_ascii_lowercase().contains(&format!("location: /v1/jobs/{id}")), "{head}");
    let done = srv.wait_for(&id, |j| j["status"] != "accepted" && j["status"] != "running");
    assert_eq!(done["status"], "successful", "{done}");
    assert_eq!(done["stop_reason"], "end_time");
    assert!(done["message"].is_null(), "{done}");
    assert_eq!(done["progress"]["iteration"], 100);
    // energy history: every iteration, decreasing
    let (s, _, csv) = srv.request("GET", &format!("/v1/jobs/{id}/energy?format=csv"), None);
    assert_eq!(s, 200);
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 102, "header + iterations 0..=100");
    let (_, hist) = srv.json("GET", &format!("/v1/jobs/{id}/energy"), None);
    let energies: Vec<f64> =
        hist["history"].as_array().unwrap().iter().map(|r| r["energy"].as_f64().unwrap()).collect();
    assert_eq!(energies.len(), 101);
    assert!(energies.windows(2).all(|w| w[1] < w[0]));
    // the shape: a circle of radius √(1 − 2t)
    let (s, shape) = srv.json("GET", &format!("/v1/jobs/{id}/results/shape.json"), None);
    assert_eq!(s, 200);
    let exact = (1.0f64 - 0.2).sqrt();
    for v in shape["components"][0]["vertices"].as_array().unwrap() {
        let r = v[0].as_f64().unwrap().hypot(v[1].as_f64().unwrap());
        assert!((r - exact).abs() < 5e-3, "radius {r}");
    }
    let (s, _, b) = srv.request("GET", &format!("/v1/jobs/{id}/results/foo.txt"), None);
    assert!(s == 404 && b.contains("no result \\\"foo.txt\\\"") && b.contains("/results lists"), "{b}");
    let (s, _, b) = srv.request("GET", &format!("/v1/jobs/{id}/results/mask.png"), None);
    assert!(s == 404 && b.contains("not an image job"), "{b}");
    let (s, head, svg) = srv.request("GET", &format!("/v1/jobs/{id}/energy.svg"), None);
    assert_eq!(s, 200);
    assert!(head.to_ascii_lowercase().contains("image/svg+xml"));
    assert_eq!(svg.split("points=\"").nth(1).unwrap().split('"').next().unwrap().split(' ').count(), 101);
    // the manifest, the glTF results and the checkpoints: every file downloads and
    // every glb passes the Khronos validator
    let (s, manifest) = srv.json("GET", &format!("/v1/jobs/{id}/results"), None);
    assert_eq!(s, 200);
    assert_eq!(manifest["final"], true);
    let names: Vec<&str> = manifest["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap()).collect();
    for want in ["shape.json", "shape.glb", "evolution.glb", "energy.csv", "energy.svg"] {
        assert!(names.contains(&want), "{names:?}");
    }
    let mut glbs = Vec::new();
    for f in manifest["files"].as_array().unwrap() {
        let (s, head, bytes) = download(srv.addr, f["href"].as_str().unwrap());
        assert_eq!(s, 200, "{f}");
        assert!(head.to_ascii_lowercase().contains(f["type"].as_str().unwrap()), "{head}");
        if f["name"].as_str().unwrap().ends_with(".glb") {
            assert_eq!(&bytes[..4], b"glTF");
            let p = dir.path().join(f["name"].as_str().unwrap());
            std::fs::write(&p, &bytes).unwrap();
            glbs.push(p);
        }
    }
    let (s, cps) = srv.json("GET", &format!("/v1/jobs/{id}/checkpoints"), None);
    assert_eq!(s, 200);
    let cps = cps["checkpoints"].as_array().unwrap().clone();
    let its: Vec<i64> = cps.iter().map(|c| c["iteration"].as_i64().unwrap()).collect();
    assert_eq!(its.first(), Some(&0));
    assert_eq!(its.last(), Some(&100));
    let (s, _, bytes) = download(srv.addr, cps[1]["href"].as_str().unwrap());
    assert_eq!(s, 200);
    let p = dir.path().join("checkpoint.glb");
    std::fs::write(&p, &bytes).unwrap();
    glbs.push(p);
    assert_eq!(srv.request("GET", &format!("/v1/jobs/{id}/checkpoints/7.glb"), None).0, 404);
    assert_eq!(srv.request("GET", &format!("/v1/jobs/{id}/checkpoints/x.png"), None).0, 404);
    validate_gltf(&glbs);
    let (s, list) = srv.json("GET", "/v1/jobs?status=successful", None);
    assert_eq!(s, 200);
    assert_eq!(list["jobs"].as_array().unwrap().len(), 1);
    assert_eq!(srv.request("DELETE", &format!("/v1/jobs/{id}"), None).0, 204);
    assert_eq!(srv.request("GET", &format!("/v1/jobs/{id}"), None).0, 404);
    srv.stop();
}

/// A run that stops at `tau_min` is successful and its message says why: the
/// square's corners move at `κ ≈ 25` against neighbours at rest, so the geometric
/// control asks for τ ≈ 1e-3, below `tau_min`.
#[test]
fn a_tau_min_stop_says_why_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let spec = r#"{"problem": {"type": "curvature_flow"},
        "initial": {"shape": "rectangle", "size": [1.0, 1.0], "resolution": 64},
        "mesh": {"adapt": false, "regularize": false},
        "flow": {"tau": 1e-2, "tau_min": 5e-3}}"#;
    let (status, _, body) = srv.request("POST", "/v1/jobs", Some(("application/json", spec)));
    assert_eq!(status, 201, "{body}");
    let id = serde_json::from_str::<Value>(&body).unwrap()["id"].as_str().unwrap().to_string();
    let done = srv.wait_for(&id, |j| j["status"] != "accepted" && j["status"] != "running");
    assert_eq!(
        (done["status"].as_str(), done["stop_reason"].as_str()),
        (Some("successful"), Some("tau_min")),
        "{done}"
    );
    let message = done["message"].as_str().unwrap_or_default();
    assert!(message.contains("geometric step control"), "{done}");
}

#[test]
fn cancel_a_running_job_and_refuse_to_delete_it_while_running() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(LONG));
    let id = job["id"].as_str().unwrap().to_string();
    srv.wait_for(&id, |j| j["status"] == "running" && j["progress"]["iteration"].as_u64().unwrap_or(0) > 200);
    assert_eq!(srv.request("DELETE", &format!("/v1/jobs/{id}"), None).0, 409);
    assert_eq!(srv.request("POST", &format!("/v1/jobs/{id}/cancel"), None).0, 202);
    let done = srv.wait_for(&id, |j| j["status"] != "running");
    assert_eq!(done["status"], "dismissed", "{done}");
    // its checkpoints are kept
    assert_eq!(srv.request("GET", &format!("/v1/jobs/{id}/results/shape.json"), None).0, 200);
    assert_eq!(srv.request("POST", &format!("/v1/jobs/{id}/cancel"), None).0, 409);
    assert_eq!(srv.request("DELETE", &format!("/v1/jobs/{id}"), None).0, 204);
    srv.stop();
}

#[test]
fn a_stopped_server_resumes_its_running_job_on_restart_without_losing_history() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("jobs.db");
    let srv = Server::start(&db, 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(LONG));
    let id = job["id"].as_str().unwrap().to_string();
    srv.wait_for(&id, |j| j["progress"]["iteration"].as_u64().unwrap_or(0) > 500);
    srv.stop();
    let srv = Server::start(&db, 1);
    let done = srv.wait_for(&id, |j| j["status"] != "accepted" && j["status"] != "running");
    assert_eq!(done["status"], "successful", "{done}");
    let (_, hist) = srv.json("GET", &format!("/v1/jobs/{id}/energy"), None);
    let its: Vec<u64> = hist["history"].as_array().unwrap().iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
    let last = done["progress"]["iteration"].as_u64().unwrap();
    assert_eq!(its, (0..=last).collect::<Vec<_>>(), "every iteration once");
    srv.stop();
}

/// kill -9 of the real binary mid-job, then a restart on the same database: the job
/// resumes from its last checkpoint and finishes; no history row is lost or doubled.
#[test]
fn kill_9_mid_job_then_restart_resumes_and_finishes() {
    use std::process::{Child, Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    // the database goes into --data-dir (created by the server)
    let data = dir.path().join("data");
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let spawn = || -> Child {
        let child = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
            .args(["serve", "--bind", &addr.to_string(), "--workers", "1", "--database", "jobs.db", "--data-dir"])
            .arg(&data)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while TcpStream::connect(addr).is_err() {
            assert!(start.elapsed() < Duration::from_secs(20), "server did not come up");
            std::thread::sleep(Duration::from_millis(20));
        }
        child
    };
    let call = |method: &str, path: &str, body: Option<&str>| http_json(addr, method, path, body);
    let wait = |id: &str, pred: &dyn Fn(&Value) -> bool| wait_for(addr, id, pred);
    let mut first = spawn();
    assert!(data.join("jobs.db").exists(), "the database is in --data-dir");
    let (s, job) = call("POST", "/v1/jobs", Some(LONG));
    assert_eq!(s, 201);
    let id = job["id"].as_str().unwrap().to_string();
    wait(&id, &|j| j["progress"]["iteration"].as_u64().unwrap_or(0) > 700);
    first.kill().unwrap(); // SIGKILL
    first.wait().unwrap();
    let mut second = spawn();
    let done = wait(&id, &|j| j["status"] != "accepted" && j["status"] != "running");
    assert_eq!(done["status"], "successful", "{done}");
    let (_, hist) = call("GET", &format!("/v1/jobs/{id}/energy"), None);
    let its: Vec<u64> = hist["history"].as_array().unwrap().iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
    let last = done["progress"]["iteration"].as_u64().unwrap();
    assert_eq!(its, (0..=last).collect::<Vec<_>>(), "every iteration exactly once");
    second.kill().unwrap();
    second.wait().unwrap();
}

#[test]
fn twenty_jobs_on_two_workers_all_finish_with_complete_histories() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 2);
    let spec = r#"{"problem": {"type": "curvature_flow"},
        "initial": {"shape": "circle", "radius": 1.0, "resolution": 48},
        "flow": {"tau": 1e-3, "end_time": 0.05, "max_iterations": 1000, "tolerance": 0},
        "output": {"checkpoint_every": 10}}"#;
    let ids: Vec<String> = (0..20)
        .map(|_| {
            let (s, j) = srv.json("POST", "/v1/jobs", Some(spec));
            assert_eq!(s, 201);
            j["id"].as_str().unwrap().to_string()
        })
        .collect();
    for id in &ids {
        let done = srv.wait_for(id, |j| j["status"] != "accepted" && j["status"] != "running");
        assert_eq!(done["status"], "successful", "{done}");
        let (_, hist) = srv.json("GET", &format!("/v1/jobs/{id}/energy"), None);
        let its: Vec<u64> =
            hist["history"].as_array().unwrap().iter().map(|r| r["iteration"].as_u64().unwrap()).collect();
        assert_eq!(its, (0..=50).collect::<Vec<_>>(), "job {id}");
    }
    // paging: 7 per page, newest first, every job exactly once
    let mut seen = Vec::new();
    let mut token: Option<String> = None;
    let mut pages = 0;
    loop {
        let path = match &token {
            Some(t) => format!("/v1/jobs?limit=7&page_token={t}"),
            None => "/v1/jobs?limit=7".to_string(),
        };
        let (s, page) = srv.json("GET", &path, None);
        assert_eq!(s, 200);
        pages += 1;
        seen.extend(page["jobs"].as_array().unwrap().iter().map(|j| j["id"].as_str().unwrap().to_string()));
        match page["next_page_token"].as_str() {
            Some(t) => token = Some(t.to_string()),
            None => break,
        }
    }
    assert_eq!(pages, 3);
    let newest_first: Vec<String> = ids.iter().rev().cloned().collect();
    assert_eq!(seen, newest_first);
    assert_eq!(srv.request("GET", "/v1/jobs?page_token=zzz", None).0, 422);
    assert_eq!(srv.request("GET", "/v1/jobs?status=done", None).0, 422);
    assert_eq!(srv.request("GET", "/v1/jobs?limit=0", None).0, 422);
    srv.stop();
}
