//! The job spec as JSON Schema (draft 2020-12), derived from the types of
//! [`super::spec`]: the same field names, tags, defaults and
//! `additionalProperties: false` (unknown fields are rejected) as the parser, by
//! construction. The bounds of single values, the rules tying `initial` to
//! `problem.type` and the `input:NAME` form are written next to the fields
//! (`#[schemars(...)]`) to match the checks of [`super::prepare`]; `tests/schema.rs`
//! holds the two to agreement. Rules relating geometry (a curve inside `Σ`,
//! `tau_min ≤ tau`) are not stated: a spec the schema accepts can still get a 422
//! naming its field.
//!
//! `api/job-spec.schema.json` is [`job_spec_schema`] (a test keeps it current;
//! `shapeflow schema` prints it), and `/v1/openapi.json` carries
//! [`openapi_schemas`] in place of the outline of `JobSpec` in `api/openapi.yaml`.

use super::spec::JobSpec;
use schemars::generate::SchemaSettings;
use serde_json::{Map, Value};

/// The standalone schema of a job spec, its subschemas under `$defs`.
pub fn job_spec_schema() -> Value {
    let mut schema = serde_json::to_value(schemars::schema_for!(JobSpec)).expect("a schema is JSON");
    schema["title"] = Value::from("shapeflow job spec");
    schema
}

/// `JobSpec` and the schemas it refers to, with `$ref`s into
/// `#/components/schemas/`, for the `components.schemas` of an OpenAPI 3.1 document.
pub fn openapi_schemas() -> Map<String, Value> {
    let mut generator =
        SchemaSettings::draft2020_12().with(|s| s.definitions_path = "/components/schemas".into()).into_generator();
    generator.subschema_for::<JobSpec>();
    generator.take_definitions(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schema_names_the_spec_fields_and_rejects_unknown_ones() {
        let s = job_spec_schema();
        assert_eq!(s["$schema"], "https://json-schema.org/draft/2020-12/schema");
        assert_eq!(s["additionalProperties"], false);
        assert_eq!(s["required"], serde_json::json!(["problem"]));
        let defs = s["$defs"].as_object().unwrap();
        for name in ["ProblemSpec", "InitialSpec", "FlowSpec", "MeshSpec", "OutputSpec", "BoundarySpec"] {
            assert!(defs.contains_key(name), "{name}");
        }
        let openapi = openapi_schemas();
        assert!(openapi.contains_key("JobSpec"));
        let text = serde_json::to_string(&openapi).unwrap();
        assert!(!text.contains("#/$defs/") && text.contains("#/components/schemas/InitialSpec"));
    }
}
