//! Running a prepared job: the flow in the job's dimension, with progress after every
//! iteration, checkpoints every `checkpoint_every` iterations (and at the start and
//! the end), cancellation, and resumption from a checkpoint.

use super::{AnyMesh, PreparedJob, ProblemKind};
use crate::flow::{
    Checkpoint, Flow, FlowError, MeshData, MeshManager, Problem, Progress, StopReason, SurgeryEvent, SurgeryKind,
    SurgeryRecord, VertexFields,
};
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

/// Keeps every checkpoint, in the order reported.
impl RunEvents for Vec<Checkpoint> {
    fn checkpoint(&mut self, c: &Checkpoint) {
        self.push(c.clone());
    }
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct JobOutcome {
    pub stop: StopReason,
    /// With `tau_min`: why the last trial steps failed; with `vanished`: what that
    /// means (a sentence for users).
    pub note: Option<&'static str>,
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

/// Run `job` (from its start, or from `resume`), reporting to `events`. A job with a
/// second stage ([`PreparedJob::second_stage`]) continues with it from where the first one
/// converged; the iterations count on, and its checkpoints carry `stage: 1`.
pub fn run_prepared(
    job: &PreparedJob,
    resume: Option<&Checkpoint>,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> Result<JobOutcome, Box<JobFailure>> {
    match &job.mesh {
        AnyMesh::Curve(m) => {
            let manager = |_| job.curve_manager.map(|c| Box::new(c.watched()) as Box<dyn MeshManager<2>>);
            let dim = Dimension { problem: &|p| Ok(p.curve_problem()), manager: &manager };
            run_stages::<2>(job, m, &dim, resume, cancel, events)
        }
        AnyMesh::Surface(m) => {
            let manager = |phase: Phase| {
                let m = if phase.coarse { job.coarse_manager } else { job.surface_manager };
                m.map(|c| Box::new(c) as Box<dyn MeshManager<3>>)
            };
            let dim = Dimension { problem: &ProblemKind::surface_problem, manager: &manager };
            run_stages::<3>(job, m, &dim, resume, cancel, events)
        }
    }
}

/// A run of a stage's problem in dimension `D`.
type MakeProblem<const D: usize> = dyn Fn(&ProblemKind) -> Result<Box<dyn Problem<D>>, FlowError>;

/// What a run needs in its dimension: the run of a stage's problem and a fresh
/// mesh manager for a phase.
struct Dimension<'a, const D: usize> {
    problem: &'a MakeProblem<D>,
    manager: &'a dyn Fn(Phase) -> Option<Box<dyn MeshManager<D>>>,
}

/// Where a run is: the stage (its problem) and, in the first stage, whether the
/// surface still converges on coarse edges ([`PreparedJob::coarse_manager`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Phase {
    stage: usize,
    coarse: bool,
}

/// How much looser the coarse start's convergence test is than the job's: the
/// coarse surface only has to come near the result, which the default edges
/// then refine (measured with edges of one to two voxels: on the nuclei volume
/// the coarse start at the job's tolerance took 61 steps where it took 40 at ten
/// times it, and the default edges after it were no fewer steps).
const COARSE_TOLERANCE: f64 = 10.0;

fn run_stages<const D: usize>(
    job: &PreparedJob,
    mesh: &Mesh<D>,
    dim: &Dimension<'_, D>,
    resume: Option<&Checkpoint>,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> Result<JobOutcome, Box<JobFailure>> {
    let mut start = resume.cloned();
    let stage = resume.map_or(0, |c| c.stage.min(usize::from(job.second_stage.is_some())));
    let coarse = stage == 0 && job.coarse_manager.is_some() && resume.is_none_or(|c| c.coarse);
    let mut phase = Phase { stage, coarse };
    // the state a later stage starts from was reported as the end of the one before
    let mut reported = false;
    let mut splits = 0;
    loop {
        let out = run_stage::<D>(job, phase, mesh, dim, start.as_ref(), reported, cancel, events)?;
        if phase.coarse && matches!(out.stop, StopReason::Converged | StopReason::TauMin) {
            // the coarse surface came near the result (or can go no further on its
            // edges): the default edges go on from there, with a fresh step and
            // their convergence judged afresh
            let fine = Checkpoint { coarse: false, ..out.last.with_fresh_step(job.settings.tau) };
            tracing::debug!(iteration = fine.iteration, stop = ?out.stop, "coarse start over, on to the default edges");
            (start, phase.coarse, reported) = (Some(fine), false, true);
            continue;
        }
        if phase.stage == 0 && job.second_stage.is_some() && out.stop == StopReason::Converged {
            // the second stage is another problem: its convergence is judged afresh
            let first = Checkpoint { stage: 1, recent_energies: Vec::new(), ..out.last };
            (start, phase.stage, reported) = (Some(first), 1, true);
            continue;
        }
        if out.stop == StopReason::Converged && splits < MAX_NECK_SPLITS {
            if let Some(next) = split_at_necks::<D>(job, dim, &out.last) {
                // a new state, one iteration on: reported, then run to convergence
                splits += 1;
                (start, reported) = (Some(next), false);
                continue;
            }
        }
        return Ok(out);
    }
}

/// How many times a run goes on after splitting its converged contours at necks
/// ([`NeckSplit`](super::NeckSplit)): each split adds objects, and an object split once is rarely
/// split again.
const MAX_NECK_SPLITS: usize = 3;

/// The state after `last` with its objects split at necks (a fresh step size,
/// its energy on the new curves or surfaces; surfaces' cuts recorded as pinches),
/// or `None` if the job splits none or has no iteration left.
fn split_at_necks<const D: usize>(job: &PreparedJob, dim: &Dimension<'_, D>, last: &Checkpoint) -> Option<Checkpoint> {
    let split = job.neck_split.as_ref()?;
    if last.iteration >= job.settings.max_iterations {
        return None;
    }
    let iteration = last.iteration + 1;
    let mut surgeries = last.surgeries.clone();
    let mesh: MeshData = if D == 2 {
        (&split.split(&last.mesh.to_mesh_unvalidated::<2>()?)?).into()
    } else {
        // the traced parts tidied as a surgery's are (the fine edges' management)
        let manager = job.surface_manager?;
        let before = last.mesh.to_mesh_unvalidated::<3>()?;
        let (surfaces, cuts) = split.split_surfaces(&before, |m| manager.tidy(m, 2))?;
        let mut components = before.component_labels().1;
        for cut in &cuts {
            components += cut.parts - 1;
            tracing::info!(at = ?cut.at, parts = cut.parts, "an object split at its neck");
            let event = SurgeryEvent { kind: SurgeryKind::Pinch, at: cut.at, components };
            surgeries.push(SurgeryRecord { iteration, time: last.time, event });
        }
        (&surfaces).into()
    };
    let energy = (dim.problem)(job.stage_problem(last.stage)).ok()?.energy(&mesh.to_mesh_unvalidated::<D>()?).ok()?;
    tracing::debug!(energy, "the energy after a neck split");
    energy.is_finite().then(|| Checkpoint {
        iteration,
        energy,
        mesh,
        surgeries,
        ..last.clone().with_fresh_step(job.settings.tau)
    })
}

/// One phase of [`run_prepared`]: the flow of the stage's problem from `start`
/// (the job's initial mesh if `None`); `reported`: `start` was already reported.
#[allow(clippy::too_many_arguments)]
fn run_stage<const D: usize>(
    job: &PreparedJob,
    phase: Phase,
    mesh: &Mesh<D>,
    dim: &Dimension<'_, D>,
    start: Option<&Checkpoint>,
    reported: bool,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> Result<JobOutcome, Box<JobFailure>> {
    let fail = |error: FlowError, last: Checkpoint| Box::new(JobFailure { error, last });
    let start_of = |c: Option<&Checkpoint>| {
        c.cloned().unwrap_or_else(|| Checkpoint {
            iteration: 0,
            time: 0.0,
            tau: job.settings.tau,
            energy: f64::NAN,
            mesh: mesh.into(),
            stage: phase.stage,
            coarse: phase.coarse,
            settled_tau: 0.0,
            recent_energies: Vec::new(),
            surgeries: Vec::new(),
        })
    };
    let mut problem = (dim.problem)(job.stage_problem(phase.stage)).map_err(|e| fail(e, start_of(start)))?;
    let tagged = |c: Checkpoint| Checkpoint { stage: phase.stage, coarse: phase.coarse, ..c };
    let mut settings = job.settings.clone();
    if phase.coarse {
        settings.tolerance *= COARSE_TOLERANCE;
    }
    if let (1.., Some(cp)) = (phase.stage, start) {
        // a later stage converges on the scale of the first stage's energy at the
        // same shape: without the balloon term the energy of a segmentation is a few
        // hundred times smaller, and re-meshing noise would keep it from converging
        if let Some(m) = cp.mesh.to_mesh_unvalidated::<D>() {
            let first = (dim.problem)(&job.problem).map_err(|e| fail(e, start_of(start)))?.energy(&m);
            let here = problem.energy(&m);
            if let (Ok(first), Ok(here)) = (first, here) {
                let scale = (first / here).abs();
                if scale.is_finite() && scale > 1.0 {
                    settings.tolerance *= scale;
                }
            }
        }
    }
    let mut flow = match start {
        // the end of the stage before, in memory
        Some(cp) if reported => Flow::continue_from(&mut *problem, cp, settings),
        Some(cp) => Flow::resume(&mut *problem, cp, settings),
        None => Flow::new(&mut *problem, mesh.clone(), settings),
    }
    .map_err(|e| fail(e, start_of(start)))?;
    if let Some(m) = (dim.manager)(phase) {
        flow = flow.with_mesh_manager(m);
    }
    let every = job.checkpoint_every.max(1);
    let first = start.map(|c| c.iteration);
    let mut last_saved = first;
    let result = flow.run(cancel, |f| {
        let it = f.iteration();
        // a resumed run reports its starting state again (the service replaces the
        // row); a later stage does not repeat the end of the one before
        if !(reported && Some(it) == first) {
            events.progress(&f.progress());
        }
        if (it % every == 0 || it == 0) && last_saved != Some(it) {
            events.checkpoint(&tagged(f.checkpoint()));
            last_saved = Some(it);
        }
    });
    let last = tagged(flow.checkpoint());
    if last_saved != Some(last.iteration) {
        events.checkpoint(&last);
    }
    match result {
        Ok(stop) => {
            let note = match stop {
                StopReason::Vanished if D == 3 => Some(
                    "every surface shrank below the mesh's resolution (the volume of a ball of radius \
                     mesh.h_min): nothing is left; for an image, no object was found (empty mask)",
                ),
                StopReason::Vanished => Some(
                    "every contour shrank below the smallest size kept (mesh.min_area): nothing is left; \
                     for an image, no object was found (empty mask)",
                ),
                _ => flow.stop_cause().map(|r| r.describe()),
            };
            Ok(JobOutcome { stop, note, last })
        }
        Err(e) => Err(fail(e, last)),
    }
}

/// Per-vertex output fields of a state of `job`: the discrete curvature, the
/// normal velocity of the next step and the problem's own field (see
/// [`Flow::vertex_fields`]). The state's mesh is validated: it may come from
/// storage.
pub fn vertex_fields(job: &PreparedJob, state: &Checkpoint) -> Result<VertexFields, FlowError> {
    fields_in_dim(job, state, false)
}

/// [`vertex_fields`] of a state that this process's own run produced, whose mesh
/// the flow keeps valid: not validated again (see [`Flow::continue_from`]).
pub fn run_vertex_fields(job: &PreparedJob, state: &Checkpoint) -> Result<VertexFields, FlowError> {
    fields_in_dim(job, state, true)
}

fn fields_in_dim(job: &PreparedJob, state: &Checkpoint, own: bool) -> Result<VertexFields, FlowError> {
    fn in_dim<const D: usize>(
        mut problem: Box<dyn Problem<D>>,
        job: &PreparedJob,
        state: &Checkpoint,
        own: bool,
    ) -> Result<VertexFields, FlowError> {
        let settings = job.settings.clone();
        let mut flow = if own {
            Flow::continue_from(&mut *problem, state, settings)?
        } else {
            Flow::resume(&mut *problem, state, settings)?
        };
        flow.vertex_fields()
    }
    let kind = job.stage_problem(state.stage);
    match state.mesh.dimension {
        2 => in_dim::<2>(kind.curve_problem(), job, state, own),
        3 => in_dim::<3>(kind.surface_problem()?, job, state, own),
        d => Err(FlowError::Checkpoint(format!("dimension {d}"))),
    }
}
