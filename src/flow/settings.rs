//! The settings of a flow (the job spec's `flow` section, resolved) and their
//! checks.

use super::problem::Problem;
use super::step::SolverKind;
use super::system::ScalarProduct;
use super::FlowError;
use serde::{Deserialize, Serialize};

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

impl FlowSettings {
    /// Whether the flow keeps each component's enclosed measure: an `H⁻¹` flow, or
    /// one with `conservation`; its steps and mesh management give it back.
    pub fn conserves_measure(&self) -> bool {
        self.conservation.is_some() || self.scalar_product == ScalarProduct::HMinus1
    }
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

/// Every setting within its bounds (the field named otherwise).
pub(super) fn check_settings(s: &FlowSettings) -> Result<(), FlowError> {
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
pub(super) fn check_bending<const D: usize>(problem: &dyn Problem<D>, s: &FlowSettings) -> Result<(), FlowError> {
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
