//! Naming the failing field of a spec whose error serde reports at a tagged object.
//!
//! `problem`, `initial` (and its `parts`), `problem.outer`, `problem.control.inner`,
//! `problem.target` and `problem.boundary` are internally tagged enums. serde
//! buffers such an object before it picks the variant, so [`serde_path_to_error`]
//! sees the error at the object (`initial`), not at the field inside it
//! (`initial.parts[1].center`). Every variant's fields are a struct of their own
//! (`CircleShape`, `PolarTarget`, …): deserializing the object, without its tag, as
//! that struct gives the path inside it, and so on down while the path ends at
//! another tagged object. The job spec's JSON schema says which enum is at a path
//! (its `$ref`) and which field an object lacks (its `required`, in the order serde
//! checks them). The message is always that of the whole spec's deserialization.

mod variants;

use super::{JobSpec, SpecError};
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};
use std::sync::OnceLock;

/// One step of a path into the document.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Step {
    Key(String),
    Index(usize),
}

/// serde_path_to_error's path as steps into the document.
pub(super) fn steps(path: &serde_path_to_error::Path) -> Vec<Step> {
    path.iter()
        .filter_map(|s| match s {
            serde_path_to_error::Segment::Map { key } => Some(Step::Key(key.clone())),
            serde_path_to_error::Segment::Seq { index } => Some(Step::Index(*index)),
            _ => None,
        })
        .collect()
}

/// The path and message of the error of deserializing `value` as `T`, if any.
fn error_of<T: DeserializeOwned>(value: &Value) -> Option<(Vec<Step>, String)> {
    let e = serde_path_to_error::deserialize::<_, T>(value).err()?;
    Some((steps(e.path()), e.into_inner().to_string()))
}

/// serde's message with the Rust type names replaced by what the user writes.
fn readable(message: &str) -> String {
    [
        ("internally tagged enum ProblemSpec", "an object with a `type`"),
        ("internally tagged enum TargetSpec", "an object with a `type`"),
        ("internally tagged enum FilmBoundarySpec", "an object with a `type`"),
        ("internally tagged enum InitialSpec", "an object with a `shape`"),
        ("internally tagged enum BoundarySpec", "an object with a `shape`"),
        ("struct JobSpec", "a job spec object"),
    ]
    .iter()
    .fold(message.to_string(), |m, (from, to)| m.replace(from, to))
}

fn node<'a>(value: &'a Value, path: &[Step]) -> Option<&'a Value> {
    path.iter().try_fold(value, |v, s| match s {
        Step::Key(k) => v.get(k),
        Step::Index(i) => v.get(i),
    })
}

pub(super) fn render(path: &[Step]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) if s.is_empty() => s.push_str(k),
            Step::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    if s.is_empty() {
        "(document)".to_string()
    } else {
        s
    }
}

/// The JSON schema of [`JobSpec`], made once.
fn schema() -> &'static Value {
    static SCHEMA: OnceLock<Value> = OnceLock::new();
    SCHEMA.get_or_init(|| serde_json::to_value(schemars::schema_for!(JobSpec)).expect("the schema is JSON"))
}

/// A subschema of [`schema`] with its `$ref`s followed (and an `Option`'s `null`
/// alternative dropped), with the name of the last definition followed.
struct Resolved<'s> {
    schema: &'s Value,
    definition: Option<&'s str>,
}

fn resolve<'s>(root: &'s Value, mut schema: &'s Value) -> Resolved<'s> {
    let mut definition = None;
    loop {
        if let Some(name) = schema.get("$ref").and_then(Value::as_str).and_then(|r| r.strip_prefix("#/$defs/")) {
            match root.get("$defs").and_then(|d| d.get(name)) {
                Some(s) => {
                    (schema, definition) = (s, Some(name));
                    continue;
                }
                None => break,
            }
        }
        let some: Option<Vec<&Value>> = schema
            .get("anyOf")
            .and_then(Value::as_array)
            .map(|alternatives| alternatives.iter().filter(|a| a.get("type") != Some(&Value::from("null"))).collect());
        match some.as_deref() {
            Some([one]) => schema = one,
            _ => break,
        }
    }
    Resolved { schema, definition }
}

/// The tag key and the variants of a tagged enum's schema (`oneOf` of objects each
/// with one `const` property).
fn tagged(schema: &Value) -> Option<(&str, &[Value])> {
    let variants = schema.get("oneOf")?.as_array()?;
    let first = variants.first()?.get("properties")?.as_object()?;
    let key = first.iter().find(|(_, p)| p.get("const").is_some())?.0;
    Some((key.as_str(), variants))
}

/// The variant of `variants` whose tag `key` is `tag`.
fn variant<'s>(variants: &'s [Value], key: &str, tag: &str) -> Option<&'s Value> {
    variants.iter().find(|v| v.pointer(&format!("/properties/{key}/const")).and_then(Value::as_str) == Some(tag))
}

/// The schema at `path` of `doc`, resolved; a tagged enum on the way is read as the
/// variant the document's tag names.
fn schema_at<'s>(doc: &Value, path: &[Step]) -> Option<Resolved<'s>> {
    let root = schema();
    let mut here = resolve(root, root);
    for (k, step) in path.iter().enumerate() {
        let mut schema = here.schema;
        if let Some((key, variants)) = tagged(schema) {
            let tag = node(doc, &path[..k])?.get(key)?.as_str()?;
            schema = variant(variants, key, tag)?;
        }
        let next = match step {
            Step::Key(name) => schema.get("properties")?.get(name)?,
            Step::Index(_) => schema.get("items")?,
        };
        here = resolve(root, next);
    }
    Some(here)
}

/// The first key of `schema`'s `required` (declaration order, as serde checks
/// them) that `object` lacks; in a tagged enum, of the variant its tag names.
fn first_missing(schema: &Value, object: &Map<String, Value>) -> Option<String> {
    let schema = match tagged(schema) {
        Some((key, variants)) => variant(variants, key, object.get(key)?.as_str()?)?,
        None => schema,
    };
    let required = schema.get("required")?.as_array()?;
    required.iter().filter_map(Value::as_str).find(|k| !object.contains_key(*k)).map(str::to_string)
}

/// The spec error of `value`, if any, with its field named as precisely as the
/// document allows.
pub(super) fn locate(value: &Value) -> Option<SpecError> {
    if !value.is_object() {
        // serde would read a struct from an array too, field by field
        let kind = match value {
            Value::Array(_) => "an array",
            Value::String(_) => "a string",
            Value::Number(_) => "a number",
            Value::Bool(_) => "a boolean",
            _ => "null",
        };
        return Some(SpecError::new("(document)", format!("a job spec must be a JSON object, got {kind}")));
    }
    let (mut path, message) = error_of::<JobSpec>(value)?;
    // down through the tagged objects, each deserialized as its variant's struct
    while let Some(Value::Object(object)) = node(value, &path) {
        let Some(at) = schema_at(value, &path) else { break };
        let (Some(definition), Some((key, variants))) = (at.definition, tagged(at.schema)) else { break };
        let tag = object.get(key).and_then(Value::as_str);
        if tag.is_none_or(|t| variant(variants, key, t).is_none()) {
            // no tag, or one that names no variant
            path.push(Step::Key(key.to_string()));
            return Some(SpecError::new(render(&path), readable(&message)));
        }
        let mut fields = object.clone();
        fields.remove(key);
        match variants::error(definition, tag.unwrap_or_default(), &Value::Object(fields)) {
            Some(Some((inner, _))) if !inner.is_empty() => path.extend(inner),
            _ => break,
        }
    }
    // an object that lacks a required key: serde names the key only in its message
    if let Some(Value::Object(object)) = node(value, &path) {
        if let Some(missing) = schema_at(value, &path).and_then(|at| first_missing(at.schema, object)) {
            path.push(Step::Key(missing));
        }
    }
    Some(SpecError::new(render(&path), readable(&message)))
}

#[cfg(test)]
mod tests;
