//! What a prepared job will need of memory to run, estimated before it is
//! accepted, so that a job that cannot fit its memory budget is refused with the
//! field that makes it large instead of failing after it has been queued.
//!
//! The estimate is a sum of what grows with the job, each term from measured
//! peak resident sizes of release runs (BENCHMARKS.md, "Memory of a job"):
//!
//! | term | bytes |
//! |---|---|
//! | the process itself | 16 MiB |
//! | each sample of the image or volume (its filtered copies, gradients, the edge field) | 60 |
//! | each vertex of the initial mesh (the step's sparse systems and their factorization) | 2,500 |
//! | the frames kept for evolution.glb | at most 2 × 64 MiB |
//!
//! Each constant is about 0.8 of what was measured, so that the estimate refuses
//! only jobs that would not fit; a job whose mesh grows by refinement can still
//! exceed its budget later and then ends with the budget's message.

use super::PreparedJob;
use crate::geometry::AnyMesh;
use crate::jobs::format_size;
use crate::limits::{MAX_EVOLUTION_BYTES, MAX_FRAMES};

/// Bytes of a job's process before its inputs.
const BASE_BYTES: u64 = 16 << 20;
/// Bytes per sample of an image or a volume.
const SAMPLE_BYTES: u64 = 60;
/// Bytes per vertex of the initial mesh.
const VERTEX_BYTES: u64 = 2_500;
/// Bytes per vertex of one kept frame (positions, normals, fields).
const FRAME_VERTEX_BYTES: u64 = 48;

/// A job's estimated memory and the field of the spec that makes most of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MemoryEstimate {
    pub bytes: u64,
    /// `problem.image`, `initial` or `output.checkpoint_every`.
    pub field: &'static str,
    /// What the bytes are for, as a user reads it ("16777216 image samples, 10242 vertices").
    pub what: String,
}

impl MemoryEstimate {
    /// The estimate of `job` (see the module's table).
    pub fn of(job: &PreparedJob) -> MemoryEstimate {
        let samples = job.image.as_ref().map_or(0, |g| g.values.len() as u64);
        let vertices = match &job.mesh {
            AnyMesh::Curve(m) => m.num_vertices(),
            AnyMesh::Surface(m) => m.num_vertices(),
        } as u64;
        let checkpoints = (job.settings.max_iterations / job.checkpoint_every.max(1)) as u64 + 1;
        let frames = (checkpoints.min(2 * MAX_FRAMES as u64) * vertices * FRAME_VERTEX_BYTES)
            .min(2 * MAX_EVOLUTION_BYTES as u64);
        let terms = [
            (samples * SAMPLE_BYTES, "problem.image"),
            (vertices * VERTEX_BYTES, "initial"),
            (frames, "output.checkpoint_every"),
        ];
        let field = terms.iter().max_by_key(|t| t.0).map_or("initial", |t| t.1);
        let mut what = Vec::new();
        if samples > 0 {
            what.push(format!("{samples} image samples"));
        }
        what.push(format!("{vertices} vertices"));
        what.push(format!("{} checkpoints", checkpoints.min(2 * MAX_FRAMES as u64)));
        MemoryEstimate { bytes: BASE_BYTES + terms.iter().map(|t| t.0).sum::<u64>(), field, what: what.join(", ") }
    }

    /// `Err((field, message))` if this estimate does not fit `budget` bytes.
    pub fn check(&self, budget: u64) -> Result<(), (&'static str, String)> {
        if self.bytes <= budget {
            return Ok(());
        }
        Err((
            self.field,
            format!(
                "the job needs about {} of memory to run ({}), more than its memory budget of {}",
                format_size(self.bytes),
                self.what,
                format_size(budget)
            ),
        ))
    }
}
