//! Running a prepared job: the flow in the job's dimension, with progress after every
//! iteration, checkpoints every `checkpoint_every` iterations (and at the start and
//! the end), cancellation, and resumption from a checkpoint.

use super::build::{AnyMesh, PreparedJob};
use crate::flow::{Checkpoint, Flow, FlowError, MeshManager, Progress, StopReason};
use crate::geometry::Mesh;
use std::sync::atomic::AtomicBool;

/// Receives what a running job reports.
pub trait RunEvents {
    /// After every accepted iteration (and once at the start).
    fn progress(&mut self, _p: &Progress) {}
    /// Every `checkpoint_every` iterations, at the start and at the end.
    fn checkpoint(&mut self, _c: &Checkpoint) {}
}

impl RunEvents for () {}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct JobOutcome {
    pub stop: StopReason,
    /// The final state (also passed to [`RunEvents::checkpoint`]).
    pub last: Checkpoint,
}

/// A run that failed: the numeric error and the last good state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{error} (last good state: iteration {})", last.iteration)]
pub struct JobFailure {
    pub error: FlowError,
    pub last: Checkpoint,
}

/// Run `job` (from its start, or from `resume`), reporting to `events`.
pub fn run_prepared(
    job: &PreparedJob,
    resume: Option<&Checkpoint>,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> Result<JobOutcome, Box<JobFailure>> {
    match &job.mesh {
        AnyMesh::Curve(m) => {
            let manager = job.curve_manager.map(|c| Box::new(c.watched()) as Box<dyn MeshManager<2>>);
            run_dim::<2>(job, m, manager, resume, cancel, events)
        }
        AnyMesh::Surface(m) => {
            let manager = job.surface_manager.map(|c| Box::new(c) as Box<dyn MeshManager<3>>);
            run_dim::<3>(job, m, manager, resume, cancel, events)
        }
    }
}

fn run_dim<const D: usize>(
    job: &PreparedJob,
    mesh: &Mesh<D>,
    manager: Option<Box<dyn MeshManager<D>>>,
    resume: Option<&Checkpoint>,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> Result<JobOutcome, Box<JobFailure>> {
    let problem = job.problem.as_dyn::<D>();
    let fail = |error: FlowError, last: Checkpoint| Box::new(JobFailure { error, last });
    let mut flow = match resume {
        Some(cp) => Flow::resume(problem, cp, job.settings.clone()),
        None => Flow::new(problem, mesh.clone(), job.settings.clone()),
    }
    .map_err(|e| {
        let start = resume.cloned().unwrap_or_else(|| Checkpoint {
            iteration: 0,
            time: 0.0,
            tau: job.settings.tau,
            energy: f64::NAN,
            mesh: mesh.into(),
        });
        fail(e, start)
    })?;
    if let Some(m) = manager {
        flow = flow.with_mesh_manager(m);
    }
    let every = job.checkpoint_every.max(1);
    let mut last_saved = resume.map(|c| c.iteration);
    let result = flow.run(cancel, |f| {
        events.progress(&f.progress());
        let it = f.iteration();
        if (it % every == 0 || it == 0) && last_saved != Some(it) {
            events.checkpoint(&f.checkpoint());
            last_saved = Some(it);
        }
    });
    let last = flow.checkpoint();
    match result {
        Ok(stop) => {
            if last_saved != Some(last.iteration) {
                events.checkpoint(&last);
            }
            Ok(JobOutcome { stop, last })
        }
        Err(e) => {
            if last_saved != Some(last.iteration) {
                events.checkpoint(&last);
            }
            Err(fail(e, last))
        }
    }
}

/// Per-vertex output fields of a state of `job`: the discrete curvature and the
/// normal velocity of the next step (see [`Flow::vertex_fields`]).
pub fn vertex_fields(job: &PreparedJob, state: &Checkpoint) -> Result<(Vec<f64>, Vec<f64>), FlowError> {
    fn in_dim<const D: usize>(job: &PreparedJob, state: &Checkpoint) -> Result<(Vec<f64>, Vec<f64>), FlowError> {
        Flow::resume(job.problem.as_dyn::<D>(), state, job.settings.clone())?.vertex_fields()
    }
    match state.mesh.dimension {
        2 => in_dim::<2>(job, state),
        3 => in_dim::<3>(job, state),
        d => Err(FlowError::Checkpoint(format!("dimension {d}"))),
    }
}
