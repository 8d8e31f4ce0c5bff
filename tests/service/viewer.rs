//! The viewer page in a real headless browser (Debian's Chromium driven by
//! playwright-core, scripts/viewer_browser.mjs) against the service on 127.0.0.1
//! with a token: the 401 message, a job submitted through the form, its energy
//! plot and its shape drawn; an image job from the examples list with its image
//! dropped on the form, and its overlay; a job whose spheres merge, each frame
//! drawn and labelled with its number of components. CI installs Chromium (.ci/run) and sets
//! `SHAPEFLOW_REQUIRE_BROWSER=1`; elsewhere, without Chromium when the tests are
//! built (build.rs), the test shows as ignored with the reason.

use crate::common::server::{download_with, Server};
use serde_json::Value;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::Command;

const TOKEN: &str = "viewer-secret";

/// A circle under curvature flow, checkpointed every 10 iterations.
const SPEC: &str = r#"{"problem": {"type": "curvature_flow"},
  "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
  "flow": {"tau": 1e-3, "end_time": 0.1, "tolerance": 0},
  "output": {"checkpoint_every": 10}}"#;

/// Two spheres that grow into each other and merge (docs/problems/surface-evolution.md),
/// checkpointed before and after the merge.
const SURGERY: &str = r#"{"problem": {"type": "curvature_flow", "gamma": 1e-3, "lambda": -0.2},
  "initial": {"shape": "union", "parts": [
    {"shape": "sphere", "center": [-0.25, 0.0, 0.0], "radius": 0.2, "resolution": 2},
    {"shape": "sphere", "center": [0.25, 0.0, 0.0], "radius": 0.2, "resolution": 2}]},
  "flow": {"tau": 1e-3, "end_time": 0.3, "max_iterations": 5000, "tolerance": 0},
  "mesh": {"pinch_off": false},
  "output": {"checkpoint_every": 50}}"#;

fn chromium() -> Option<PathBuf> {
    let path = PathBuf::from(std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into()));
    path.exists().then_some(path)
}

/// `GET path` with the token: status and body bytes.
fn get(addr: SocketAddr, path: &str) -> (u16, Vec<u8>) {
    let (status, _, body) = download_with(addr, path, &format!("Authorization: Bearer {TOKEN}\r\n"));
    (status, body)
}

/// The number of primitives of a .glb: the meshes three.js draws for it.
fn primitives(glb: &[u8]) -> usize {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n["mesh"].as_u64())
        .map(|m| doc["meshes"][m as usize]["primitives"].as_array().unwrap().len())
        .sum()
}

#[test]
#[cfg_attr(
    not(shapeflow_browser),
    ignore = "needs Chromium (apt-get install chromium, or set CHROMIUM): .ci/run installs it"
)]
fn the_page_submits_a_job_and_draws_its_energy_and_shape() {
    let chromium = chromium().expect("Chromium was found when the tests were built, but not now");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(root.join("node_modules/playwright-core").exists(), "playwright-core is missing: run `npm ci` first");
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start_with(&dir.path().join("jobs.db"), 1, Some(TOKEN));
    let addr = srv.addr;

    let spec_file = dir.path().join("spec.json");
    std::fs::write(&spec_file, SPEC).unwrap();
    let surgery_file = dir.path().join("surgery.json");
    std::fs::write(&surgery_file, SURGERY).unwrap();
    let shots = root.join("target/viewer");
    std::fs::create_dir_all(&shots).unwrap();
    let out = Command::new("node")
        .arg(root.join("scripts/viewer_browser.mjs"))
        .arg(format!("http://{addr}"))
        .arg(TOKEN)
        .arg(&spec_file)
        .arg(&shots)
        .arg("segment_star")
        .arg(root.join("examples/data/star.png"))
        .arg(&surgery_file)
        .env("CHROMIUM", &chromium)
        .output()
        .expect("node");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "browser: {stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();

    // without the token the page says why it shows nothing, and asks for it
    assert!(report["unauthorized"].as_str().unwrap().contains("401"), "{report}");
    assert_eq!(report["tokenFormShown"], true, "{report}");
    // the job ran to its end
    let id = report["job"].as_str().unwrap();
    assert_eq!(report["status"], "successful", "{report}");
    let (s, body) = get(addr, &format!("/v1/jobs/{id}/energy"));
    assert_eq!(s, 200);
    let history: Value = serde_json::from_slice(&body).unwrap();
    let iterations = history["history"].as_array().unwrap().len();
    assert!(iterations >= 100, "{iterations}");
    // the energy plot holds every iteration and is drawn
    assert_eq!(report["points"].as_u64().unwrap() as usize, iterations, "{report}");
    assert!(report["energyInk"].as_u64().unwrap() > 500, "{report}");
    // the shape: every primitive of shape.glb rendered, the canvas not empty
    let (s, glb) = get(addr, &format!("/v1/jobs/{id}/results/shape.glb"));
    assert_eq!(s, 200);
    assert_eq!(report["meshes"].as_u64().unwrap() as usize, primitives(&glb), "{report}");
    assert!(report["shapeInk"].as_u64().unwrap() > 2000, "{report}");
    // one frame per checkpoint plus the result, the legend names the field
    let (_, list) = get(addr, &format!("/v1/jobs/{id}/checkpoints"));
    let checkpoints = serde_json::from_slice::<Value>(&list).unwrap()["checkpoints"].as_array().unwrap().len();
    assert_eq!(report["frames"].as_u64().unwrap() as usize, checkpoints + 1, "{report}");
    assert!(report["legend"].as_str().unwrap().contains("curvature"), "{report}");
    assert!(report["files"].as_array().unwrap().iter().any(|f| f == "shape.glb"), "{report}");
    // the image job: the example from the list, star.png dropped and named after its
    // input, the overlay at the image's size
    assert_eq!(report["dropped"], "image", "{report}");
    assert_eq!(report["imageStatus"], "successful", "{report}");
    let (s, _) = get(addr, &format!("/v1/jobs/{}/results/overlay.png", report["imageJob"].as_str().unwrap()));
    assert_eq!(s, 200);
    let star = image::image_dimensions(root.join("examples/data/star.png")).unwrap();
    assert_eq!(report["overlayWidth"].as_u64(), Some(star.0 as u64), "{report}");
    surgery_frames(addr, &report);
    assert_eq!(report["errors"], serde_json::json!([]), "{report}");

    srv.stop();
}

/// The merging spheres' job: every frame of the slider drawn (its primitives, ink on
/// the canvas), its label naming the components its checkpoint has by the job's
/// history, two before the merge and one after.
fn surgery_frames(addr: SocketAddr, report: &Value) {
    assert_eq!(report["surgeryStatus"], "successful", "{report}");
    let id = report["surgeryJob"].as_str().unwrap();
    let (_, body) = get(addr, &format!("/v1/jobs/{id}/energy"));
    let history: Value = serde_json::from_slice(&body).unwrap();
    let parts_at = |iteration: u64| {
        let rows = history["history"].as_array().unwrap();
        let row = rows.iter().rev().find(|r| r["iteration"].as_u64().unwrap() <= iteration).unwrap();
        row["components"].as_u64().unwrap()
    };
    let (_, list) = get(addr, &format!("/v1/jobs/{id}/checkpoints"));
    let list: Value = serde_json::from_slice(&list).unwrap();
    let mut expected: Vec<u64> =
        list["checkpoints"].as_array().unwrap().iter().map(|c| parts_at(c["iteration"].as_u64().unwrap())).collect();
    expected.push(parts_at(u64::MAX));
    let frames = report["surgeryFrames"].as_array().unwrap();
    assert_eq!(frames.len(), expected.len(), "{report}");
    assert_eq!((expected[0], expected[expected.len() - 1]), (2, 1), "the spheres merged: {expected:?}");
    for (frame, n) in frames.iter().zip(&expected) {
        let label = frame["label"].as_str().unwrap();
        let named = if *n == 1 { "1 component".to_string() } else { format!("{n} components") };
        assert!(label.ends_with(&named), "{label} for {n}: {report}");
        assert!(frame["meshes"].as_u64().unwrap() >= 1 && frame["ink"].as_u64().unwrap() > 2000, "{frame}");
    }
}
