//! Bad requests (problem+json naming the field), body limits and tokens, and the
//! routes against the OpenAPI document.

use super::*;

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
