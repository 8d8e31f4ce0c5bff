//! The encodings of a row's columns that both backends share, and the messages
//! of jobs whose attempts ended abnormally.

use super::ResultIndex;
use crate::flow::Progress;

/// A history row's surgery as stored (JSON), `None` for a row without one.
pub(crate) fn surgery_json(p: &Progress) -> Option<String> {
    p.surgery.map(|s| serde_json::to_string(&s).expect("a surgery serializes"))
}

/// The stored result index of a row's `results` column.
pub(crate) fn results_of(text: Option<String>) -> Option<ResultIndex> {
    text.and_then(|t| serde_json::from_str(&t).ok())
}

/// The message of a job ended after too many attempts: `last`, the message its
/// last abandoned attempt left ([`super::JobStore::abandon`]), if any.
pub(crate) fn crash_message(takeovers: i64, last: Option<&str>) -> String {
    let attempts = takeovers + 1;
    match last.and_then(|m| m.strip_prefix(ABANDONED)) {
        Some(why) => format!("the job ended abnormally on each of its {attempts} attempts, the last time: {why}; not tried again"),
        None => format!("the job's worker stopped without a trace {takeovers} times (a node crashed or was killed while running it); not tried again"),
    }
}

/// How the message of an abandoned attempt begins (the rest says why).
pub(crate) const ABANDONED: &str = "attempt ended, going on from the last checkpoint: ";
