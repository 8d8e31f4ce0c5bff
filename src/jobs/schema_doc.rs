//! The job-spec reference in Markdown (docs/job-spec-reference.md), generated from
//! the JSON Schema of [`super::job_spec_schema`], so that the reference has exactly
//! the schema's fields, types, bounds, defaults and descriptions. `shapeflow schema
//! --markdown` prints it; `tests/schema.rs` keeps the committed file current.

use serde_json::{Map, Value};
use std::fmt::Write;

/// The reference page of the job spec `schema` (a [`super::job_spec_schema`]).
pub fn job_spec_reference(schema: &Value) -> String {
    let empty = Map::new();
    let defs = schema["$defs"].as_object().unwrap_or(&empty);
    let mut out = String::new();
    out.push_str(
        "# Job spec reference\n\n\
         Generated from `api/job-spec.schema.json` by `shapeflow schema --markdown`; do not\n\
         edit by hand (a test compares the two). The guide with examples is\n\
         [job-spec.md](job-spec.md). Every object rejects unknown fields; a field left out\n\
         takes its default.\n\n",
    );
    out.push_str("## The spec\n\n");
    object_table(&mut out, schema, defs);
    for (name, def) in defs {
        let _ = writeln!(out, "## `{name}`\n");
        if let Some(d) = def["description"].as_str() {
            let _ = writeln!(out, "{}\n", one_line(d));
        }
        if let Some(values) = def["enum"].as_array() {
            let _ = writeln!(out, "One of: {}.\n", join_values(values));
        }
        if let Some(variants) = def["oneOf"].as_array().filter(|v| v.iter().all(|v| v.get("const").is_some())) {
            // documented values of an enumeration
            for v in variants {
                let d = v["description"].as_str().map(one_line).unwrap_or_default();
                let _ = writeln!(out, "- {}: {d}", code(&v["const"]));
            }
            out.push('\n');
        } else if let Some(variants) = def["oneOf"].as_array() {
            for v in variants {
                let tag = v["properties"]
                    .as_object()
                    .and_then(|p| p.iter().find_map(|(k, s)| s["const"].as_str().map(|c| (k.clone(), c.to_string()))));
                match tag {
                    Some((key, value)) => {
                        let _ = writeln!(out, "### `{key}: \"{value}\"`\n");
                    }
                    None => out.push_str("### variant\n\n"),
                }
                if let Some(d) = v["description"].as_str() {
                    let _ = writeln!(out, "{}\n", one_line(d));
                }
                if let Some(values) = v["enum"].as_array() {
                    let _ = writeln!(out, "One of: {}.\n", join_values(values));
                }
                if v["properties"].is_object() {
                    object_table(&mut out, v, defs);
                }
            }
        } else if def["properties"].is_object() {
            object_table(&mut out, def, defs);
        } else if def.get("anyOf").is_some() {
            let _ = writeln!(out, "Type: {}.\n", type_of(def));
        }
    }
    out
}

/// A table of the properties of an object schema.
fn object_table(out: &mut String, schema: &Value, defs: &Map<String, Value>) {
    let empty = Map::new();
    let props = schema["properties"].as_object().unwrap_or(&empty);
    let required: Vec<&str> =
        schema["required"].as_array().map(|r| r.iter().filter_map(Value::as_str).collect()).unwrap_or_default();
    out.push_str("| field | type | bounds | default | meaning |\n|---|---|---|---|---|\n");
    for (name, p) in props {
        if p.get("const").is_some() {
            continue; // the tag, in the heading
        }
        let req = if required.contains(&name.as_str()) { " (required)" } else { "" };
        let default = match p.get("default") {
            Some(Value::Null) | None => String::new(),
            Some(v) if v.is_object() => "see its type".into(),
            Some(v) => code(v),
        };
        let mut meaning = p["description"].as_str().map(one_line).unwrap_or_default();
        if meaning.is_empty() {
            if let Some(d) = reference(p).and_then(|r| defs.get(r)).and_then(|d| d["description"].as_str()) {
                meaning = one_line(d);
            }
        }
        let _ = writeln!(
            out,
            "| `{name}`{req} | {} | {} | {default} | {} |",
            type_of(p),
            bounds(p),
            meaning.replace('|', "\\|")
        );
    }
    out.push('\n');
}

/// The name of the `$defs` entry `p` refers to (directly or as the non-null branch).
fn reference(p: &Value) -> Option<&str> {
    let r =
        p["$ref"].as_str().or_else(|| p["anyOf"].as_array().and_then(|a| a.iter().find_map(|s| s["$ref"].as_str())))?;
    r.strip_prefix("#/$defs/")
}

fn type_of(p: &Value) -> String {
    if let Some(r) = reference(p) {
        return format!("[`{r}`](#{})", r.to_lowercase());
    }
    if let Some(branches) = p["anyOf"].as_array() {
        let parts: Vec<String> = branches.iter().filter(|b| b["type"] != "null").map(type_of).collect();
        return parts.join(" or ");
    }
    let kind = match &p["type"] {
        Value::String(s) => s.clone(),
        Value::Array(a) => a.iter().filter_map(Value::as_str).filter(|t| *t != "null").collect::<Vec<_>>().join(" or "),
        _ => String::from("any"),
    };
    if kind == "array" {
        let item = type_of(&p["items"]);
        let n = match (p["minItems"].as_u64(), p["maxItems"].as_u64()) {
            (Some(a), Some(b)) if a == b => format!("{a} × "),
            _ => String::new(),
        };
        return format!("array of {n}{item}");
    }
    if let Some(pattern) = p["pattern"].as_str() {
        return format!("{kind} (`{pattern}`)");
    }
    if let Some(values) = p["enum"].as_array() {
        return join_values(values);
    }
    kind
}

fn bounds(p: &Value) -> String {
    let mut b = Vec::new();
    for (key, sign) in [("exclusiveMinimum", ">"), ("minimum", "≥"), ("maximum", "≤"), ("exclusiveMaximum", "<")] {
        if let Some(v) = p.get(key) {
            b.push(format!("{sign} {}", number(v)));
        }
    }
    if let Some(v) = p.get("minItems") {
        if p.get("maxItems") != Some(v) {
            b.push(format!("at least {v} items"));
        }
    }
    b.join(", ")
}

/// A bound as a reader writes it: `64`, not `64.0`.
fn number(v: &Value) -> String {
    match v.as_f64() {
        Some(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{}", x as i64),
        _ => v.to_string(),
    }
}

fn join_values(values: &[Value]) -> String {
    values.iter().filter(|v| !v.is_null()).map(code).collect::<Vec<_>>().join(", ")
}

fn code(v: &Value) -> String {
    format!("`{v}`")
}

/// A description on one line (a table cell).
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
