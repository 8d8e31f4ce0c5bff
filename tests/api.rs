//! The HTTP service over real HTTP on 127.0.0.1 against a temporary SQLite file.

mod common;

use common::server::*;
use common::validate_gltf;
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

const CIRCLE: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
    "flow": {"tau": 1e-3, "end_time": 0.1, "max_iterations": 100000, "tolerance": 0},
    "output": {"checkpoint_every": 20}}"#;

const LONG: &str = r#"{"problem": {"type": "surface_diffusion"},
    "initial": {"shape": "ellipse", "semi_axes": [1.0, 0.5], "resolution": 128},
    "flow": {"tau": 1e-6, "end_time": 0.02, "max_iterations": 1000000},
    "mesh": {"adapt": false, "regularize": false, "topology_changes": false},
    "output": {"checkpoint_every": 200}}"#;

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
fn bad_inputs_are_problem_json_naming_the_field_and_the_server_keeps_serving() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let cases = [
        ("{\"problem\": ", "(document)"),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "flow": {"taux": 1}}"#,
            "flow.taux",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "flow": {"tau": -1}}"#,
            "flow.tau",
        ),
        (
            r#"{"problem": {"type": "curvature_flow", "gamma": -2}, "initial": {"shape": "circle", "radius": 1}}"#,
            "problem.gamma",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "polygon", "points": [[0,0],[1,1],[1,0],[0,1]]}}"#,
            "initial",
        ),
        (r#"{"problem": {"type": "nonsense"}, "initial": {"shape": "circle", "radius": 1}}"#, "problem.type"),
        // wrong types inside the tagged objects are named too
        (
            r#"{"problem": {"type": "curvature_flow", "gamma": "1"}, "initial": {"shape": "circle", "radius": 1}}"#,
            "problem.gamma",
        ),
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "circle", "radius": 1}, {"shape": "circle", "radius": 1, "center": [0]}]}}"#,
            "initial.parts[1].center",
        ),
        // a key given twice (serde_json would keep the last silently)
        (
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1}, "problem": {"type": "surface_diffusion"}}"#,
            "problem",
        ),
        // NaN is not JSON: the document is malformed
        (r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": NaN}}"#, "(document)"),
        (
            r#"{"problem": {"type": "curvature_flow", "lambda": -1e999}, "initial": {"shape": "circle", "radius": 1}}"#,
            "(document)",
        ),
    ];
    for (body, field) in cases {
        let (status, head, b) = srv.request("POST", "/v1/jobs", Some(("application/json", body)));
        assert_eq!(status, 422, "{body}: {b}");
        assert!(head.to_ascii_lowercase().contains("content-type: application/problem+json"), "{head}");
        let p: Value = serde_json::from_str(&b).unwrap();
        assert_eq!(p["status"], 422);
        assert_eq!(p["errors"][0]["field"], field, "{b}");
    }
    assert_eq!(srv.request("POST", "/v1/jobs", Some(("text/plain", CIRCLE))).0, 415);
    assert_eq!(srv.request("GET", "/v1/jobs/does-not-exist", None).0, 404);
    // query parameters: 422 naming the parameter; unknown routes and methods: problem+json too
    for (path, parameter) in [
        ("/v1/jobs?limit=abc", "limit"),
        ("/v1/jobs?limit=0", "limit"),
        ("/v1/jobs?page_token=p-1", "page_token"),
        ("/v1/jobs?status=done", "status"),
        ("/v1/jobs?limit=5&limit=6", "limit"),
        ("/v1/jobs?stauts=running", "stauts"),
    ] {
        let (status, head, b) = srv.request("GET", path, None);
        assert_eq!(status, 422, "{path}: {b}");
        assert!(head.to_ascii_lowercase().contains("application/problem+json"), "{head}");
        let p: Value = serde_json::from_str(&b).unwrap();
        assert_eq!(
            (p["errors"][0]["field"].as_str(), p["title"].as_str()),
            (Some(parameter), Some("Invalid query parameter"))
        );
    }
    let (status, head, b) = srv.request("GET", "/v1/nope", None);
    assert_eq!(status, 404);
    assert!(head.to_ascii_lowercase().contains("application/problem+json") && b.contains("/v1/nope"), "{head}{b}");
    let (status, head, b) = srv.request("PUT", "/v1/jobs", Some(("application/json", CIRCLE)));
    assert_eq!(status, 405);
    let head = head.to_ascii_lowercase();
    assert!(
        head.contains("application/problem+json") && head.contains("allow: ") && head.contains("post,get"),
        "{head}{b}"
    );
    assert_eq!(srv.request("GET", "/healthz", None).0, 200);
    let (_, list) = srv.json("GET", "/v1/jobs", None);
    assert_eq!(list["jobs"].as_array().unwrap().len(), 0, "nothing was stored");
    srv.stop();
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

/// The routes of the router, `service::ROUTES` and `api/openapi.yaml` agree.
#[test]
fn router_and_openapi_document_list_the_same_routes() {
    let yaml = std::fs::read_to_string("api/openapi.yaml").unwrap();
    let mut documented = Vec::new();
    let mut path: Option<String> = None;
    for line in yaml.lines() {
        if let Some(p) = line.strip_prefix("  /").and_then(|l| l.strip_suffix(':')) {
            path = Some(format!("/{p}"));
        } else if !line.starts_with("    ") && !line.starts_with("  /") {
            path = None;
        } else if let Some(p) = &path {
            for m in ["get", "post", "delete", "put", "patch"] {
                if line.starts_with(&format!("    {m}:")) {
                    documented.push((m.to_uppercase(), p.clone()));
                }
            }
        }
    }
    let mut listed: Vec<(String, String)> =
        shapeflow::service::ROUTES.iter().map(|(m, p)| (m.to_string(), p.to_string())).collect();
    documented.sort();
    listed.sort();
    assert_eq!(documented, listed, "api/openapi.yaml vs service::ROUTES");
    // and every listed route exists in the router: an unknown job gives our own
    // problem+json 404 (or a success), never axum's empty 404/405
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    for (m, p) in &listed {
        let path = p.replace("{id}", "00000000-0000-0000-0000-000000000000");
        let body = (m == "POST" && p == "/v1/jobs").then_some(("application/json", CIRCLE));
        let (status, head, _) = srv.request(m, &path, body);
        assert!(status != 405, "{m} {p}: 405");
        if status == 404 {
            assert!(head.to_ascii_lowercase().contains("application/problem+json"), "{m} {p} is not routed");
        }
    }
    // the served document is api/openapi.yaml, as JSON, with the same routes
    let (s, doc) = srv.json("GET", "/v1/openapi.json", None);
    assert_eq!(s, 200);
    assert_eq!(doc["openapi"], "3.1.0");
    let mut served: Vec<(String, String)> = doc["paths"]
        .as_object()
        .unwrap()
        .iter()
        .flat_map(|(p, item)| {
            item.as_object().unwrap().keys().filter(|k| *k != "parameters").map(move |m| (m.to_uppercase(), p.clone()))
        })
        .collect();
    served.sort();
    assert_eq!(served, listed, "/v1/openapi.json vs service::ROUTES");
    // with the job spec's schema derived from its types in place of the YAML's outline
    let schemas = &doc["components"]["schemas"];
    assert_eq!(schemas["JobSpec"]["additionalProperties"], false);
    assert_eq!(schemas["JobSpec"]["properties"]["initial"]["anyOf"][0]["$ref"], "#/components/schemas/InitialSpec");
    assert!(schemas["InitialSpec"]["oneOf"].as_array().unwrap().len() >= 12);
    assert_eq!(schemas["Job"]["properties"]["id"]["format"], "uuid");
    srv.stop();
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

#[test]
fn oversized_bodies_get_413_with_the_limit_and_tokens_are_enforced() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let huge = format!("{{\"pad\": \"{}\"}}", "x".repeat(shapeflow::service::MAX_BODY_BYTES + 10));
    let (status, head, body) = srv.request("POST", "/v1/jobs", Some(("application/json", &huge)));
    assert_eq!(status, 413);
    assert!(head.to_ascii_lowercase().contains("application/problem+json"));
    assert!(body.contains(&shapeflow::service::MAX_BODY_BYTES.to_string()), "{body}");
    assert_eq!(srv.request("GET", "/healthz", None).0, 200);
    srv.stop();

    let srv = Server::start_with(&dir.path().join("secure.db"), 1, Some("s3cret"));
    assert_eq!(srv.request("GET", "/healthz", None).0, 200);
    let (status, head, body) = srv.request("GET", "/v1/jobs", None);
    assert_eq!(status, 401, "{body}");
    assert!(head.to_ascii_lowercase().contains("www-authenticate: bearer"), "{head}");
    assert_eq!(http(srv.addr, "GET", "/v1/jobs", None, "Authorization: Bearer s3cret\r\n").0, 200);
    srv.stop();
}

/// Parse an SSE body into (event, id, data) triples.
fn sse_events(body: &str) -> Vec<(String, Option<String>, String)> {
    body.split("\n\n")
        .filter_map(|block| {
            let (mut ev, mut id, mut data) = (String::from("message"), None, String::new());
            let mut any = false;
            for line in block.lines() {
                if let Some(v) = line.strip_prefix("event:") {
                    ev = v.trim().to_string();
                    any = true;
                } else if let Some(v) = line.strip_prefix("id:") {
                    id = Some(v.trim().to_string());
                } else if let Some(v) = line.strip_prefix("data:") {
                    data += v.trim();
                    any = true;
                }
            }
            any.then_some((ev, id, data))
        })
        .collect()
}

#[test]
fn events_stream_every_iteration_then_the_status_and_resume_after_last_event_id() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(CIRCLE));
    let id = job["id"].as_str().unwrap().to_string();
    let (status, head, body) = srv.request("GET", &format!("/v1/jobs/{id}/events"), None);
    assert_eq!(status, 200);
    assert!(head.to_ascii_lowercase().contains("text/event-stream"), "{head}");
    let events = sse_events(&body);
    let progress: Vec<u64> =
        events.iter().filter(|e| e.0 == "progress").map(|e| e.1.as_ref().unwrap().parse().unwrap()).collect();
    assert_eq!(progress, (0..=100).collect::<Vec<_>>());
    let last = events.last().unwrap();
    assert_eq!(last.0, "status");
    let j: Value = serde_json::from_str(&last.2).unwrap();
    assert_eq!(j["status"], "successful");
    // reconnect after iteration 50
    let mut s = TcpStream::connect(srv.addr).unwrap();
    write!(s, "GET /v1/jobs/{id}/events HTTP/1.1\r\nHost: x\r\nLast-Event-ID: 50\r\nConnection: close\r\n\r\n")
        .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let (_, b) = out.split_once("\r\n\r\n").unwrap();
    let again: Vec<u64> = sse_events(&dechunk(b))
        .iter()
        .filter(|e| e.0 == "progress")
        .map(|e| e.1.as_ref().unwrap().parse().unwrap())
        .collect();
    assert_eq!(again, (51..=100).collect::<Vec<_>>());
    srv.stop();
}

/// Multipart submission of an image job: the segmentation runs in the service and
/// mask.png, overlay.png and the glTF results download; bad uploads are 4xx
/// problem+json naming the field and the input, and the server keeps serving.
#[test]
fn multipart_segmentation_and_bad_uploads() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let png = std::fs::read("examples/data/star.png").unwrap();
    let spec = br#"{"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 300}}"#;
    let (ctype, body) = multipart(&[("spec", None, spec), ("image", Some("star.png"), &png)]);
    let (s, head, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 201, "{text}");
    assert!(head.to_ascii_lowercase().contains("location: /v1/jobs/"));
    let id = serde_json::from_str::<Value>(&text).unwrap()["id"].as_str().unwrap().to_string();
    let done = srv.wait_for(&id, |j| j["status"] != "accepted" && j["status"] != "running");
    assert_eq!(done["status"], "successful", "{done}");
    assert_eq!(done["stop_reason"], "converged");
    let (_, manifest) = srv.json("GET", &format!("/v1/jobs/{id}/results"), None);
    let mut glbs = Vec::new();
    for f in manifest["files"].as_array().unwrap() {
        let (s, _, bytes) = download(srv.addr, f["href"].as_str().unwrap());
        assert_eq!(s, 200, "{f}");
        let name = f["name"].as_str().unwrap();
        if name == "mask.png" {
            let mask = image::load_from_memory(&bytes).unwrap().to_luma8();
            assert_eq!(mask.dimensions(), (128, 128));
            let area = mask.pixels().filter(|p| p.0[0] == 255).count() as f64;
            let exact = std::f64::consts::PI * 34.0 * 34.0 * 1.045;
            assert!((area / exact - 1.0).abs() < 0.03, "{area}");
        }
        if name == "shape.json" {
            // the refined contour the mask shows, with pixel coordinates
            let shape: Value = serde_json::from_slice(&bytes).unwrap();
            assert_eq!(shape["image"]["width"], 128, "{shape}");
            assert!(shape["components"][0]["pixels"].as_array().is_some_and(|p| !p.is_empty()), "{shape}");
        }
        if name.ends_with(".glb") {
            let p = dir.path().join(name);
            std::fs::write(&p, &bytes).unwrap();
            glbs.push(p);
        }
    }
    assert!(manifest["files"].as_array().unwrap().iter().any(|f| f["name"] == "overlay.png"), "{manifest}");
    validate_gltf(&glbs);

    // bad uploads
    let mut zero = png.clone();
    zero[16..24].copy_from_slice(&[0; 8]);
    let cases: Vec<(Vec<u8>, u16, &str)> = vec![
        (png[..png.len() / 2].to_vec(), 422, "input `image`"),
        (zero, 422, "input `image`"),
        (b"GIF89a not really".to_vec(), 422, "input `image`"),
    ];
    for (bytes, want, needle) in cases {
        let (ctype, body) = multipart(&[("spec", None, spec), ("image", Some("x.png"), &bytes)]);
        let (s, head, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
        assert_eq!(s, want, "{text}");
        assert!(head.to_ascii_lowercase().contains("application/problem+json"), "{head}");
        let j: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(j["errors"][0]["field"], "problem.image", "{text}");
        assert!(j["detail"].as_str().unwrap().contains(needle), "{text}");
    }
    // no spec part; an input the spec does not get
    let (ctype, body) = multipart(&[("image", Some("star.png"), &png)]);
    let (s, _, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 422, "{text}");
    assert!(text.contains("\"spec\""), "{text}");
    let (ctype, body) = multipart(&[("spec", None, spec), ("picture", Some("star.png"), &png)]);
    let (s, _, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 422);
    assert!(text.contains("no input named"), "{text}");
    // a part the spec does not use, and the spec given twice
    let (ctype, body) = multipart(&[("spec", None, spec), ("image", Some("star.png"), &png), ("extra", None, b"x")]);
    let (s, _, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 422, "{text}");
    assert_eq!(serde_json::from_str::<Value>(&text).unwrap()["errors"][0]["field"], "extra", "{text}");
    let (ctype, body) = multipart(&[("spec", None, spec), ("spec", None, spec), ("image", Some("star.png"), &png)]);
    let (s, _, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 422, "{text}");
    assert!(text.contains("twice"), "{text}");
    // oversized upload: 413 with the limit
    let big = vec![0u8; shapeflow::service::MAX_UPLOAD_BYTES + 1024];
    let (ctype, body) = multipart(&[("spec", None, spec), ("image", Some("big.png"), &big)]);
    let (s, _, text) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(s, 413, "{text}");
    assert!(text.contains(&shapeflow::service::MAX_UPLOAD_BYTES.to_string()), "{text}");
    // still serving, and nothing bad was stored
    let (s, list) = srv.json("GET", "/v1/jobs", None);
    assert_eq!(s, 200);
    assert_eq!(list["jobs"].as_array().unwrap().len(), 1);
    srv.stop();
}
