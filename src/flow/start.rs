//! How a [`Flow`] starts: afresh, from a stored checkpoint, or from the end of a
//! previous stage of the same job; and with a mesh manager.

use super::driver::Flow;
use super::mesh_management::MeshManager;
use super::problem::Problem;
use super::settings::{check_bending, check_settings, FlowSettings};
use super::step::SemiImplicitStep;
use super::{Checkpoint, FlowError};
use crate::fem::{Matrices, Pattern};
use crate::geometry::{Mesh, PatchSearch};

impl<'p, const D: usize> Flow<'p, D> {
    /// Run mesh management (regularization, adaptivity, topology) after every step.
    pub fn with_mesh_manager(mut self, manager: Box<dyn MeshManager<D> + 'p>) -> Self {
        self.manager = Some(manager);
        self
    }

    /// Start a flow at iteration 0, time 0.
    pub fn new(problem: &'p mut dyn Problem<D>, mesh: Mesh<D>, settings: FlowSettings) -> Result<Self, FlowError> {
        check_settings(&settings)?;
        check_bending(&*problem, &settings)?;
        let energy = problem.energy(&mesh).map_err(|e| FlowError::Problem(e.0))?;
        if !energy.is_finite() {
            return Err(FlowError::NonFiniteEnergy { value: energy, iteration: 0 });
        }
        let tau = settings.tau;
        Ok(Self::assemble_state(problem, mesh, settings, 0, 0.0, tau, energy))
    }

    /// Continue from a checkpoint (its mesh validated: it may come from a file).
    pub fn resume(
        problem: &'p mut dyn Problem<D>,
        checkpoint: &Checkpoint,
        settings: FlowSettings,
    ) -> Result<Self, FlowError> {
        let mesh = checkpoint.mesh.to_mesh::<D>().map_err(|e| FlowError::Checkpoint(e.to_string()));
        Self::from_checkpoint(problem, checkpoint, mesh, settings)
    }

    /// Continue a state this process's own flow produced (the next stage of a job,
    /// with another problem; the fields of a checkpoint's frame): like
    /// [`Flow::resume`], without validating the mesh again (the flow keeps its
    /// meshes valid up to the tolerances of its own checks, which are not those of
    /// a file read from outside).
    pub fn continue_from(
        problem: &'p mut dyn Problem<D>,
        checkpoint: &Checkpoint,
        settings: FlowSettings,
    ) -> Result<Self, FlowError> {
        let mesh = checkpoint
            .mesh
            .to_mesh_unvalidated::<D>()
            .ok_or_else(|| FlowError::Checkpoint(format!("not a mesh of dimension {D}")));
        Self::from_checkpoint(problem, checkpoint, mesh, settings)
    }

    /// The flow at `checkpoint`'s iteration, time, τ and energy on `mesh`.
    fn from_checkpoint(
        problem: &'p mut dyn Problem<D>,
        checkpoint: &Checkpoint,
        mesh: Result<Mesh<D>, FlowError>,
        settings: FlowSettings,
    ) -> Result<Self, FlowError> {
        check_settings(&settings)?;
        check_bending(&*problem, &settings)?;
        let mut flow = Self::assemble_state(
            problem,
            mesh?,
            settings,
            checkpoint.iteration,
            checkpoint.time,
            checkpoint.tau,
            checkpoint.energy,
        );
        flow.settled_tau = checkpoint.settled_tau;
        flow.recent = checkpoint.recent_energies.clone();
        flow.surgeries = checkpoint.surgeries.clone();
        Ok(flow)
    }

    fn assemble_state(
        problem: &'p mut dyn Problem<D>,
        mesh: Mesh<D>,
        settings: FlowSettings,
        iteration: usize,
        time: f64,
        tau: f64,
        energy: f64,
    ) -> Self {
        let vertices = mesh.num_vertices();
        let pattern = Pattern::new(mesh.num_vertices(), mesh.elements());
        let solver = SemiImplicitStep::new(settings.solver);
        let matrices = Matrices::assemble(&mesh, &pattern);
        Flow {
            problem,
            settings,
            mesh,
            pattern,
            solver,
            matrices,
            iteration,
            time,
            tau,
            energy,
            manager: None,
            stop_cause: None,
            rediscretized_at: None,
            settled_tau: 0.0,
            recent: Vec::new(),
            vertex_limit: vertex_limit(vertices),
            surgeries: Vec::new(),
            search: PatchSearch::default(),
        }
    }
}

/// The most vertices a run that starts with `vertices` may grow to.
fn vertex_limit(vertices: usize) -> usize {
    use crate::limits::{MAX_MESH_GROWTH, MAX_VERTICES, MIN_VERTEX_ALLOWANCE};
    (MAX_MESH_GROWTH.saturating_mul(vertices)).max(MIN_VERTEX_ALLOWANCE).min(MAX_VERTICES.max(vertices))
}
