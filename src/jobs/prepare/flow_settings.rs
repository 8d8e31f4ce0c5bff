//! `flow`: the flow settings, resolved from the spec and the problem's defaults
//! ([`crate::flow::Problem::flow_defaults`]).

use super::checks::positive;
use super::ProblemKind;
use crate::flow::{FlowSettings, ScalarProduct, SolverKind};
use crate::jobs::spec::bounds::MAX_ITERATIONS;
use crate::jobs::spec::{FlowSpec, SpecError};

/// The flow settings of `f` for `problem`, each default the problem's own and each
/// bound checked with the field named.
pub(super) fn flow_settings(f: &FlowSpec, problem: &ProblemKind) -> Result<FlowSettings, SpecError> {
    let run = problem.curve_problem();
    let default_product = run.default_scalar_product();
    let scalar_product = f.scalar_product.unwrap_or(default_product);
    if let ProblemKind::StressedFilm(p) = problem {
        if p.bending > 0.0 && scalar_product != ScalarProduct::HMinus1 {
            return Err(SpecError::new("problem.bending", "needs flow.scalar_product h_minus_1"));
        }
        if p.bending > 0.0 && f.solver.unwrap_or_default() != SolverKind::Lumped {
            return Err(SpecError::new("problem.bending", "needs flow.solver lumped"));
        }
    }
    let d = FlowSettings::default();
    let own = run.flow_defaults(scalar_product);
    let default_tau = own.tau.unwrap_or(d.tau);
    let tau = positive("flow.tau", f.tau.unwrap_or(default_tau))?;
    let default_tau_min = own.tau_min.unwrap_or(d.tau_min);
    let tau_min = positive("flow.tau_min", f.tau_min.unwrap_or(default_tau_min.min(tau)))?;
    if tau_min > tau {
        return Err(SpecError::new("flow.tau_min", format!("must not exceed flow.tau ({tau})")));
    }
    // a run given an end time runs to it unless the spec also asks for a tolerance
    let default_tolerance = if f.end_time.is_some() { 0.0 } else { own.tolerance.unwrap_or(d.tolerance) };
    let tolerance = f.tolerance.unwrap_or(default_tolerance);
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(SpecError::new("flow.tolerance", format!("must be a nonnegative number, got {tolerance}")));
    }
    let end_time = f.end_time.map(|t| positive("flow.end_time", t)).transpose()?;
    let step_control = match f.step_control {
        None => d.step_control,
        Some(0.0) => None,
        Some(e) => Some(positive("flow.step_control", e)?),
    };
    let conservation = match f.conservation {
        None => own.conservation,
        Some(0.0) => None,
        Some(c) => Some(positive("flow.conservation", c)?),
    };
    let alpha = f.alpha.unwrap_or(d.alpha);
    if !(alpha.is_finite() && alpha >= 0.0) {
        return Err(SpecError::new("flow.alpha", format!("must be a nonnegative number, got {alpha}")));
    }
    let beta = positive("flow.beta", f.beta.unwrap_or(d.beta))?;
    let max_iterations = MAX_ITERATIONS.check("flow.max_iterations", f.max_iterations.unwrap_or(d.max_iterations))?;
    let settings = FlowSettings {
        scalar_product,
        solver: f.solver.unwrap_or_default(),
        tau,
        tau_min,
        max_iterations,
        end_time,
        tolerance,
        backtracking: f.backtracking.unwrap_or(!run.is_physical()),
        step_control,
        alpha,
        beta,
        conservation,
        tolerance_per_time: run.is_physical(),
    };
    Ok(settings)
}
