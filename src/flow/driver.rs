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
//!    wetting layer). Last, on the state the step would accept (that offset
//!    included), so does a surface on which two triangles sharing no vertex meet
//!    (components passing through each other, or one through itself: never
//!    accepted), checked along the whole step too when it moves a vertex by more
//!    than a quarter of the mean edge ([`super::intersections`]); where surfaces
//!    merge, so does a contact of their curved sheets ([`surface_contact`]);
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
//! After an accepted step it stops with [`StopReason::Converged`] when
//! `|J_{n+1} − J_n| ≤ tolerance·|J_n|·s`, with `s = τ/τ_spec` for physical
//! evolutions (a rate). For the others `s = 1`, and only steps whose `τ` the flow's
//! own limits set are judged: `τ_spec`, the end time, step control or
//! backtracking; not a step that tangling cut short (a sliver flipping however
//! short the step), nor one whose `τ` is still doubling back after a short step
//! and below half the last such `τ`. Those change `J` little because they are
//! short, not because the state is stationary.

use super::acceptance::{self as rules, Verdict};
use super::contact::{advanced, first_contact, surface_contact};
use super::mesh_management::MeshManager;
use super::problem::Problem;
use super::report::{Progress, Rejection, StepReport, StopReason, SurgeryRecord};
use super::settings::FlowSettings;
use super::step::SemiImplicitStep;
use super::system::LinearSystem;
use super::FlowError;
use crate::fem::{Matrices, Pattern};
use crate::geometry::{Mesh, PatchSearch};
use std::sync::atomic::{AtomicBool, Ordering};

pub use super::checkpoint::{Checkpoint, MeshData};

impl StepReport {
    /// Apply a rule's verdict: on a retry, count and record the rejection and
    /// return the shorter `τ` (the trial step is then abandoned).
    fn retry(&mut self, verdict: Verdict) -> Option<f64> {
        let Verdict::Retry { tau, rejection } = verdict else { return None };
        if rejection.is_backtrack() {
            self.backtracks += 1;
        } else {
            self.reductions += 1;
        }
        self.rejected = Some(rejection);
        Some(tau)
    }
}

/// A running gradient flow on a mesh of dimension `D`.
pub struct Flow<'p, const D: usize> {
    pub(super) problem: &'p mut dyn Problem<D>,
    pub(super) settings: FlowSettings,
    pub(super) mesh: Mesh<D>,
    pub(super) pattern: Pattern<D>,
    pub(super) solver: SemiImplicitStep,
    /// Workspace: the P1 matrices of the current mesh (allocations reused).
    pub(super) matrices: Matrices<D>,
    pub(super) iteration: usize,
    pub(super) time: f64,
    pub(super) tau: f64,
    pub(super) energy: f64,
    pub(super) manager: Option<Box<dyn MeshManager<D> + 'p>>,
    /// Why [`Flow::run`] ended with `tau_min` (the last rejection).
    pub(super) stop_cause: Option<Rejection>,
    /// The iteration at which [`Problem::rediscretize`] was last called (once per
    /// iteration).
    pub(super) rediscretized_at: Option<usize>,
    /// The `τ` of the last step that the flow's own limits set (`τ_spec`, the end
    /// time, step control, backtracking): a step growing back to it after a short
    /// one is judged for convergence once it is at least half as long.
    pub(super) settled_tau: f64,
    /// The recorded energies (after mesh management) at the ends of the last judged
    /// steps, oldest first, at most [`rules::WINDOW`] + 1 of them: the test over
    /// several steps.
    pub(super) recent: Vec<f64>,
    /// The most vertices mesh management may give the mesh
    /// ([`crate::limits::MAX_MESH_GROWTH`] times those it started with).
    pub(super) vertex_limit: usize,
    /// The topological surgeries so far, oldest first.
    pub(super) surgeries: Vec<SurgeryRecord>,
    /// The intersection search of trial surfaces (its patches kept while the
    /// connectivity is).
    pub(super) search: PatchSearch,
}

impl<'p, const D: usize> Flow<'p, D> {
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
            surgery: self.surgeries.last().filter(|s| s.iteration == self.iteration).map(|s| s.event),
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
            coarse: false,
            settled_tau: self.settled_tau,
            recent_energies: self.recent.clone(),
            surgeries: self.surgeries.clone(),
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

    /// Take one step (with its retries), or report why the run is over.
    pub fn step(&mut self) -> Result<StepReport, FlowError> {
        let s = &self.settings;
        let mut report = StepReport::new();
        if self.iteration >= s.max_iterations {
            report.stop = Some(StopReason::MaxIterations);
            return Ok(report);
        }
        let mut tau = s.tau.min(2.0 * self.tau);
        // still growing back after a step that was cut short
        let growing = 2.0 * self.tau < s.tau;
        if let Some(end) = s.end_time {
            let left = end - self.time;
            if left <= 1e-12 * end.abs().max(1.0) {
                report.stop = Some(StopReason::EndTime);
                return Ok(report);
            }
            tau = tau.min(left);
        }
        let lin = self.linearize()?;
        let limits = self.problem.step_limits(&self.mesh);
        let s = &self.settings;
        let matrices = &self.matrices;
        let (ax, grad, product) = (&lin.ax, &lin.grad, &lin.product);
        // an `H⁻¹` flow conserves each component's measure: the step's `O(τ²)`
        // change of it is removed whether or not `conservation` also bounds it
        let conserving = s.conserves_measure();
        let (a0, components) = match conserving {
            true => (self.mesh.enclosed_measure(), self.mesh.component_measures()),
            false => (0.0, Vec::new()),
        };
        let mut smallest_rise = f64::INFINITY;
        let mut tangled = false;
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
                report.stop = Some(rules::stop_below_tau_min(report.rejected, smallest_rise, s.tolerance, self.energy));
                tracing::debug!(iteration = self.iteration, smallest_rise, last = ?report.rejected, "no step above tau_min");
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
                limits: limits.as_deref(),
            };
            let vel = self.solver.velocity(&sys)?;
            let advanced = advanced(&self.mesh, &vel.vector, tau);
            let a1 = if s.conservation.is_some() { advanced.enclosed_measure() } else { a0 };
            // the problem's constraints (an obstacle, the image's box, the objects'
            // territories)
            let mut candidate = self.problem.constrain_step(&self.mesh, advanced, &mut self.search);
            let limit = rules::motion_limit(&self.mesh, &candidate, tau, s.step_control);
            if let Some(shorter) = report.retry(rules::step_control(tau, limit)) {
                tau = shorter;
                continue;
            }
            // a tangled step is retried with half the step; below tau_min the run
            // stops with `tau_min` on the last good state
            if let Some(shorter) = report.retry(rules::tangling(&self.mesh, &candidate, tau)) {
                tangled = true;
                tau = shorter;
                continue;
            }
            if let Some(shorter) = report.retry(rules::conservation(a0, a1, s.conservation, tau, s.tau_min)) {
                tau = shorter;
                continue;
            }
            if conserving {
                // the step's O(τ²) change of each component's measure (and what the
                // constraint added) removed
                candidate = candidate.with_component_measures(&components);
                if let Some(shorter) = report.retry(rules::tangling(&self.mesh, &candidate, tau)) {
                    tangled = true;
                    tau = shorter;
                    continue;
                }
            }
            // after the conservation's correction, which moves every vertex
            // and, where the surfaces merge, a contact of their curved sheets
            let (verdict, curved) =
                surface_contact(&self.mesh, &candidate, tau, &mut self.search, self.manager.as_deref());
            if let Some(shorter) = report.retry(verdict) {
                if shorter >= super::intersections::CONTACT * s.tau {
                    tau = shorter;
                    continue;
                }
                // in contact: shorter steps would only creep closer. A merge if the
                // management merges (not one folded through itself); else the run
                // ends on the last state, or a curved contact alone is taken as a
                // step (its curved gap is below zero: the triangles' rule goes on)
                let merged = self.manager.as_mut().and_then(|m| m.merge(&self.mesh));
                if let Some(merged) =
                    merged.filter(|m| super::intersections::surface_intersection(m, &mut self.search).is_none())
                {
                    let at = curved.unwrap_or_else(|| {
                        super::intersections::contact_point(&self.mesh, &candidate, &mut self.search)
                    });
                    self.take_merge(merged, at)?;
                    report.rejected = None;
                    report.merged = true;
                    report.accepted = true;
                    return Ok(report);
                }
                if curved.is_none() {
                    report.stop = Some(StopReason::TauMin);
                    return Ok(report);
                }
            }
            let mut energy = self.problem.energy(&candidate).map_err(|e| FlowError::Problem(e.0))?;
            if energy.is_nan() || energy == f64::NEG_INFINITY {
                return Err(FlowError::NonFiniteEnergy { value: energy, iteration: self.iteration + 1 });
            }
            if energy > self.energy && energy.is_finite() && s.backtracking && self.problem.merges(&candidate) {
                // a merge is an event of the flow, not a descent step: shorten the
                // step to just past the first contact and take it
                if let Some((t, c, e)) =
                    first_contact(&mut *self.problem, &mut self.solver, &sys, (&candidate, energy))?
                {
                    (tau, candidate, energy, report.contact) = (t, c, e, true);
                }
            }
            tracing::trace!(tau, energy, current = self.energy, "trial");
            if !report.contact {
                let verdict = rules::energy(self.energy, energy, s.backtracking, tau);
                if let Some(shorter) = report.retry(verdict) {
                    tau = shorter;
                    smallest_rise = smallest_rise.min(energy - self.energy);
                    continue;
                }
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
            // a step whose τ the flow's own limits did not set (tangling cut it
            // short, or τ is still growing back after such a step) changes `J` little
            // because it is short, not because the state is stationary
            let limited = report.backtracks > 0 || report.reductions > 0;
            let (judged, settled) = rules::judged_step(tau, self.settled_tau, tangled, growing, limited);
            let last_settled = std::mem::replace(&mut self.settled_tau, settled);
            let (per_time, tolerance, tau_min) = (s.tolerance_per_time, s.tolerance, s.tau_min);
            let judged = judged || per_time;
            let scale = if s.tolerance_per_time { tau / s.tau } else { 1.0 };
            let small = (previous - energy).abs() <= s.tolerance * previous.abs() * scale;
            // a non-physical flow's step is small twice in a row: one step that
            // overshoots a stiff mode can change `J` by next to nothing while the
            // state still moves (the steps around it lowering `J` by far more)
            let settled_before = per_time || rules::last_change_small(&self.recent, s.tolerance);
            if judged && s.tolerance > 0.0 && small && settled_before {
                report.stop = Some(StopReason::Converged);
            }
            let managed = match self.manage_mesh() {
                Err(FlowError::Management(reason)) => {
                    // the step left a shape the management cannot repair: it is taken
                    // back, and the next call tries half of it
                    tracing::debug!(iteration = self.iteration, %reason, tau, "management failed, step taken back");
                    (self.mesh, self.time, self.energy, self.settled_tau) = (before, time, previous, last_settled);
                    self.tau = 0.25 * tau;
                    self.iteration -= 1;
                    report.accepted = false;
                    report.rejected = Some(Rejection::Management);
                    report.stop = (0.5 * tau < tau_min).then_some(StopReason::TauMin);
                    return Ok(report);
                }
                other => other?,
            };
            match managed {
                Some(StopReason::PinchOff) => {
                    // a neck collapsed during this step, which the mesh no longer
                    // resolves: the run ends on the last good state, before the step
                    (self.mesh, self.time, self.tau, self.energy) = (before, time, last_tau, previous);
                    self.iteration -= 1;
                    report.accepted = false;
                    report.stop = Some(StopReason::PinchOff);
                }
                Some(stop) => report.stop = Some(stop),
                None => {}
            }
            // the recorded energies of the judged steps of a non-physical flow; a
            // step that is not judged starts the window again
            if judged && !per_time && report.accepted {
                self.recent.push(self.energy);
                if self.recent.len() > rules::WINDOW + 1 {
                    self.recent.remove(0);
                }
                if report.stop.is_none() && rules::stationary_over_window(&self.recent, tolerance) {
                    report.stop = Some(StopReason::Converged);
                }
            } else {
                self.recent.clear();
            }
            return Ok(report);
        }
    }
}
