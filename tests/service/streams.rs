//! Event streams (SSE with `Last-Event-ID` resume) and multipart image jobs.

use super::*;

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

/// Two spheres under mean curvature flow with surgery (`mesh.pinch_off: false`):
/// the small one shrinks away while the large one goes on.
const SHRINKING_SPHERES: &str = r#"{"problem": {"type": "curvature_flow", "gamma": 1.0},
    "initial": {"shape": "union", "parts": [
        {"shape": "sphere", "center": [-0.5, 0.0, 0.0], "radius": 0.1, "resolution": 3},
        {"shape": "sphere", "center": [0.5, 0.0, 0.0], "radius": 0.3, "resolution": 3}]},
    "flow": {"tau": 1e-4, "end_time": 0.004, "tolerance": 0},
    "mesh": {"pinch_off": false}}"#;

/// A topological surgery is in the progress event of the iteration it made, in
/// that iteration's history row and in shape.json, with its kind and place.
#[test]
fn a_surgery_is_in_the_events_the_history_and_shape_json() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 1);
    let (_, job) = srv.json("POST", "/v1/jobs", Some(SHRINKING_SPHERES));
    let id = job["id"].as_str().unwrap().to_string();
    let (status, _, body) = srv.request("GET", &format!("/v1/jobs/{id}/events"), None);
    assert_eq!(status, 200);
    let events: Vec<Value> = sse_events(&body)
        .iter()
        .filter(|e| e.0 == "progress")
        .map(|e| serde_json::from_str(&e.2).unwrap())
        .filter(|p: &Value| p.get("surgery").is_some())
        .collect();
    assert_eq!(events.len(), 1, "{events:?}");
    let (iteration, surgery) = (events[0]["iteration"].clone(), events[0]["surgery"].clone());
    assert_eq!(surgery["kind"], "vanish");
    assert_eq!(surgery["components"], 1);
    assert!((surgery["at"][0].as_f64().unwrap() + 0.5).abs() < 0.01, "{surgery}");
    assert_eq!(events[0]["components"], 1);
    let (_, history) = srv.json("GET", &format!("/v1/jobs/{id}/energy"), None);
    let rows: Vec<&Value> =
        history["history"].as_array().unwrap().iter().filter(|r| r.get("surgery").is_some()).collect();
    assert_eq!(rows.len(), 1);
    assert_eq!((&rows[0]["iteration"], &rows[0]["surgery"]), (&iteration, &surgery));
    let (_, shape) = srv.json("GET", &format!("/v1/jobs/{id}/results/shape.json"), None);
    let recorded = &shape["surgeries"][0];
    assert_eq!(
        (&recorded["iteration"], &recorded["kind"], &recorded["at"]),
        (&iteration, &surgery["kind"], &surgery["at"])
    );
    assert!(recorded["time"].as_f64().unwrap() > 0.0);
    srv.stop();
}
