//! The driver: time-step selection (geometric control, backtracking), stop
//! criteria, progress, cancellation and checkpoints.
//!
//! Each step tries `τ = min(τ_spec, 2 τ_last)` (clipped to the end time), solves for
//! `V⃗`, and then
//! 1. *geometric control* (paper §4.1): if `τ max_T |V⃗(z_a) − V⃗(z_b)| / h_T > ε`
//!    the step is retried with `τ ← 0.9 ε τ / ratio`;
//! 2. *tangling*: an element that degenerates or flips halves `τ`; so does a change
//!    of the enclosed measure above `conservation` (relative, when set; down to
//!    `4 τ_min`); an accepted change below it is then removed by offsetting each
//!    component along its normals ([`Mesh::with_component_measures`]), after the
//!    problem's constraints are enforced ([`Problem::constrain`]: the film's
//!    wetting layer);
//! 3. *backtracking* (paper §3.2): while `J(Γ_{n+1}) > J(Γ_n)`, halve `τ`;
//! 4. *contact* (paper §4.1, topological changes): a trial step in which two
//!    curves cross ([`Problem::merges`]) and whose merged shape has a higher energy
//!    is not backtracked away from the contact: `τ` is bisected down to just past
//!    the first contact and that step is taken. Backtracking alone would keep such
//!    curves apart forever, creeping together with `τ → 0` along a growing stretch
//!    where they touch without merging, because merging removes the stretch where
//!    they meet (in shape design, boundary through which the state's flux enters
//!    `Ω`). A curve that touches itself (a neck or a notch closing) is backtracked
//!    as usual;
//! 5. *rediscretization*: when backtracking has brought `τ` below `τ_min`, the
//!    problem may re-evaluate the current state on a fresh discretization
//!    ([`Problem::rediscretize`]; shape design: trial curves reuse the current
//!    state's bulk mesh, and once its triangles at `Γ` are too flat every trial is
//!    triangulated afresh and differs from `J_n` by that change of mesh, which can
//!    exceed what the step gains). `J_n` is replaced by the fresh value and the step
//!    is tried again, once per iteration.
//!
//! Below `τ_min` the run stops with [`StopReason::TauMin`] on the last good state,
//! or with [`StopReason::Converged`] when the trials were rejected for raising `J`
//! by no more than `tolerance·|J|` (the state is stationary to the tolerance).

use super::mesh_management::{Managed, MeshManager};
use super::problem::{curvature_and_normals, Problem, SurfaceState};
use super::step::{SemiImplicitStep, SolverKind};
use super::system::{LinearSystem, ProductWeights, ScalarProduct};
use super::FlowError;
use crate::fem::{Matrices, Pattern, Weight};
use crate::geometry::{degenerate_measure, simplex, Mesh, Point};
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};

pub use super::checkpoint::{Checkpoint, MeshData};

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    Converged,
    MaxIterations,
    EndTime,
    TauMin,
    Cancelled,
    /// A neck of a surface collapsed (mesh management detected it after the step).
    PinchOff,
    /// Every component shrank below the smallest size the mesh management keeps
    /// (curves: `min_area`): nothing is left to evolve. The run ends on the last
    /// state, whose components are all below that size.
    Vanished,
}

impl StopReason {
    pub fn as_str(&self) -> &'static str {
        match self {
            StopReason::Converged => "converged",
            StopReason::MaxIterations => "max_iterations",
            StopReason::EndTime => "end_time",
            StopReason::TauMin => "tau_min",
            StopReason::Cancelled => "cancelled",
            StopReason::PinchOff => "pinch_off",
            StopReason::Vanished => "vanished",
        }
    }
}

/// Settings of the flow (the job spec's `flow` section, resolved).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlowSettings {
    pub scalar_product: ScalarProduct,
    pub solver: SolverKind,
    /// Nominal time step.
    pub tau: f64,
    /// Smallest time step before the run stops with `tau_min`.
    pub tau_min: f64,
    pub max_iterations: usize,
    pub end_time: Option<f64>,
    /// Stop when `|J_{n+1} − J_n| ≤ tolerance·|J_n|` (0 disables; see also
    /// `tolerance_per_time`).
    pub tolerance: f64,
    /// Halve τ until the energy decreases.
    pub backtracking: bool,
    /// ε of the geometric time-step control (`None` disables).
    pub step_control: Option<f64>,
    /// Constant α, β of the plain `h1` product.
    pub alpha: f64,
    pub beta: f64,
    /// Largest relative change of the enclosed measure per step (`None`: no
    /// check). For area-conserving (`H^{-1}`) flows, whose steps conserve it up to
    /// `O(τ²)`: a larger change halves τ, a smaller one is removed by offsetting each
    /// component to its measure before the step.
    #[serde(default)]
    pub conservation: Option<f64>,
    /// Physical evolutions: compare the energy change with `tolerance·|J_n|·τ/τ_cap`
    /// (`τ_cap` = [`Self::tau`]), a relative rate of change, so that a run of steps
    /// forced far below the cap (a fresh topological change, a pinch) is not taken
    /// for convergence.
    #[serde(default)]
    pub tolerance_per_time: bool,
}

impl Default for FlowSettings {
    fn default() -> Self {
        FlowSettings {
            scalar_product: ScalarProduct::L2,
            solver: SolverKind::Lumped,
            tau: 1e-3,
            tau_min: 1e-10,
            max_iterations: 1000,
            end_time: None,
            tolerance: 1e-6,
            backtracking: true,
            step_control: Some(0.5),
            alpha: 1e-2,
            beta: 1.0,
            conservation: None,
            tolerance_per_time: false,
        }
    }
}

/// Progress after a step (what the callback and the service report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    pub iteration: usize,
    pub time: f64,
    pub tau: f64,
    pub energy: f64,
    pub vertices: usize,
    pub components: usize,
}

/// What one call of [`Flow::step`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// `Some` if the run is over (then no step was taken, except for `Converged`,
    /// which is reported after the step that converged).
    pub stop: Option<StopReason>,
    /// Whether a step was accepted.
    pub accepted: bool,
    /// Halvings of τ by backtracking (energy increase) in this step.
    pub backtracks: usize,
    /// Reductions of τ by the geometric control, tangling or conservation in this step.
    pub reductions: usize,
    /// Why the last trial step of this call was rejected (with `stop:
    /// Some(TauMin)`: why the run could not go on).
    pub rejected: Option<Rejection>,
    /// The accepted step ends just past the first contact of two curves (a merge
    /// taken although the energy rose; see the module documentation, item 4).
    pub contact: bool,
    /// Backtracking failed on the followed discretization, and the current state was
    /// re-evaluated on a fresh one ([`Problem::rediscretize`]; module documentation,
    /// item 5): no step was taken, the next call starts from the new energy.
    pub rediscretized: bool,
}

/// Why a trial step was rejected (τ then shrinks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rejection {
    /// The geometric control: vertices would move too far relative to their elements.
    StepControl,
    /// An element would degenerate or flip.
    Tangled,
    /// The enclosed measure would change by more than `conservation`.
    Conservation,
    /// The problem rejected the shape (energy `+∞`).
    Inadmissible,
    /// The energy would increase (backtracking).
    EnergyIncrease,
}

impl Rejection {
    /// A sentence for users: why the last trial steps failed.
    pub fn describe(&self) -> &'static str {
        match self {
            Rejection::StepControl => {
                "the geometric step control kept shrinking the step (the velocity is very large relative to \
                 the element sizes somewhere, e.g. at a sharp corner)"
            }
            Rejection::Tangled => "every trial step tangled the mesh",
            Rejection::Conservation => "every trial step changed the enclosed area beyond flow.conservation",
            Rejection::Inadmissible => {
                "every trial shape was inadmissible for the problem (shape design: the curve met D or Σ; \
                 stressed film: the surface met the substrate or a lateral wall outside its crossing)"
            }
            Rejection::EnergyIncrease => "every trial step increased the energy (backtracking)",
        }
    }
}

/// A running gradient flow on a mesh of dimension `D`.
pub struct Flow<'p, const D: usize> {
    problem: &'p dyn Problem<D>,
    settings: FlowSettings,
    mesh: Mesh<D>,
    pattern: Pattern<D>,
    solver: SemiImplicitStep,
    /// Workspace: the P1 matrices of the current mesh (allocations reused).
    matrices: Matrices<D>,
    iteration: usize,
    time: f64,
    tau: f64,
    energy: f64,
    manager: Option<Box<dyn MeshManager<D> + 'p>>,
    /// Why [`Flow::run`] ended with `tau_min` (the last rejection).
    stop_cause: Option<Rejection>,
    /// The iteration at which [`Problem::rediscretize`] was last called (once per
    /// iteration).
    rediscretized_at: Option<usize>,
}

impl<'p, const D: usize> Flow<'p, D> {
    /// Run mesh management (regularization, adaptivity, topology) after every step.
    pub fn with_mesh_manager(mut self, manager: Box<dyn MeshManager<D> + 'p>) -> Self {
        self.manager = Some(manager);
        self
    }

    /// Start a flow at iteration 0, time 0.
    pub fn new(problem: &'p dyn Problem<D>, mesh: Mesh<D>, settings: FlowSettings) -> Result<Self, FlowError> {
        check_settings(&settings)?;
        check_bending(problem, &settings)?;
        let energy = problem.energy(&mesh).map_err(|e| FlowError::Problem(e.0))?;
        if !energy.is_finite() {
            return Err(FlowError::NonFiniteEnergy { value: energy, iteration: 0 });
        }
        let tau = settings.tau;
        Ok(Self::assemble_state(problem, mesh, settings, 0, 0.0, tau, energy))
    }

    /// Continue from a checkpoint.
    pub fn resume(
        problem: &'p dyn Problem<D>,
        checkpoint: &Checkpoint,
        settings: FlowSettings,
    ) -> Result<Self, FlowError> {
        check_settings(&settings)?;
        check_bending(problem, &settings)?;
        let mesh = checkpoint.mesh.to_mesh::<D>().map_err(|e| FlowError::Checkpoint(e.to_string()))?;
        Ok(Self::assemble_state(
            problem,
            mesh,
            settings,
            checkpoint.iteration,
            checkpoint.time,
            checkpoint.tau,
            checkpoint.energy,
        ))
    }

    /// Continue a state this process's own flow produced (the next stage of a job)
    /// with another problem: like [`Flow::resume`], without validating the mesh
    /// again (the flow keeps its meshes valid up to the tolerances of its own
    /// checks, which are not those of a file read from outside).
    pub fn continue_from(
        problem: &'p dyn Problem<D>,
        checkpoint: &Checkpoint,
        settings: FlowSettings,
    ) -> Result<Self, FlowError> {
        check_settings(&settings)?;
        check_bending(problem, &settings)?;
        let mesh = checkpoint
            .mesh
            .to_mesh_unvalidated::<D>()
            .ok_or_else(|| FlowError::Checkpoint(format!("not a mesh of dimension {D}")))?;
        Ok(Self::assemble_state(
            problem,
            mesh,
            settings,
            checkpoint.iteration,
            checkpoint.time,
            checkpoint.tau,
            checkpoint.energy,
        ))
    }

    fn assemble_state(
        problem: &'p dyn Problem<D>,
        mesh: Mesh<D>,
        settings: FlowSettings,
        iteration: usize,
        time: f64,
        tau: f64,
        energy: f64,
    ) -> Self {
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
        }
    }

    pub fn mesh(&self) -> &Mesh<D> {
        &self.mesh
    }
    pub fn settings(&self) -> &FlowSettings {
        &self.settings
    }
    pub fn energy(&self) -> f64 {
        self.energy
    }
    pub fn time(&self) -> f64 {
        self.time
    }
    pub fn iteration(&self) -> usize {
        self.iteration
    }

    pub fn progress(&self) -> Progress {
        Progress {
            iteration: self.iteration,
            time: self.time,
            tau: self.tau,
            energy: self.energy,
            vertices: self.mesh.num_vertices(),
            components: self.mesh.num_components(),
        }
    }

    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            iteration: self.iteration,
            time: self.time,
            tau: self.tau,
            energy: self.energy,
            mesh: MeshData::from(&self.mesh),
            stage: 0,
        }
    }

    /// Why the last [`Flow::run`] stopped with `tau_min`: the rejection of its last
    /// trial step.
    pub fn stop_cause(&self) -> Option<Rejection> {
        self.stop_cause
    }

    /// Run until a stop reason, calling `on_progress` after every accepted step
    /// (and once at the start), and checking `cancel` before every step.
    pub fn run(&mut self, cancel: &AtomicBool, mut on_progress: impl FnMut(&Self)) -> Result<StopReason, FlowError> {
        on_progress(self);
        loop {
            if cancel.load(Ordering::Relaxed) {
                return Ok(StopReason::Cancelled);
            }
            let report = self.step()?;
            if report.accepted {
                on_progress(self);
            }
            if let Some(stop) = report.stop {
                self.stop_cause = report.rejected.filter(|_| stop == StopReason::TauMin);
                return Ok(stop);
            }
        }
    }

    /// Assemble on `Γ_n`: `A X`, the discrete curvature, the shape gradient and the
    /// weights of the scalar product.
    fn linearize(&mut self) -> Result<Linearization<D>, FlowError> {
        let s = &self.settings;
        self.matrices.assemble_into(&self.mesh, &self.pattern, s.solver == SolverKind::Consistent);
        let matrices = &self.matrices;
        let ax = matrices.stiffness_times_positions(&self.mesh, &self.pattern);
        let (curvature, normals) = curvature_and_normals(matrices, &ax);
        let state = SurfaceState { mesh: &self.mesh, matrices, curvature: &curvature, normals: &normals };
        let grad = self.problem.shape_gradient(&state).map_err(|e| FlowError::Problem(e.0))?;
        check_values("g", &grad.g, self.mesh.num_vertices())?;
        check_values("f", &grad.f, self.mesh.num_vertices())?;
        let product = match s.scalar_product {
            ScalarProduct::L2 => ProductWeights::L2,
            ScalarProduct::HMinus1 => ProductWeights::HMinus1,
            ScalarProduct::H1 => {
                ProductWeights::H1 { alpha: Weight::Constant(s.alpha), beta: Weight::Constant(s.beta) }
            }
            ScalarProduct::H1Newton => match self.problem.h1_weights(&state, &grad) {
                Some(w) => {
                    for (what, weight) in [("alpha", &w.alpha), ("beta", &w.beta)] {
                        weight.check(&self.mesh).map_err(|r| FlowError::Problem(format!("{what}: {r}")))?;
                    }
                    ProductWeights::H1 { alpha: w.alpha, beta: w.beta }
                }
                None => ProductWeights::H1 { alpha: Weight::Constant(s.alpha), beta: Weight::Constant(s.beta) },
            },
        };
        Ok(Linearization { ax, curvature, grad, product })
    }

    /// Per-vertex fields of the current state for output: the discrete curvature
    /// `κ_i` and the normal velocity `V_i` of the next step with the last `τ`
    /// (nothing moves).
    pub fn vertex_fields(&mut self) -> Result<(Vec<f64>, Vec<f64>), FlowError> {
        let lin = self.linearize()?;
        let sys = LinearSystem {
            mesh: &self.mesh,
            pattern: &self.pattern,
            matrices: &self.matrices,
            ax: &lin.ax,
            g: &lin.grad.g,
            f: &lin.grad.f,
            product: &lin.product,
            tau: self.tau,
            bending: self.problem.bending(),
        };
        let vel = self.solver.velocity(&sys)?;
        Ok((lin.curvature, vel.normal))
    }

    /// Take one step (with its retries), or report why the run is over.
    pub fn step(&mut self) -> Result<StepReport, FlowError> {
        let s = &self.settings;
        let mut report = StepReport {
            stop: None,
            accepted: false,
            backtracks: 0,
            reductions: 0,
            rejected: None,
            contact: false,
            rediscretized: false,
        };
        if self.iteration >= s.max_iterations {
            report.stop = Some(StopReason::MaxIterations);
            return Ok(report);
        }
        let mut tau = s.tau.min(2.0 * self.tau);
        if let Some(end) = s.end_time {
            let left = end - self.time;
            if left <= 1e-12 * end.abs().max(1.0) {
                report.stop = Some(StopReason::EndTime);
                return Ok(report);
            }
            tau = tau.min(left);
        }
        let lin = self.linearize()?;
        let s = &self.settings;
        let matrices = &self.matrices;
        let (ax, grad, product) = (&lin.ax, &lin.grad, &lin.product);
        let (a0, components) = match s.conservation {
            Some(_) => (self.mesh.enclosed_measure(), self.mesh.component_measures()),
            None => (0.0, Vec::new()),
        };
        let mut smallest_rise = f64::INFINITY;
        loop {
            if tau < s.tau_min {
                if report.rejected == Some(Rejection::EnergyIncrease) && self.rediscretized_at != Some(self.iteration) {
                    self.rediscretized_at = Some(self.iteration);
                    let fresh = self.problem.rediscretize(&self.mesh).map_err(|e| FlowError::Problem(e.0))?;
                    if let Some(energy) = fresh.filter(|e| e.is_finite() && *e != self.energy) {
                        tracing::debug!(iteration = self.iteration, from = self.energy, to = energy, "rediscretized");
                        self.energy = energy;
                        report.rediscretized = true;
                        return Ok(report);
                    }
                }
                // no step lowers J, and none raises it by more than the tolerance:
                // the state is stationary to the tolerance (rounding and quadrature
                // of J, not a failure of the flow)
                let stationary = s.tolerance > 0.0 && smallest_rise <= s.tolerance * self.energy.abs();
                report.stop = Some(if report.rejected == Some(Rejection::EnergyIncrease) && stationary {
                    StopReason::Converged
                } else {
                    StopReason::TauMin
                });
                return Ok(report);
            }
            let sys = LinearSystem {
                mesh: &self.mesh,
                pattern: &self.pattern,
                matrices,
                ax,
                g: &grad.g,
                f: &grad.f,
                product,
                tau,
                bending: self.problem.bending(),
            };
            let vel = self.solver.velocity(&sys)?;
            if let Some(eps) = s.step_control {
                let ratio = tau * relative_motion(&self.mesh, &vel.vector);
                if ratio > eps {
                    tau *= (0.9 * eps / ratio).min(0.5);
                    report.reductions += 1;
                    report.rejected = Some(Rejection::StepControl);
                    continue;
                }
            }
            let mut candidate = advanced(&self.mesh, &vel.vector, tau);
            if tangled(&self.mesh, &candidate).is_some() {
                // retried with half the step; below tau_min the run stops with
                // `tau_min` on the last good state
                tau *= 0.5;
                report.reductions += 1;
                report.rejected = Some(Rejection::Tangled);
                continue;
            }
            if let Some(tol) = s.conservation {
                let a1 = candidate.enclosed_measure();
                // down to 4 τ_min: a fresh topological change leaves corners that
                // need a few very short steps; below that the step is taken anyway
                if (a1 - a0).abs() > tol * a0.abs() && tau > 4.0 * s.tau_min {
                    tau *= 0.5;
                    report.reductions += 1;
                    report.rejected = Some(Rejection::Conservation);
                    continue;
                }
            }
            // the problem's constraints (an obstacle), then the step's O(τ²) change of
            // each component's measure (and what the constraint added) removed
            candidate = self.problem.constrain_step(&self.mesh, candidate);
            if s.conservation.is_some() {
                candidate = candidate.with_component_measures(&components);
            }
            let mut energy = self.problem.energy(&candidate).map_err(|e| FlowError::Problem(e.0))?;
            if energy.is_nan() || energy == f64::NEG_INFINITY {
                return Err(FlowError::NonFiniteEnergy { value: energy, iteration: self.iteration + 1 });
            }
            if energy > self.energy && energy.is_finite() && s.backtracking && self.problem.merges(&candidate) {
                // a merge is an event of the flow, not a descent step: shorten the
                // step to just past the first contact and take it
                if let Some((t, c, e)) = first_contact(self.problem, &mut self.solver, &sys, (&candidate, energy))? {
                    (tau, candidate, energy, report.contact) = (t, c, e, true);
                }
            }
            // +∞ marks an inadmissible candidate (shape design: Γ met D or Σ), which
            // is shortened even where backtracking is off
            if !report.contact && energy > self.energy && (s.backtracking || energy == f64::INFINITY) {
                smallest_rise = smallest_rise.min(energy - self.energy);
                tau *= 0.5;
                report.backtracks += 1;
                report.rejected =
                    Some(if energy == f64::INFINITY { Rejection::Inadmissible } else { Rejection::EnergyIncrease });
                continue;
            }
            tracing::debug!(
                iteration = self.iteration + 1,
                tau,
                backtracks = report.backtracks,
                reductions = report.reductions,
                last_rejection = ?report.rejected,
                "step accepted"
            );
            let previous = self.energy;
            let before = std::mem::replace(&mut self.mesh, candidate);
            let (time, last_tau) = (self.time, self.tau);
            self.time += tau;
            self.tau = tau;
            self.energy = energy;
            self.iteration += 1;
            report.accepted = true;
            let scale = if s.tolerance_per_time { tau / s.tau } else { 1.0 };
            if s.tolerance > 0.0 && (previous - energy).abs() <= s.tolerance * previous.abs() * scale {
                report.stop = Some(StopReason::Converged);
            }
            let managed = self.manage_mesh()?;
            if managed == ManageOutcome::Vanished {
                report.stop = Some(StopReason::Vanished);
            }
            if managed == ManageOutcome::PinchOff {
                // a neck collapsed during this step, which the mesh no longer
                // resolves: the run ends on the last good state, before the step
                (self.mesh, self.time, self.tau, self.energy) = (before, time, last_tau, previous);
                self.iteration -= 1;
                report.accepted = false;
                report.stop = Some(StopReason::PinchOff);
            }
            return Ok(report);
        }
    }
}

impl<const D: usize> Flow<'_, D> {
    /// Apply the mesh manager, if any; a new connectivity rebuilds the pattern and
    /// drops the symbolic factorizations. The energy is re-evaluated on the result.
    fn manage_mesh(&mut self) -> Result<ManageOutcome, FlowError> {
        let Some(manager) = self.manager.as_mut() else { return Ok(ManageOutcome::Continue) };
        let (mesh, remeshed) = match manager.manage(&self.mesh)? {
            Managed::Unchanged => return Ok(ManageOutcome::Continue),
            Managed::PinchOff => return Ok(ManageOutcome::PinchOff),
            Managed::Vanished => return Ok(ManageOutcome::Vanished),
            Managed::Moved(m) => (m, false),
            Managed::Remeshed(m) => (m, true),
        };
        let energy = self.problem.energy(&mesh).map_err(|e| FlowError::Problem(e.0))?;
        if energy == f64::INFINITY {
            // management made the shape inadmissible (shape design: a regularized
            // spike crossed a fixed boundary): keep the accepted mesh this time
            return Ok(ManageOutcome::Continue);
        }
        if !energy.is_finite() {
            return Err(FlowError::NonFiniteEnergy { value: energy, iteration: self.iteration });
        }
        self.mesh = mesh;
        if remeshed {
            self.pattern = Pattern::new(self.mesh.num_vertices(), self.mesh.elements());
            self.solver.reset();
        }
        self.energy = energy;
        Ok(ManageOutcome::Continue)
    }
}

/// What the mesh management after an accepted step means for the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ManageOutcome {
    Continue,
    PinchOff,
    Vanished,
}

fn check_settings(s: &FlowSettings) -> Result<(), FlowError> {
    let bad = |field: &'static str, reason: &str| Err(FlowError::Settings { field, reason: reason.into() });
    if !(s.tau.is_finite() && s.tau > 0.0) {
        return bad("flow.tau", "must be a positive number");
    }
    if !(s.tau_min.is_finite() && s.tau_min > 0.0 && s.tau_min <= s.tau) {
        return bad("flow.tau_min", "must be positive and at most flow.tau");
    }
    if !(s.tolerance.is_finite() && s.tolerance >= 0.0) {
        return bad("flow.tolerance", "must be a nonnegative number");
    }
    if let Some(t) = s.end_time {
        if !(t.is_finite() && t > 0.0) {
            return bad("flow.end_time", "must be a positive number");
        }
    }
    if let Some(e) = s.step_control {
        if !(e.is_finite() && e > 0.0) {
            return bad("flow.step_control", "must be a positive number");
        }
    }
    if !(s.alpha.is_finite() && s.alpha >= 0.0) {
        return bad("flow.alpha", "must be a nonnegative number");
    }
    if !(s.beta.is_finite() && s.beta > 0.0) {
        return bad("flow.beta", "must be a positive number");
    }
    Ok(())
}

/// A bending energy needs the `H^{-1}` product, the lumped solver and a curve.
fn check_bending<const D: usize>(problem: &dyn Problem<D>, s: &FlowSettings) -> Result<(), FlowError> {
    let eps = problem.bending();
    let bad = |reason: &str| Err(FlowError::Settings { field: "problem.bending", reason: reason.into() });
    if !(eps.is_finite() && eps >= 0.0) {
        return bad("must be a nonnegative number");
    }
    if eps > 0.0 {
        if D != 2 {
            return bad("is implemented for curves (2D) only");
        }
        if s.scalar_product != ScalarProduct::HMinus1 {
            return bad("needs flow.scalar_product h_minus_1");
        }
        if s.solver != SolverKind::Lumped {
            return bad("needs flow.solver lumped");
        }
    }
    Ok(())
}

fn check_values(what: &'static str, v: &[f64], n: usize) -> Result<(), FlowError> {
    if v.len() != n {
        return Err(FlowError::Problem(format!("{what} has {} values for {n} vertices", v.len())));
    }
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(FlowError::NonFiniteInput { what, index }),
        None => Ok(()),
    }
}

/// `max_T max_{a,b ∈ T} |V⃗(z_a) − V⃗(z_b)| / h_T`: relative motion per unit time.
fn relative_motion<const D: usize>(mesh: &Mesh<D>, v: &[Point<D>]) -> f64 {
    let mut worst: f64 = 0.0;
    for (e, el) in mesh.elements().iter().enumerate() {
        let h = simplex::diameter(&mesh.element_points(e));
        for a in 0..D {
            for b in a + 1..D {
                worst = worst.max((v[el[a]] - v[el[b]]).norm() / h);
            }
        }
    }
    worst
}

/// `Γ_n` moved by `τ V⃗`.
fn advanced<const D: usize>(mesh: &Mesh<D>, velocity: &[Point<D>], tau: f64) -> Mesh<D> {
    mesh.with_positions(mesh.positions().iter().zip(velocity).map(|(x, v)| x + v * tau).collect())
}

/// Bisections of `τ` that locate a first contact (to `2⁻¹⁰` of the trial step).
const CONTACT_BISECTIONS: usize = 10;

/// The step of `sys` (whose candidate `full`, with its energy, merges curves)
/// shortened to just past the first contact: `τ` is bisected between `0` (the
/// current shape, whose curves do not cross) and `sys.tau`, keeping the upper end a
/// merging candidate; returns that `τ`, its candidate and energy, or `None` if a
/// shortened candidate is tangled or inadmissible (the step is then backtracked as
/// usual).
#[allow(clippy::type_complexity)]
fn first_contact<const D: usize>(
    problem: &dyn Problem<D>,
    solver: &mut SemiImplicitStep,
    sys: &LinearSystem<'_, D>,
    full: (&Mesh<D>, f64),
) -> Result<Option<(f64, Mesh<D>, f64)>, FlowError> {
    let mut trial = |tau: f64| -> Result<Option<Mesh<D>>, FlowError> {
        let vel = solver.velocity(&LinearSystem { tau, ..*sys })?;
        let candidate = advanced(sys.mesh, &vel.vector, tau);
        Ok(if tangled(sys.mesh, &candidate).is_some() { None } else { Some(candidate) })
    };
    let (mut lo, mut hi) = (0.0, sys.tau);
    let mut best = None;
    for _ in 0..CONTACT_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        match trial(mid)? {
            Some(c) if problem.merges(&c) => {
                hi = mid;
                best = Some(c);
            }
            Some(_) => lo = mid,
            None => return Ok(None),
        }
    }
    // no shorter step merged: the contact lies within the last bisection interval
    let Some(candidate) = best else { return Ok(Some((sys.tau, full.0.clone(), full.1))) };
    let energy = problem.energy(&candidate).map_err(|e| FlowError::Problem(e.0))?;
    Ok(energy.is_finite().then_some((hi, candidate, energy)))
}

/// What a step needs from `Γ_n`.
struct Linearization<const D: usize> {
    ax: Vec<Point<D>>,
    curvature: Vec<f64>,
    grad: super::problem::ShapeGradient,
    product: ProductWeights,
}

/// First element that degenerated (relative to `old`, or below what validation
/// accepts: [`degenerate_measure`]) or flipped between `old` and `new`.
fn tangled<const D: usize>(old: &Mesh<D>, new: &Mesh<D>) -> Option<usize> {
    let tiny = degenerate_measure(new.positions());
    (0..old.num_elements()).find(|&e| {
        let (m0, n0) = old.element_geometry(e);
        let (m1, n1) = new.element_geometry(e);
        !(m1 > 1e-12 * m0) || !(m1 > tiny) || n0.dot(&n1) <= 0.0 || !m1.is_finite()
    })
}
