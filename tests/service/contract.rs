//! The answers of a real server against the response schemas of
//! `api/openapi.yaml` (as served at `/v1/openapi.json`), checked by Ajv: the job,
//! the job list, the manifest, the checkpoint list and shape.json of a curve, a
//! surface and a segmentation, while running and once ended.

use super::*;
use std::path::Path;

/// The served document's schemas as one JSON Schema whose root is `name`'s.
fn schema_of(doc: &Value, name: &str) -> Value {
    let text = serde_json::to_string(&doc["components"]["schemas"]).unwrap();
    let defs: Value = serde_json::from_str(&text.replace("#/components/schemas/", "#/$defs/")).unwrap();
    serde_json::json!({ "$defs": defs, "$ref": format!("#/$defs/{name}") })
}

#[test]
fn answers_match_the_response_schemas_of_the_openapi_document() {
    let dir = tempfile::tempdir().unwrap();
    let srv = Server::start(&dir.path().join("jobs.db"), 2);
    let (_, doc) = srv.json("GET", "/v1/openapi.json", None);
    let curve = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
        "flow": {"tau": 1e-3, "max_iterations": 30}, "output": {"checkpoint_every": 10}}"#;
    let surface = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "sphere", "radius": 1.0, "resolution": 2},
        "flow": {"tau": 1e-3, "max_iterations": 20}, "output": {"checkpoint_every": 5}}"#;
    let mut ids = Vec::new();
    for spec in [curve, surface] {
        let (status, job) = srv.json("POST", "/v1/jobs", Some(spec));
        assert_eq!(status, 201, "{job}");
        ids.push(job);
    }
    let png = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/coins.png")).unwrap();
    let spec = r#"{"problem": {"type": "segmentation", "image": "input:image"}, "flow": {"max_iterations": 40}}"#;
    let (ctype, body) = multipart(&[("spec", None, spec.as_bytes()), ("image", Some("coins.png"), &png)]);
    let (status, _, job) = post_bytes(srv.addr, "/v1/jobs", &ctype, &body);
    assert_eq!(status, 201, "{job}");
    ids.push(serde_json::from_str(&job).unwrap());
    let ids: Vec<String> = ids.iter().map(|j| j["id"].as_str().unwrap().to_string()).collect();

    let mut answers: Vec<(&str, Value)> = Vec::new();
    let (_, running) = srv.json("GET", &format!("/v1/jobs/{}/results", ids[2]), None);
    answers.push(("Manifest", running));
    for id in &ids {
        let done = srv.wait_for(id, |j| j["status"] != "accepted" && j["status"] != "running");
        assert_eq!(done["status"], "successful", "{done}");
        answers.push(("Job", done));
        for (schema, path) in [
            ("Manifest", format!("/v1/jobs/{id}/results")),
            ("Checkpoints", format!("/v1/jobs/{id}/checkpoints")),
            ("ShapeJson", format!("/v1/jobs/{id}/results/shape.json")),
        ] {
            let (status, answer) = srv.json("GET", &path, None);
            assert_eq!(status, 200, "{path}: {answer}");
            answers.push((schema, answer));
        }
    }
    let (_, list) = srv.json("GET", "/v1/jobs", None);
    let listed = list["jobs"].as_array().unwrap().clone();
    assert_eq!(listed.len(), 3);
    answers.extend(listed.into_iter().map(|j| ("Job", j)));
    let shapes: Vec<u64> =
        answers.iter().filter(|a| a.0 == "ShapeJson").map(|a| a.1["dimension"].as_u64().unwrap()).collect();
    assert_eq!(shapes, vec![2, 3, 2]);
    assert!(answers.iter().any(|a| a.0 == "ShapeJson" && a.1["image"]["width"].is_u64()), "the segmentation's image");

    for name in ["Job", "Manifest", "Checkpoints", "ShapeJson"] {
        let schema = dir.path().join(format!("{name}.schema.json"));
        std::fs::write(&schema, serde_json::to_string(&schema_of(&doc, name)).unwrap()).unwrap();
        let files: Vec<_> = answers
            .iter()
            .enumerate()
            .filter(|(_, a)| a.0 == name)
            .map(|(k, a)| {
                let f = dir.path().join(format!("answer{k}.json"));
                std::fs::write(&f, serde_json::to_string(&a.1).unwrap()).unwrap();
                f
            })
            .collect();
        assert!(!files.is_empty());
        for (ok, line) in common::validate_json_schema(&schema, &files) {
            assert!(ok, "{name}: {line}");
        }
    }
    srv.stop();
}
