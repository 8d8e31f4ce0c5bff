//! What a job's process and its worker say to each other over the child's
//! standard input and output: small typed messages, each a JSON header and a
//! payload of raw bytes (an input file, a frame's JSON, a result file), framed as
//! `u32` header length, header, `u64` payload length, payload (little-endian).
//! The worker sends one [`Request`] with its payloads, then at most a
//! [`Control::Cancel`]; the child answers with [`Report`]s, the last an
//! [`Report::Outcome`].

use crate::flow::Progress;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::io::{self, Read, Write};

/// Largest header a reader accepts (headers are small: a spec is at most
/// [`crate::limits::MAX_BODY_BYTES`]).
const MAX_HEADER: usize = 8 * 1024 * 1024;

/// What a job's process is asked to run. Its payloads follow it, in order: each
/// input's bytes (as named in `inputs`) and the JSON of each of the
/// `prior_frames` frames stored by earlier attempts (for evolution.glb), the run
/// resuming from the last of them if `resume`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Request {
    pub spec: String,
    pub inputs: Vec<String>,
    pub resume: bool,
    pub prior_frames: usize,
    /// Only prepare the job (decode its inputs, build its initial shape) and say
    /// whether that works ([`RunEnd::Valid`] or [`RunEnd::Invalid`]): a
    /// submission's validation, away from the service's memory.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub validate_only: bool,
    /// The job's memory budget in bytes, which the process sets as its own limit
    /// (`RLIMIT_DATA`) before it reads the payloads (a process started ahead of
    /// its job has none yet).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory: Option<u64>,
    /// A fault to inject (debug builds of a service started with fault injection
    /// on, for the tests of isolation only; see `Fault`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fault: Option<String>,
}

/// What the worker may send after the request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Control {
    /// Stop at the next step, write the last checkpoint and the result files.
    Cancel,
}

/// What a job's process reports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Report {
    /// What every glb file of the job shares; payload: its JSON.
    Context,
    /// A history row.
    Progress(Progress),
    /// A checkpoint; payload: its frame's JSON.
    Checkpoint { iteration: usize, time: f64 },
    /// A result file; payload: its bytes.
    File { name: String, media_type: String },
    /// How the run ended (the last message).
    Outcome(RunEnd),
}

/// How a job's run ended, as its process saw it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum RunEnd {
    /// Stopped by its rules (converged, end_time, ...), with the run's note.
    Stopped { stop: String, note: Option<String> },
    /// Stopped because cancellation was asked.
    Cancelled,
    /// The run failed (a numeric failure) or the spec no longer prepares.
    Failed { message: String },
    /// A panic, caught: its message.
    Panicked { message: String },
    /// Validation only: the job prepares.
    Valid,
    /// Validation only: the spec or an input is wrong (the field and why).
    Invalid { field: String, message: String },
}

/// Write one message.
pub fn write_message(w: &mut impl Write, header: &impl Serialize, payload: &[u8]) -> io::Result<()> {
    let head = serde_json::to_vec(header).map_err(io::Error::other)?;
    w.write_all(&(head.len() as u32).to_le_bytes())?;
    w.write_all(&head)?;
    w.write_all(&(payload.len() as u64).to_le_bytes())?;
    w.write_all(payload)?;
    w.flush()
}

/// Read one message: `None` at the end of the stream (before a message begins).
pub fn read_message<H: DeserializeOwned>(r: &mut impl Read) -> io::Result<Option<(H, Vec<u8>)>> {
    let mut len = [0u8; 4];
    match r.read_exact(&mut len) {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(e),
    }
    let n = u32::from_le_bytes(len) as usize;
    if n > MAX_HEADER {
        return Err(io::Error::new(io::ErrorKind::InvalidData, format!("a message header of {n} bytes")));
    }
    let mut head = vec![0u8; n];
    r.read_exact(&mut head)?;
    let header = serde_json::from_slice(&head).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
    let mut len = [0u8; 8];
    r.read_exact(&mut len)?;
    let n = u64::from_le_bytes(len);
    let mut payload = Vec::new();
    r.take(n).read_to_end(&mut payload)?;
    if payload.len() as u64 != n {
        return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "a message cut short"));
    }
    Ok(Some((header, payload)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_round_trip_and_end_cleanly() {
        let mut buf = Vec::new();
        let p =
            Progress { iteration: 3, time: 0.5, tau: 1e-3, energy: 2.0, vertices: 10, components: 1, surgery: None };
        write_message(&mut buf, &Report::Progress(p), &[]).unwrap();
        write_message(&mut buf, &Report::File { name: "shape.glb".into(), media_type: "m".into() }, b"glb").unwrap();
        let mut r = buf.as_slice();
        let (h, body): (Report, _) = read_message(&mut r).unwrap().unwrap();
        assert_eq!((h, body.len()), (Report::Progress(p), 0));
        let (h, body): (Report, _) = read_message(&mut r).unwrap().unwrap();
        assert_eq!(h, Report::File { name: "shape.glb".into(), media_type: "m".into() });
        assert_eq!(body, b"glb");
        assert!(read_message::<Report>(&mut r).unwrap().is_none());
    }

    #[test]
    fn a_message_cut_short_is_an_error() {
        let mut buf = Vec::new();
        write_message(&mut buf, &Control::Cancel, b"0123456789").unwrap();
        buf.truncate(buf.len() - 3);
        assert!(read_message::<Control>(&mut buf.as_slice()).is_err());
    }
}
