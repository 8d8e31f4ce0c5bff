use super::*;

fn field(json: &str) -> String {
    locate(&serde_json::from_str(json).unwrap()).expect("an error").field
}

#[test]
fn fields_inside_tagged_objects_are_named() {
    let circle = r#""initial": {"shape": "circle", "radius": 1}"#;
    assert_eq!(
        field(r#"{"problem": {"type": "curvature_flow", "gamma": "1"}, "initial": {"shape": "circle", "radius": 1}}"#),
        "problem.gamma"
    );
    assert_eq!(
        field(&format!(r#"{{"problem": {{"type": "curvature_flow", "sigma": 1}}, {circle}}}"#)),
        "problem.sigma"
    );
    assert_eq!(
        field(r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle", "radius": 1, "center": [0]}}"#),
        "initial.center"
    );
    assert_eq!(field(r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "circle"}}"#), "initial.radius");
    assert_eq!(
        field(
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [
                    {"shape": "circle", "radius": 1}, {"shape": "circle", "radius": "big"}]}}"#
        ),
        "initial.parts[1].radius"
    );
    assert_eq!(
        field(
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "polygon", "points": [[0, 0], [1], [1, 1]]}}"#
        ),
        "initial.points[1]"
    );
    assert_eq!(field(&format!(r#"{{"problem": {{"type": "flow"}}, {circle}}}"#)), "problem.type");
    let design = |inner: &str, target: &str| {
        format!(
            r#"{{"problem": {{"type": "shape_design", "outer": {{"shape": "circle", "radius": 3}},
                   "control": {{"inner": {inner}, "outer": {{"shape": "circle", "radius": 2.5}}}},
                   "target": {target}}}, {circle}}}"#
        )
    };
    let ring = r#"{"shape": "circle", "radius": 2}"#;
    let color = r#"{"type": "constant", "value": 1, "color": "red"}"#;
    assert_eq!(field(&design(ring, color)), "problem.target.color");
    let centre = r#"{"shape": "circle", "radius": 2, "centre": [0, 0]}"#;
    let twice = design(centre, r#"{"type": "constant", "value": 1}"#)
        .replace(r#""radius": 2.5}"#, r#""radius": 2.5, "centre": [0, 0]}"#);
    assert_eq!(field(&twice), "problem.control.inner.centre");
    let constant = r#"{"type": "constant", "value": 1}"#;
    assert_eq!(field(&design(r#"{"shape": "circle"}"#, constant)), "problem.control.inner.radius");
    assert_eq!(field(r#"{"initial": {"shape": "circle", "radius": 1}}"#), "problem");
    // a missing key after present required ones (removing those gives `missing field` too)
    let torus = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "torus", "major_radius": 2}}"#;
    assert_eq!(field(torus), "initial.minor_radius");
    let polar = r#"{"type": "polar", "a": 1, "b": 2}"#;
    assert_eq!(field(&design(ring, polar)), "problem.target.k");
    let no_target = r#"{"problem": {"type": "shape_design", "outer": {"shape": "circle", "radius": 3},
            "control": {"inner": {"shape": "circle", "radius": 2}, "outer": {"shape": "circle", "radius": 2.5}}},
            "initial": {"shape": "circle", "radius": 1}}"#;
    assert_eq!(field(no_target), "problem.target");
    let parts = r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [
            {"shape": "circle", "radius": 1}, {"shape": "circle"}, {"shape": "ellipse"}]}}"#;
    assert_eq!(field(parts), "initial.parts[1].radius");
    assert_eq!(
        field(&format!(
            r#"{{"problem": {{"type": "stressed_film", "length": 1, "boundary": {{"type": "x", "value": 0}}}}, {circle}}}"#
        )),
        "problem.boundary.value"
    );
    assert_eq!(
        field(&format!(
            r#"{{"problem": {{"type": "stressed_film", "length": 1, "boundary": {{"type": "y"}}}}, {circle}}}"#
        )),
        "problem.boundary.type"
    );
    assert_eq!(
        field(
            r#"{"problem": {"type": "curvature_flow"}, "initial": {"shape": "union", "parts": [{"shape": "blob"}]}}"#
        ),
        "initial.parts[0].shape"
    );
    assert_eq!(
        field(&format!(
            r#"{{"problem": {{"type": "shape_design", "outer": {{"shape": "circle", "radius": 3}},
                   "control": {{"inner": {{"shape": "circle", "radius": "2"}}, "outer": {{"shape": "circle", "radius": 2.5}}}},
                   "target": {{"type": "constant", "value": 0.45}}}}, {circle}}}"#
        )),
        "problem.control.inner.radius"
    );
    assert_eq!(
        field(&format!(r#"{{"problem": {{"type": "curvature_flow"}}, {circle}, "flow": {{"tau": "x"}}}}"#)),
        "flow.tau"
    );
}

#[test]
fn a_bad_point_of_a_long_polygon_is_named() {
    let mut points: Vec<serde_json::Value> =
        (0..100_000).map(|i| serde_json::json!([(i as f64).cos(), (i as f64).sin()])).collect();
    points[77_777] = serde_json::json!([1.0]);
    points[90_000] = serde_json::json!(["x", 0.0]);
    let doc = serde_json::json!({"problem": {"type": "curvature_flow"},
                                     "initial": {"shape": "polygon", "points": points}});
    assert_eq!(locate(&doc).unwrap().field, "initial.points[77777]");
}

/// Every variant of every tagged enum of the schema has its struct in the table of
/// `variants`, and nothing else is in it.
#[test]
fn every_tagged_variant_has_its_struct() {
    let defs = schema()["$defs"].as_object().unwrap();
    let mut pairs = 0;
    for (name, def) in defs {
        let Some((key, variants)) = tagged(def) else { continue };
        for v in variants {
            let tag = v["properties"][key]["const"].as_str().unwrap();
            assert!(variants::error(name, tag, &serde_json::json!({})).is_some(), "{name} {tag}");
            pairs += 1;
        }
    }
    assert_eq!(pairs, 29, "tagged variants in the schema");
    assert!(variants::error("InitialSpec", "blob", &serde_json::json!({})).is_none());
}

/// A field missing from the object of a variant is named after the object.
#[test]
fn the_first_missing_field_is_named() {
    let doc = serde_json::json!({"problem": {"type": "stressed_film"}, "initial": {"shape": "film", "height": 1}});
    assert_eq!(locate(&doc).unwrap().field, "problem.length");
    let doc = serde_json::json!({"problem": {"type": "curvature_flow"}, "initial": {"shape": "film"}});
    assert_eq!(locate(&doc).unwrap().field, "initial.height");
    let doc = serde_json::json!({"problem": {"type": "curvature_flow"}, "initial": {"radius": 1}});
    assert_eq!(locate(&doc).unwrap().field, "initial.shape");
}

#[test]
fn messages_speak_of_the_spec_not_of_rust_types() {
    let e = locate(&serde_json::json!({"problem": 1, "initial": {"shape": "circle", "radius": 1}})).unwrap();
    assert_eq!(e.field, "problem");
    assert!(e.message.contains("an object with a `type`") && !e.message.contains("Spec"), "{e}");
    let e = locate(&serde_json::json!([1, 2])).unwrap();
    assert_eq!(e.field, "(document)");
    assert!(e.message.contains("must be a JSON object"), "{e}");
}
