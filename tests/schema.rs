//! The job spec's JSON Schema (`api/job-spec.schema.json`, derived from the parser's
//! types) against the parser: Ajv (npm `ajv`, installed by `npm ci`) and
//! `parse_spec` + `prepare` must agree on the examples, on malformed specs and on
//! every bound the schema states.

mod common;

use common::validate_json_schema;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::Path;

/// docs/job-spec-reference.md is the reference generated from the schema
/// (`shapeflow schema --markdown`), and it names every field of every spec object.
#[test]
fn the_job_spec_reference_is_current() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let committed = std::fs::read_to_string(root.join("docs/job-spec-reference.md")).unwrap();
    let schema = shapeflow::jobs::job_spec_schema();
    let generated = shapeflow::jobs::job_spec_reference(&schema);
    assert!(
        committed.trim_end() == generated.trim_end(),
        "docs/job-spec-reference.md is stale: run `cargo run -- schema --markdown > docs/job-spec-reference.md`"
    );
    for field in ["tau", "end_time", "edge_contrast", "checkpoint_every", "topology_changes", "wetting_layer"] {
        assert!(committed.contains(&format!("| `{field}`")), "{field}");
    }
}

/// `api/job-spec.schema.json` is the schema derived from the spec's types (`shapeflow
/// schema`); Ajv (draft 2020-12, strict) accepts every example and rejects what the
/// parser rejects for its shape: unknown or misspelt fields, a missing `problem`, an
/// unknown `type` or `shape`, a wrong type deep in a union.
#[test]
fn job_spec_schema_is_current_and_agrees_with_the_parser() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let schema_path = root.join("api/job-spec.schema.json");
    let committed = std::fs::read_to_string(&schema_path).unwrap();
    let derived = serde_json::to_string_pretty(&shapeflow::jobs::job_spec_schema()).unwrap() + "\n";
    assert!(
        committed == derived,
        "api/job-spec.schema.json is stale: run `cargo run -- schema > api/job-spec.schema.json`"
    );

    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut expect = Vec::new();
    let mut examples: Vec<_> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    examples.sort();
    assert!(examples.len() >= 15);
    for p in examples {
        expect.push(true);
        files.push(p);
    }
    let circle = r#""initial": {"shape": "circle", "radius": 1}"#;
    let cases = [
        (true, format!(r#"{{"problem": {{"type": "curvature_flow"}}, {circle}}}"#)),
        (true, r#"{"problem": {"type": "segmentation", "image": ["input:a", "input:b"]}}"#.to_string()),
        (true, r#"{"problem": {"type": "surface_diffusion"}, "initial": {"shape": "mesh", "file": "input:m"}}"#.into()),
        (
            true,
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "circle", "radius": 1}, {"shape": "rectangle", "center": [3, 0], "size": [1, 2]}]}, "flow": {"scalar_product": "h1", "tau": 0.01}, "mesh": {"h_min": null}}"#.into(),
        ),
        (false, format!(r#"{{"problem": {{"type": "curvature_flow"}}, {circle}, "flw": {{}}}}"#)),
        (false, format!(r#"{{"problem": {{"type": "curvature_flow", "gama": 1}}, {circle}}}"#)),
        (false, circle.replace("\"initial\": ", "{\"initial\": ") + "}"),
        (false, format!(r#"{{"problem": {{"type": "mean_curvature"}}, {circle}}}"#)),
        (false, r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "disc", "radius": 1}}"#.into()),
        (
            false,
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "circle", "radius": "1"}]}}"#.into(),
        ),
        (false, format!(r#"{{"problem": {{"type": "curvature_flow"}}, {circle}, "flow": {{"scalar_product": "h2"}}}}"#)),
        (false, format!(r#"{{"problem": {{"type": "curvature_flow"}}, {circle}, "output": {{"checkpoint_every": -1}}}}"#)),
    ];
    for (i, (valid, text)) in cases.iter().enumerate() {
        assert_eq!(shapeflow::jobs::parse_spec(text).is_ok(), *valid, "the parser on case {i}: {text}");
        let p = dir.path().join(format!("case{i}.json"));
        std::fs::write(&p, text).unwrap();
        expect.push(*valid);
        files.push(p);
    }
    let report = validate_json_schema(&schema_path, &files);
    for ((ok, line), want) in report.iter().zip(&expect) {
        assert_eq!(ok, want, "{line}");
    }
}

/// A 32×32 PNG: a bright square on a dark ground.
fn square_png() -> Vec<u8> {
    let img = image::GrayImage::from_fn(32, 32, |x, y| {
        image::Luma([if (8..24).contains(&x) && (8..24).contains(&y) { 200 } else { 20 }])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Every bound the schema states (`exclusiveMinimum`, `minimum`, `maximum`,
/// `minItems`) and every rule between fields (`initial` and `problem.type`) is one
/// the parser enforces: a value just outside it is rejected by both, the parser
/// naming the field, and the value on an inclusive bound is accepted by both.
#[test]
fn the_schema_bounds_and_rules_are_the_parser_ones() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let curve =
        json!({"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1.0, "resolution": 16}});
    let diffusion = json!({"problem": {"type": "surface_diffusion"}, "initial": {"shape": "sphere", "radius": 1.0, "resolution": 1}});
    let design = json!({"problem": {"type": "shape_design", "outer": {"shape": "circle", "radius": 3.0},
        "control": {"inner": {"shape": "circle", "radius": 1.5}, "outer": {"shape": "square", "size": 3.6}},
        "target": {"type": "log_radial", "radius": 3.0}}, "initial": {"shape": "circle", "radius": 0.5, "resolution": 16}});
    let film = json!({"problem": {"type": "stressed_film", "length": 1.0}, "initial": {"shape": "film", "height": 0.5, "resolution": 16}});
    let polyline = json!({"problem": {"type": "stressed_film", "length": 1.0},
        "initial": {"shape": "film_polyline", "points": [[0.0, 0.5], [0.3, 0.6], [0.6, 0.5]], "resolution": 16}});
    let segmentation = json!({"problem": {"type": "segmentation", "image": "input:img"}});
    let with = |base: &Value, path: &str, v: Value| {
        let mut s = base.clone();
        let (parent, key) = path.rsplit_once('/').unwrap();
        s.pointer_mut(parent).unwrap().as_object_mut().unwrap().insert(key.to_string(), v);
        s
    };
    let shape = |base: &Value, initial: Value| with(base, "/initial", initial);
    // (spec, valid, the field a rejection names)
    let mut cases: Vec<(Value, bool, &str)> = vec![
        (with(&curve, "/problem/gamma", json!(0.0)), false, "problem.gamma"),
        (with(&diffusion, "/problem/gamma", json!(-1.0)), false, "problem.gamma"),
        (with(&curve, "/initial/radius", json!(0.0)), false, "initial.radius"),
        (with(&curve, "/initial/resolution", json!(2)), false, "initial.resolution"),
        (with(&curve, "/initial/resolution", json!(3)), true, ""),
        (with(&curve, "/initial/resolution", json!(2_000_001)), false, "initial.resolution"),
        (
            shape(&diffusion, json!({"shape": "ellipsoid", "semi_axes": [1.0, 0.5, 0.5], "resolution": 9})),
            false,
            "initial.resolution",
        ),
        (shape(&curve, json!({"shape": "ellipse", "semi_axes": [1.0, 0.0]})), false, "initial.semi_axes[1]"),
        (shape(&curve, json!({"shape": "rectangle", "size": [-1.0, 1.0]})), false, "initial.size[0]"),
        (with(&diffusion, "/initial/resolution", json!(9)), false, "initial.resolution"),
        (with(&diffusion, "/initial/radius", json!(-2.0)), false, "initial.radius"),
        (shape(&diffusion, json!({"shape": "ellipsoid", "semi_axes": [1.0, 0.0, 1.0]})), false, "initial.semi_axes[1]"),
        (shape(&diffusion, json!({"shape": "box", "size": [1.0, 1.0, 0.0]})), false, "initial.size[2]"),
        (
            shape(&diffusion, json!({"shape": "box", "size": [1.0, 1.0, 1.0], "resolution": 0.0})),
            false,
            "initial.resolution",
        ),
        (
            shape(&diffusion, json!({"shape": "torus", "major_radius": 0.0, "minor_radius": 0.2})),
            false,
            "initial.major_radius",
        ),
        (
            shape(&diffusion, json!({"shape": "torus", "major_radius": 1.0, "minor_radius": 0.0})),
            false,
            "initial.minor_radius",
        ),
        (
            shape(&diffusion, json!({"shape": "torus", "major_radius": 1.0, "minor_radius": 0.2, "resolution": 2})),
            false,
            "initial.resolution",
        ),
        (
            shape(&diffusion, json!({"shape": "torus", "major_radius": 1.0, "minor_radius": 0.2, "resolution": 4097})),
            false,
            "initial.resolution",
        ),
        (with(&design, "/problem/gamma", json!(-0.1)), false, "problem.gamma"),
        (with(&design, "/problem/gamma", json!(0.0)), true, ""),
        (with(&design, "/problem/spacing", json!(0.0)), false, "problem.spacing"),
        (with(&design, "/problem/outer/radius", json!(0.0)), false, "problem.outer.radius"),
        (with(&design, "/problem/control/inner/radius", json!(-1.5)), false, "problem.control.inner.radius"),
        (with(&design, "/problem/control/outer/size", json!(-3.6)), false, "problem.control.outer.size"),
        (with(&design, "/problem/target/radius", json!(0.0)), false, "problem.target.radius"),
        (with(&film, "/problem/length", json!(0.0)), false, "problem.length"),
        (with(&film, "/problem/gamma", json!(0.0)), false, "problem.gamma"),
        (with(&film, "/problem/wetting_layer", json!(0.0)), false, "problem.wetting_layer"),
        (with(&film, "/problem/bending", json!(-1e-3)), false, "problem.bending"),
        (with(&film, "/problem/bending", json!(0.0)), true, ""),
        (with(&film, "/initial/height", json!(0.0)), false, "initial.height"),
        (with(&film, "/initial/mode", json!(0)), false, "initial.mode"),
        (with(&film, "/initial/resolution", json!(7)), false, "initial.resolution"),
        (with(&film, "/initial/resolution", json!(8)), true, ""),
        (with(&film, "/initial/resolution", json!(100_001)), false, "initial.resolution"),
        (with(&polyline, "/initial/points", json!([[0.0, 0.5], [0.5, 0.5]])), false, "initial.points"),
        (with(&polyline, "/initial/resolution", json!(7)), false, "initial.resolution"),
        (with(&polyline, "/initial/resolution", json!(100_001)), false, "initial.resolution"),
        (with(&segmentation, "/problem/sigma", json!(64.5)), false, "problem.sigma"),
        (with(&segmentation, "/problem/sigma", json!(-0.5)), false, "problem.sigma"),
        (with(&segmentation, "/problem/sigma", json!(0.0)), true, ""),
        (with(&segmentation, "/problem/lambda", json!(-1.0)), false, "problem.lambda"),
        (with(&segmentation, "/problem/lambda_final", json!(-1.0)), false, "problem.lambda_final"),
        (with(&segmentation, "/problem/epsilon", json!(0.0)), false, "problem.epsilon"),
        (with(&segmentation, "/problem/channel", json!(256)), false, "problem.channel"),
        (with(&segmentation, "/problem/channel", json!(0)), true, ""),
        (with(&segmentation, "/problem/time_point", json!(-1)), false, "problem.time_point"),
        (with(&segmentation, "/problem/time_point", json!(1_000_001)), false, "problem.time_point"),
        (with(&segmentation, "/problem/time_point", json!(0)), true, ""),
        (with(&segmentation, "/problem/min_separation", json!(0.5)), false, "problem.min_separation"),
        (with(&segmentation, "/problem/min_separation", json!(10_001.0)), false, "problem.min_separation"),
        (with(&segmentation, "/problem/min_separation", json!(1.0)), true, ""),
        (with(&curve, "/output", json!({"checkpoint_every": 0})), false, "output.checkpoint_every"),
        (with(&curve, "/output", json!({"checkpoint_every": 1})), true, ""),
        // rules between fields that the schema states: only segmentation may leave
        // `initial` out, film shapes are for the stressed film and only for it
        (json!({"problem": {"type": "curvature_flow"}}), false, "initial"),
        (with(&design, "/initial", Value::Null), false, "initial"),
        (with(&segmentation, "/initial", Value::Null), true, ""),
        (shape(&film, json!({"shape": "circle", "radius": 0.1})), false, "initial.shape"),
        (shape(&curve, json!({"shape": "film", "height": 0.5})), false, "initial.shape"),
        // inputs are named `input:NAME`
        (with(&segmentation, "/problem/image", json!("img")), false, "problem.image"),
        (with(&segmentation, "/problem/image", json!([])), false, "problem.image"),
        (with(&segmentation, "/problem/image", json!(["input:img", "img"])), false, "problem.image[1]"),
        (shape(&curve, json!({"shape": "mesh", "file": "m.obj"})), false, "initial.file"),
    ];
    // the curve resolution bounds of the other curve shapes (the circle's are above)
    for curve_shape in [
        json!({"shape": "ellipse", "semi_axes": [1.0, 0.5]}),
        json!({"shape": "rectangle", "size": [1.0, 0.5]}),
        json!({"shape": "polygon", "points": [[0, 0], [1, 0], [0, 1]]}),
    ] {
        for bad in [2, 2_000_001] {
            let mut initial = curve_shape.clone();
            initial["resolution"] = json!(bad);
            cases.push((shape(&curve, initial), false, "initial.resolution"));
        }
    }
    for (name, bad) in [
        ("flow.tau", json!(0.0)),
        ("flow.tau_min", json!(0.0)),
        ("flow.end_time", json!(0.0)),
        ("flow.beta", json!(0.0)),
        ("flow.tolerance", json!(-1e-9)),
        ("flow.step_control", json!(-0.5)),
        ("flow.alpha", json!(-0.01)),
        ("flow.conservation", json!(-1e-6)),
        ("flow.max_iterations", json!(0)),
        ("flow.max_iterations", json!(100_000_001)),
    ] {
        let field = name.strip_prefix("flow.").unwrap();
        cases.push((with(&curve, "/flow", json!({ field: bad })), false, name));
    }
    for (field, ok) in
        [("tolerance", json!(0.0)), ("step_control", json!(0.0)), ("alpha", json!(0.0)), ("max_iterations", json!(1))]
    {
        cases.push((with(&curve, "/flow", json!({ field: ok })), true, ""));
    }
    let inputs = HashMap::from([("img".to_string(), square_png())]);
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (i, (spec, valid, field)) in cases.iter().enumerate() {
        let text = spec.to_string();
        let parsed = shapeflow::jobs::parse_spec(&text).and_then(|s| shapeflow::jobs::prepare(s, &inputs));
        match (&parsed, valid) {
            (Ok(_), true) => {}
            (Err(e), false) => assert_eq!(&e.field, field, "case {i}: {text}: {e}"),
            (Ok(_), false) => panic!("case {i}: the parser accepts {text}"),
            (Err(e), true) => panic!("case {i}: the parser rejects {text}: {e}"),
        }
        let p = dir.path().join(format!("bound{i}.json"));
        std::fs::write(&p, &text).unwrap();
        files.push(p);
    }
    let report = validate_json_schema(&root.join("api/job-spec.schema.json"), &files);
    for ((ok, line), (spec, valid, _)) in report.iter().zip(&cases) {
        assert_eq!(ok, valid, "the schema on {spec}: {line}");
    }
}
