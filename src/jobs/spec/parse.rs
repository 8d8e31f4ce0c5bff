//! Parsing a spec from JSON text, with the failing field named.

use super::path::locate;
use super::segmentation::IMAGE_MESSAGE;
use super::unique_keys::duplicate_key;
use super::{JobSpec, SpecError};
use serde::Deserialize;

/// Parse a spec from JSON text. Errors name the field path, also inside the tagged
/// objects (`initial.parts[1].center`, see [`super::path`]).
pub fn parse_spec(text: &str) -> Result<JobSpec, SpecError> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| SpecError::new("(document)", format!("malformed JSON: {e}")))?;
    if let Some(e) = duplicate_key(text) {
        return Err(e);
    }
    // one deserialization for a good spec (an object: serde also reads a struct from
    // an array); a bad one is searched for the field to name
    if value.is_object() {
        if let Ok(spec) = JobSpec::deserialize(&value) {
            return Ok(spec);
        }
    }
    let mut e = locate(&value).unwrap_or_else(|| SpecError::new("(document)", "not a valid job spec".to_string()));
    if let Some(rest) = e.message.strip_prefix(IMAGE_MESSAGE) {
        e = SpecError::new("problem.image", format!("must be \"input:NAME\" or a list of them{rest}"));
    }
    Err(e)
}
