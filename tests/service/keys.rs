//! Keys that own their jobs, on a real `shapeflow serve` process (docs/keys.md):
//! keys made with `shapeflow keys create` while it runs, each seeing only its own
//! jobs, an admin seeing all, a quota of active jobs, a revoked key refused, and
//! the service's cap on waiting jobs.

use super::nodes::Node;
use super::*;
use std::process::Command;

/// A million steps: stays accepted or running for the length of the test.
const SLOW: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
    "flow": {"tau": 1e-9, "end_time": 1.0, "max_iterations": 1000000, "tolerance": 0},
    "output": {"checkpoint_every": 100000}}"#;

/// `shapeflow keys ARGS --data-dir DIR`: its standard output.
fn keys(dir: &std::path::Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shapeflow"))
        .arg("keys")
        .args(args)
        .arg("--data-dir")
        .arg(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "keys {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn with(key: &str) -> String {
    format!("Authorization: Bearer {key}\r\n")
}

fn post(addr: SocketAddr, key: &str) -> (u16, String, Value) {
    let (status, head, body) = http(addr, "POST", "/v1/jobs", Some(("application/json", SLOW)), &with(key));
    (status, head, serde_json::from_str(&body).unwrap_or_default())
}

fn ids(addr: SocketAddr, key: &str) -> Vec<String> {
    let (status, _, body) = http(addr, "GET", "/v1/jobs", None, &with(key));
    assert_eq!(status, 200, "{body}");
    let list: Value = serde_json::from_str(&body).unwrap();
    list["jobs"].as_array().unwrap().iter().map(|j| j["id"].as_str().unwrap().to_string()).collect()
}

#[test]
fn each_key_sees_only_its_jobs_within_its_quota_and_a_revoked_key_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1"], "");
    // no key yet: open, as before
    let (status, open) = http_json(node.addr, "POST", "/v1/jobs", Some(SLOW));
    assert_eq!(status, 201, "{open}");
    let last_line = |out: String| out.lines().last().unwrap().to_string();
    let ana = last_line(keys(dir.path(), &["create", "ana", "--max-active", "3"]));
    let ben = last_line(keys(dir.path(), &["create", "ben"]));
    let root = last_line(keys(dir.path(), &["create", "root", "--admin"]));
    assert!(ana.starts_with("sf_") && ana.len() == 67, "{ana}");
    let stored = std::fs::read(dir.path().join("shapeflow.db")).unwrap();
    assert!(!stored.windows(ana.len()).any(|w| w == ana.as_bytes()), "the key itself is not stored");
    std::thread::sleep(shapeflow::service::keys::KEY_CACHE + Duration::from_millis(200));

    let (status, head, _) = http(node.addr, "GET", "/v1/jobs", None, "");
    assert_eq!(status, 401);
    assert!(head.to_ascii_lowercase().contains("www-authenticate: bearer"), "{head}");
    assert_eq!(http(node.addr, "GET", "/v1/jobs", None, &with("sf_0000")).0, 401);
    assert_eq!(http(node.addr, "GET", "/healthz", None, "").0, 200);

    // ten quick POSTs against a quota of three
    let answers: Vec<(u16, String, Value)> = (0..10).map(|_| post(node.addr, &ana)).collect();
    let created: Vec<String> =
        answers.iter().filter(|a| a.0 == 201).map(|a| a.2["id"].as_str().unwrap().to_string()).collect();
    assert_eq!(created.len(), 3, "{:?}", answers.iter().map(|a| a.0).collect::<Vec<_>>());
    for (status, head, body) in answers.iter().filter(|a| a.0 != 201) {
        assert_eq!(*status, 429, "{body}");
        assert!(head.to_ascii_lowercase().contains("retry-after: "), "{head}");
        assert!(body["detail"].as_str().unwrap().contains("3 jobs accepted or running"), "{body}");
    }
    let (status, _, bens) = post(node.addr, &ben);
    assert_eq!(status, 201, "another key is not held by ana's quota: {bens}");
    let bens = bens["id"].as_str().unwrap().to_string();

    let mut seen = ids(node.addr, &ana);
    seen.sort();
    let mut mine = created.clone();
    mine.sort();
    assert_eq!(seen, mine, "ana sees exactly her jobs");
    assert_eq!(ids(node.addr, &ben), vec![bens.clone()]);
    let all = ids(node.addr, &root);
    assert_eq!(all.len(), 5, "the admin sees every job: {all:?}");
    assert!(all.contains(&open["id"].as_str().unwrap().to_string()));
    let theirs = format!("/v1/jobs/{}", created[0]);
    for path in [theirs.clone(), format!("{theirs}/energy"), format!("{theirs}/results"), format!("{theirs}/events")] {
        assert_eq!(http(node.addr, "GET", &path, None, &with(&ben)).0, 404, "{path}");
    }
    assert_eq!(http(node.addr, "POST", &format!("{theirs}/cancel"), None, &with(&ben)).0, 404);
    assert_eq!(http(node.addr, "DELETE", &theirs, None, &with(&ben)).0, 404);
    assert_eq!(http(node.addr, "GET", &theirs, None, &with(&ana)).0, 200);
    // the admin manages them all
    for id in all {
        assert_eq!(http(node.addr, "POST", &format!("/v1/jobs/{id}/cancel"), None, &with(&root)).0, 202, "{id}");
    }

    let listed = keys(dir.path(), &["list"]);
    assert!(listed.contains("ana\tuser\tmax-active 3") && listed.contains("root\tadmin"), "{listed}");
    keys(dir.path(), &["revoke", "ana"]);
    std::thread::sleep(shapeflow::service::keys::KEY_CACHE + Duration::from_millis(200));
    assert_eq!(http(node.addr, "GET", "/v1/jobs", None, &with(&ana)).0, 401);
    assert_eq!(http(node.addr, "GET", "/v1/jobs", None, &with(&ben)).0, 200);
}

#[test]
fn the_service_queues_at_most_its_cap_of_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "0", "--max-queued", "2"], "");
    for _ in 0..2 {
        assert_eq!(http_json(node.addr, "POST", "/v1/jobs", Some(SLOW)).0, 201);
    }
    let (status, head, body) = http(node.addr, "POST", "/v1/jobs", Some(("application/json", SLOW)), "");
    assert_eq!(status, 503, "{body}");
    assert!(head.to_ascii_lowercase().contains("retry-after: "), "{head}");
    assert!(body.contains("2 jobs waiting"), "{body}");
}

/// Checkpoints at every step: a job that stores a lot quickly.
const HOARDER: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 256},
    "flow": {"tau": 1e-6, "end_time": 1.0, "max_iterations": 400, "tolerance": 0},
    "output": {"checkpoint_every": 1}}"#;

/// `--max-storage`: a running job stops at what is left of its key's quota
/// (failed, its checkpoints kept), the next POST is 429 while the key's jobs
/// keep that much, and deleting them makes room again.
#[test]
fn a_key_with_a_storage_quota_stops_at_it_and_is_refused_until_it_deletes() {
    let dir = tempfile::tempdir().unwrap();
    let node = Node::start(dir.path(), &["--workers", "1"], "");
    let cara = keys(dir.path(), &["create", "cara", "--max-storage", "300KiB"]).lines().last().unwrap().to_string();
    assert!(keys(dir.path(), &["list"]).contains("cara\tuser\tmax-active -\tmax-storage 300 KiB"));
    std::thread::sleep(shapeflow::service::keys::KEY_CACHE + Duration::from_millis(200));
    let submit = || http(node.addr, "POST", "/v1/jobs", Some(("application/json", HOARDER)), &with(&cara));
    let (status, _, body) = submit();
    assert_eq!(status, 201, "{body}");
    let id = serde_json::from_str::<Value>(&body).unwrap()["id"].as_str().unwrap().to_string();
    let start = Instant::now();
    let done = loop {
        let (_, _, body) = http(node.addr, "GET", &format!("/v1/jobs/{id}"), None, &with(&cara));
        let job: Value = serde_json::from_str(&body).unwrap();
        if job["status"] != "accepted" && job["status"] != "running" {
            break job;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "{job}");
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(done["status"], "failed", "{done}");
    assert!(done["message"].as_str().unwrap().contains("storage quota"), "{done}");
    let (_, _, cps) = http(node.addr, "GET", &format!("/v1/jobs/{id}/checkpoints"), None, &with(&cara));
    let kept = serde_json::from_str::<Value>(&cps).unwrap()["checkpoints"].as_array().unwrap().len();
    assert!((2..400).contains(&kept), "its checkpoints so far are kept: {kept}");

    let (status, head, body) = submit();
    assert_eq!(status, 429, "{body}");
    assert!(body.contains("storage quota is 300 KiB"), "{body}");
    assert!(head.to_ascii_lowercase().contains("retry-after: "), "{head}");
    assert_eq!(http(node.addr, "DELETE", &format!("/v1/jobs/{id}"), None, &with(&cara)).0, 204);
    let (status, _, body) = submit();
    assert_eq!(status, 201, "room again once deleted: {body}");
}
