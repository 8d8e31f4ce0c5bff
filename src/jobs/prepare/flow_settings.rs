//! `flow`: the flow settings, resolved from the spec and the problem's defaults.

use super::checks::positive;
use super::ProblemKind;
use crate::flow::{FlowSettings, ScalarProduct, SolverKind};
use crate::jobs::spec::bounds::MAX_ITERATIONS;
use crate::jobs::spec::{FlowSpec, SpecError};

/// Default `flow.tau` of the stressed film (its rates are `γk⁴` for wavenumbers `k`).
pub const STRESSED_FILM_TAU: f64 = 1e-5;
/// Default `flow.tau_min` of the stressed film: just after a void closes off, the
/// corners where the walls met move at up to `~10⁷` and need steps near `h⁴/γ`
/// (measured down to 2e-12 at 128 vertices) until surface diffusion has rounded them.
pub const STRESSED_FILM_TAU_MIN: f64 = 1e-15;
/// Default `flow.conservation` of the stressed film.
pub const STRESSED_FILM_CONSERVATION: f64 = 1e-6;

/// Default `flow.tau` of segmentation with the Newton-type H1 product.
pub const SEGMENTATION_NEWTON_TAU: f64 = 10.0;

/// Default `flow.tau` (the cap of the adaptive step) of shape design.
pub const SHAPE_DESIGN_TAU: f64 = 10.0;

/// Default `flow.tau` of Chan–Vese segmentation, times `L`: the data term's speed
/// is at most `max(λ_in, λ_out)` (normalized intensities), so a step moves the
/// contour at most about this many pixels; the step control and backtracking
/// shorten it where needed.
pub const CHAN_VESE_TAU_PIXELS: f64 = 8.0;

/// Default `flow.tau` of segmentation with the L2 (and plain H1) product.
pub const SEGMENTATION_L2_TAU: f64 = 1e-3;

/// The flow settings of `f` for `problem`, each default the problem's own and each
/// bound checked with the field named.
pub(super) fn flow_settings(f: &FlowSpec, problem: &ProblemKind) -> Result<FlowSettings, SpecError> {
    let default_product = problem.curve_problem().default_scalar_product();
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
    let default_tau = match (problem, scalar_product) {
        // the Newton-type product scales V like a Newton step (τ = 1); far from edges
        // β is clipped at ε and V = -G/ε, so a larger cap lets the step control decide
        (ProblemKind::Segmentation(_), ScalarProduct::H1Newton) => SEGMENTATION_NEWTON_TAU,
        (ProblemKind::Segmentation(_), _) => SEGMENTATION_L2_TAU,
        (ProblemKind::ChanVese(p), _) => CHAN_VESE_TAU_PIXELS / p.intensity.scale(),
        // the step control and backtracking pick the step; τ only caps it
        (ProblemKind::ShapeDesign(_), _) => SHAPE_DESIGN_TAU,
        (ProblemKind::StressedFilm(_), _) => STRESSED_FILM_TAU,
        _ => d.tau,
    };
    let tau = positive("flow.tau", f.tau.unwrap_or(default_tau))?;
    let default_tau_min = match problem {
        ProblemKind::StressedFilm(_) => STRESSED_FILM_TAU_MIN,
        _ => d.tau_min,
    };
    let tau_min = positive("flow.tau_min", f.tau_min.unwrap_or(default_tau_min.min(tau)))?;
    if tau_min > tau {
        return Err(SpecError::new("flow.tau_min", format!("must not exceed flow.tau ({tau})")));
    }
    // a run given an end time runs to it unless the spec also asks for a tolerance
    let default_tolerance = if f.end_time.is_some() { 0.0 } else { d.tolerance };
    let tolerance = f.tolerance.unwrap_or(default_tolerance);
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(SpecError::new("flow.tolerance", format!("must be a nonnegative number, got {tolerance}")));
    }
    let end_time = f.end_time.map(|t| positive("flow.end_time", t)).transpose()?;
    let step_control = match f.step_control {
        None => d.step_control,
        Some(e) if e == 0.0 => None,
        Some(e) => Some(positive("flow.step_control", e)?),
    };
    let conservation = match (f.conservation, problem) {
        (None, ProblemKind::StressedFilm(_)) => Some(STRESSED_FILM_CONSERVATION),
        (None, _) => None,
        (Some(c), _) if c == 0.0 => None,
        (Some(c), _) => Some(positive("flow.conservation", c)?),
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
        backtracking: f.backtracking.unwrap_or(!problem.physical()),
        step_control,
        alpha,
        beta,
        conservation,
        tolerance_per_time: problem.physical(),
    };
    Ok(settings)
}
