//! Naming the failing field of a spec whose error serde reports at a tagged object.
//!
//! `problem`, `initial` (and its `parts`), `problem.control.inner`, `problem.target`
//! … are internally tagged enums. serde buffers such an object before it picks the
//! variant, so [`serde_path_to_error`] sees the error at the object (`initial`), not
//! at the field inside it (`initial.parts[1].center`). This module finds that field:
//! removing the culprit from the document makes the error go away or change (a
//! required culprit turns into `missing field`), while removing any other entry
//! leaves the very same error, since serde reports the first failure it meets.
//! The search descends one level at a time, into objects (trying each key) and
//! into arrays of objects or arrays (bisecting on the length of a truncated copy:
//! the error stays the same exactly when the first failing element is kept). Each
//! trial deserializes the whole document, so the trials are capped
//! ([`MAX_TRIALS`]): a long polygon costs a few dozen, not one per point.

use super::{JobSpec, SpecError};
use serde_json::Value;

/// One step of a path into the document.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Step {
    Key(String),
    Index(usize),
}

/// The keys that carry an enum's tag: removing them always changes the error.
const TAG_KEYS: [&str; 2] = ["type", "shape"];

/// Most nodes a breadth-first search visits.
const MAX_VISITS: usize = 10_000;

/// The paths of the objects at or below `path`, breadth first (containers only,
/// at most [`MAX_VISITS`] of them visited).
fn objects_below(value: &Value, path: &[Step]) -> Vec<Vec<Step>> {
    let mut queue = std::collections::VecDeque::from([path.to_vec()]);
    let mut objects = Vec::new();
    let mut visits = 0;
    while let Some(at) = queue.pop_front() {
        visits += 1;
        if visits > MAX_VISITS {
            break;
        }
        let child = |step: Step| [at.as_slice(), &[step]].concat();
        match node(value, &at) {
            Some(Value::Object(o)) => {
                queue.extend(
                    o.iter().filter(|(_, v)| v.is_object() || v.is_array()).map(|(k, _)| child(Step::Key(k.clone()))),
                );
                objects.push(at);
            }
            Some(Value::Array(a)) => {
                queue.extend(
                    (0..a.len()).filter(|&i| a[i].is_object() || a[i].is_array()).map(|i| child(Step::Index(i))),
                );
            }
            _ => {}
        }
    }
    objects
}

/// The first object at or below `path`, breadth first, that has the key `name`.
fn holder(value: &Value, path: &[Step], name: &str) -> Option<Vec<Step>> {
    objects_below(value, path).into_iter().find(|at| node(value, at).is_some_and(|o| o.get(name).is_some()))
}

/// Most trial deserializations per error (spec objects have at most about a dozen
/// keys; an array of a million entries bisects in 20).
const MAX_TRIALS: usize = 96;

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

/// The error of deserializing `value` as a [`JobSpec`]: its path and message.
fn first_error(value: &Value) -> Option<(Vec<Step>, String)> {
    let e = serde_path_to_error::deserialize::<_, JobSpec>(value).err()?;
    let path = steps(e.path());
    Some((path, readable(&e.into_inner().to_string())))
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

fn node_mut<'a>(value: &'a mut Value, path: &[Step]) -> Option<&'a mut Value> {
    path.iter().try_fold(value, |v, s| match s {
        Step::Key(k) => v.get_mut(k),
        Step::Index(i) => v.get_mut(i),
    })
}

/// The document with the array at `path` cut to its first `len` entries.
fn truncated(value: &Value, path: &[Step], len: usize) -> Value {
    let mut copy = value.clone();
    if let Some(Value::Array(a)) = node_mut(&mut copy, path) {
        a.truncate(len);
    }
    copy
}

/// The document without the entry at `path` (which must exist).
fn without(value: &Value, path: &[Step]) -> Value {
    let mut copy = value.clone();
    let (last, parent) = path.split_last().expect("a non-empty path");
    match (node_mut(&mut copy, parent), last) {
        (Some(Value::Object(o)), Step::Key(k)) => {
            o.remove(k);
        }
        (Some(Value::Array(a)), Step::Index(i)) => {
            a.remove(*i);
        }
        _ => {}
    }
    copy
}

/// The name in backticks of serde's `unknown field `x``/`missing field `x`` messages.
fn named_field<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    message.strip_prefix(prefix)?.split('`').next()
}

/// The object that lacks the required key `name`: removing entries cannot find it
/// (removing any present required key also gives a `missing field` error), but
/// adding `name: null` to it changes the error into one about that value, while
/// adding it where it does not belong gives `unknown field`, and adding it where it
/// is not the missing one leaves the error as it is. Objects are tried breadth first
/// from `path` (serde's path, the buffered object that holds the culprit).
fn missing_at(value: &Value, path: Vec<Step>, name: &str, message: &str) -> Vec<Step> {
    let unknown = format!("unknown field `{name}`");
    let lacking = objects_below(value, &path)
        .into_iter()
        .filter(|at| node(value, at).is_some_and(|o| o.get(name).is_none()))
        .take(MAX_TRIALS);
    for at in lacking {
        let mut doc = value.clone();
        if let Some(Value::Object(m)) = node_mut(&mut doc, &at) {
            m.insert(name.to_string(), Value::Null);
        }
        match first_error(&doc) {
            Some((_, m)) if m == message || m.starts_with(&unknown) => {}
            _ => return at,
        }
    }
    path
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
    let (mut path, message) = first_error(value)?;
    if let Some(name) = named_field(&message, "missing field `") {
        let mut path = missing_at(value, path, name, &message);
        path.push(Step::Key(name.to_string()));
        return Some(SpecError::new(render(&path), message));
    }
    // descend while one entry of the current node carries the error
    let trials = std::cell::Cell::new(0);
    let same = |doc: Value| {
        trials.set(trials.get() + 1);
        first_error(&doc).is_some_and(|(_, m)| m == message)
    };
    'descend: loop {
        match node(value, &path) {
            Some(Value::Object(o)) => {
                let keys: Vec<String> = o.keys().filter(|k| !TAG_KEYS.contains(&k.as_str())).cloned().collect();
                for key in keys {
                    if trials.get() >= MAX_TRIALS {
                        break 'descend;
                    }
                    let mut trial = path.clone();
                    trial.push(Step::Key(key));
                    if !same(without(value, &trial)) {
                        path = trial;
                        continue 'descend;
                    }
                }
                break;
            }
            Some(Value::Array(a)) if !a.is_empty() && a.iter().all(|v| v.is_object() || v.is_array()) => {
                // the smallest kept length with the same error: `lo` entries lose it, `hi` keep it
                let (mut lo, mut hi) = (0, a.len());
                if same(truncated(value, &path, lo)) {
                    break;
                }
                while hi - lo > 1 {
                    if trials.get() >= MAX_TRIALS {
                        break 'descend;
                    }
                    let mid = (lo + hi) / 2;
                    if same(truncated(value, &path, mid)) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                path.push(Step::Index(hi - 1));
            }
            _ => break,
        }
    }
    if let Some(name) = named_field(&message, "unknown field `") {
        // an unknown key is where the search ends; if the same key is wrong in two
        // places the search stops above both: name the first
        if path.last() != Some(&Step::Key(name.to_string())) {
            if let Some(at) = holder(value, &path, name) {
                path = at;
            }
            path.push(Step::Key(name.to_string()));
        }
    } else if message.starts_with("unknown variant") {
        if let Some(Value::Object(o)) = node(value, &path) {
            if let Some(tag) = TAG_KEYS.iter().find(|t| o.contains_key(**t)) {
                path.push(Step::Key(tag.to_string()));
            }
        }
    }
    Some(SpecError::new(render(&path), message))
}

#[cfg(test)]
mod tests;
