//! Where a job's bytes live and when its result files are made: inputs, frames
//! and result files are blobs (here the directory `blobs` beside the SQLite
//! file), the database keeps keys; an ended job's files are computed once, when
//! it ends, and served as stored; a running job shows its latest frame; an ended
//! job without stored files (an older version's, or one whose nodes kept dying)
//! gets them on the first request.

use crate::common::server::*;
use crate::common::validate_gltf;
use std::path::{Path, PathBuf};

const CIRCLE: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
    "flow": {"tau": 1e-3, "end_time": 0.05, "max_iterations": 100000, "tolerance": 0},
    "output": {"checkpoint_every": 10}}"#;

const LONG: &str = r#"{"problem": {"type": "surface_diffusion"},
    "initial": {"shape": "ellipse", "semi_axes": [1.0, 0.5], "resolution": 128},
    "flow": {"tau": 1e-6, "end_time": 0.02, "max_iterations": 1000000},
    "mesh": {"adapt": false, "regularize": false, "topology_changes": false},
    "output": {"checkpoint_every": 20}}"#;

/// Statements and one-number queries on the service's SQLite file (a second
/// connection beside the service's).
fn sql(db: &Path, statements: &[&str]) -> Vec<i64> {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let url = format!("sqlite:{}", db.display());
    rt.block_on(async {
        let pool = sqlx::SqlitePool::connect(&url).await.unwrap();
        let mut out = Vec::new();
        for s in statements {
            if s.starts_with("SELECT") {
                out.push(
                    sqlx::query_scalar::<_, i64>(sqlx::AssertSqlSafe(s.to_string())).fetch_one(&pool).await.unwrap(),
                );
            } else {
                sqlx::query(sqlx::AssertSqlSafe(s.to_string())).execute(&pool).await.unwrap();
            }
        }
        pool.close().await;
        out
    })
}

/// The folders of the job's result sets in the blob directory.
fn result_sets(dir: &Path, id: &str) -> Vec<PathBuf> {
    let results = dir.join("blobs/jobs").join(id).join("results");
    std::fs::read_dir(results).map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect()).unwrap_or_default()
}

/// A service on a temporary directory and its ended circle job.
fn ended_circle() -> (tempfile::TempDir, PathBuf, Server, String) {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("jobs.db");
    let srv = Server::start(&db, 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(CIRCLE));
    let id = job["id"].as_str().unwrap().to_string();
    srv.wait_for(&id, |j| j["status"] == "successful");
    (dir, db, srv, id)
}

#[test]
fn an_ended_jobs_files_are_stored_blobs_served_as_stored() {
    let (dir, db, srv, id) = ended_circle();
    // one result set, written by the worker, with the files the manifest lists
    let sets = result_sets(dir.path(), &id);
    assert_eq!(sets.len(), 1, "{sets:?}");
    let (_, manifest) = srv.json("GET", &format!("/v1/jobs/{id}/results"), None);
    let names: Vec<&str> = manifest["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "energy",
            "energy.csv",
            "energy.svg",
            "shape.json",
            "shape.glb",
            "shape.vtp",
            "evolution.glb",
            "evolution_vtk.zip"
        ]
    );
    for name in &names[3..] {
        let stored = std::fs::read(sets[0].join(name)).unwrap();
        let (s, head, served) = download(srv.addr, &format!("/v1/jobs/{id}/results/{name}"));
        assert_eq!(s, 200);
        assert_eq!(served, stored, "{name} is served as stored");
        let media = match name.rsplit('.').next() {
            Some("glb") => "model/gltf-binary",
            Some("vtp") => "application/xml",
            Some("zip") => "application/zip",
            _ => "application/json",
        };
        assert!(head.to_ascii_lowercase().contains(media), "{head}");
    }
    // served, not rebuilt: a changed blob is what the next GET returns
    let glb = sets[0].join("shape.glb");
    let original = std::fs::read(&glb).unwrap();
    std::fs::write(&glb, b"stored bytes").unwrap();
    assert_eq!(download(srv.addr, &format!("/v1/jobs/{id}/results/shape.glb")).2, b"stored bytes");
    std::fs::write(&glb, original).unwrap();
    // the rows hold keys: every checkpoint is a frame blob with its fields
    let counts = sql(
        &db,
        &[
            "SELECT COUNT(*) FROM checkpoints WHERE blob IS NULL OR length(data) > 0",
            "SELECT COUNT(*) FROM checkpoints",
            "SELECT COUNT(*) FROM jobs WHERE results IS NULL",
        ],
    );
    assert_eq!(counts[0], 0);
    assert_eq!(counts[1], 6, "iterations 0, 10, …, 50");
    assert_eq!(counts[2], 0);
    let frame = dir.path().join("blobs/jobs").join(&id).join("checkpoints");
    let first: serde_json::Value = serde_json::from_slice(&std::fs::read(frame.join("0.e1.json")).unwrap()).unwrap();
    assert_eq!(first["fields"]["curvature"].as_array().unwrap().len(), 64);
    // a checkpoint glb is encoded from its frame and validates
    let (s, _, bytes) = download(srv.addr, &format!("/v1/jobs/{id}/checkpoints/20.glb"));
    assert_eq!(s, 200);
    let file = dir.path().join("20.glb");
    std::fs::write(&file, bytes).unwrap();
    validate_gltf(&[file]);
    // deleting the job deletes its blobs (in the background, within a few seconds)
    assert_eq!(srv.request("DELETE", &format!("/v1/jobs/{id}"), None).0, 204);
    let asked = std::time::Instant::now();
    while dir.path().join("blobs/jobs").join(&id).exists() {
        assert!(asked.elapsed() < std::time::Duration::from_secs(20), "the deleted job's blobs are still there");
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    srv.stop();
}

#[test]
fn a_running_job_shows_its_latest_frame_and_image_results_come_at_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(LONG));
    let id = job["id"].as_str().unwrap().to_string();
    srv.wait_for(&id, |j| j["status"] == "running" && j["progress"]["iteration"].as_u64().unwrap_or(0) > 60);
    let (_, manifest) = srv.json("GET", &format!("/v1/jobs/{id}/results"), None);
    let names: Vec<&str> = manifest["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["energy", "energy.csv", "energy.svg", "shape.json", "shape.glb", "evolution.glb"]);
    let mut files = Vec::new();
    for name in ["shape.glb", "evolution.glb"] {
        let (s, _, bytes) = download(srv.addr, &format!("/v1/jobs/{id}/results/{name}"));
        assert_eq!(s, 200, "{name}");
        files.push(dir.path().join(name));
        std::fs::write(files.last().unwrap(), bytes).unwrap();
    }
    validate_gltf(&files);
    let (s, shape) = srv.json("GET", &format!("/v1/jobs/{id}/results/shape.json"), None);
    assert!(s == 200 && shape["iteration"].as_u64().unwrap() >= 20, "{shape}");
    // not an image job; nothing written for it yet either
    assert!(result_sets(dir.path(), &id).is_empty());
    assert_eq!(srv.request("POST", &format!("/v1/jobs/{id}/cancel"), None).0, 202);
    srv.wait_for(&id, |j| j["status"] == "dismissed");
    // a cancelled job's state is a result too
    assert_eq!(result_sets(dir.path(), &id).len(), 1);
    srv.stop();
}

#[test]
fn an_ended_job_without_stored_files_gets_them_on_first_request() {
    let (dir, db, srv, id) = ended_circle();
    let shape_before = download(srv.addr, &format!("/v1/jobs/{id}/results/shape.json")).2;
    // as an older version left it: checkpoints as JSON in their rows (no fields),
    // no result files, no glb context
    let frames = dir.path().join("blobs/jobs").join(&id).join("checkpoints");
    let last: serde_json::Value = serde_json::from_slice(&std::fs::read(frames.join("50.e1.json")).unwrap()).unwrap();
    let mut legacy = last.clone();
    legacy.as_object_mut().unwrap().remove("fields");
    let update = format!(
        "UPDATE checkpoints SET data = '{}', blob = NULL WHERE job_id = '{id}' AND iteration = 50",
        legacy.to_string().replace('\'', "''")
    );
    sql(&db, &[&update, "UPDATE jobs SET results = NULL"]);
    for set in result_sets(dir.path(), &id) {
        std::fs::remove_dir_all(set).unwrap();
    }
    std::fs::remove_file(dir.path().join("blobs/jobs").join(&id).join("context.json")).unwrap();
    std::fs::remove_file(frames.join("50.e1.json")).unwrap();
    // the first request computes and stores them; they match what the worker made
    let (_, manifest) = srv.json("GET", &format!("/v1/jobs/{id}/results"), None);
    assert_eq!(manifest["files"].as_array().unwrap().len(), 8, "{manifest}");
    assert_eq!(result_sets(dir.path(), &id).len(), 1);
    assert_eq!(download(srv.addr, &format!("/v1/jobs/{id}/results/shape.json")).2, shape_before);
    let (s, _, bytes) = download(srv.addr, &format!("/v1/jobs/{id}/checkpoints/50.glb"));
    assert_eq!(s, 200);
    let file = dir.path().join("50.glb");
    std::fs::write(&file, bytes).unwrap();
    validate_gltf(&[file]);
    assert_eq!(sql(&db, &["SELECT COUNT(*) FROM jobs WHERE results IS NULL"]), [0]);
    srv.stop();
}
