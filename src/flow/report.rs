//! What a flow reports: why a run stopped, the progress after a step, what one
//! step did and why a trial step was rejected.

use serde::{Deserialize, Serialize};

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

/// Progress after a step (what the callback and the service report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    pub iteration: usize,
    pub time: f64,
    pub tau: f64,
    pub energy: f64,
    pub vertices: usize,
    pub components: usize,
    /// The topological surgery that made this state (a merge or a pinch-off cut in
    /// 3D), if one did; left out of the JSON otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surgery: Option<SurgeryEvent>,
}

/// What a topological surgery of surfaces did ([`super::surgery`]), and where.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SurgeryEvent {
    pub kind: SurgeryKind,
    /// A point of the surgery: the contact of a merge, the neck of a pinch-off,
    /// the centroid of a component that vanished.
    pub at: [f64; 3],
    /// The number of components after it.
    pub components: usize,
}

/// The kinds of topological surgery.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurgeryKind {
    /// Surfaces in contact joined.
    Merge,
    /// A neck cut and both sides capped.
    Pinch,
    /// A component that shrank below the mesh's resolution removed (the rest go on).
    Vanish,
}

impl SurgeryKind {
    pub fn as_str(&self) -> &'static str {
        match self {
            SurgeryKind::Merge => "merge",
            SurgeryKind::Pinch => "pinch",
            SurgeryKind::Vanish => "vanish",
        }
    }
}

/// A surgery as a run records it (checkpoints, shape.json): the iteration and flow
/// time of the state it made.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SurgeryRecord {
    pub iteration: usize,
    pub time: f64,
    #[serde(flatten)]
    pub event: SurgeryEvent,
}

/// What one call of [`super::Flow::step`] did.
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
    /// re-evaluated on a fresh one ([`super::Problem::rediscretize`]; module documentation,
    /// item 5): no step was taken, the next call starts from the new energy.
    pub rediscretized: bool,
    /// Surfaces in contact were merged ([`super::surgery`]): the accepted iteration
    /// is the merge, of no flow time (`time` and `tau` stay); the next call steps
    /// from the merged surface.
    pub merged: bool,
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
    /// The mesh management could not repair the shape the step left (the step is
    /// taken back after it was accepted).
    Management,
    /// Surfaces would pass through each other, or one through itself.
    Intersection,
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
            Rejection::Intersection => {
                "every trial step made the surface pass through itself or another component: the surfaces \
                 are in contact, and the run ends on the last state before the contact"
            }
            Rejection::Management => {
                "the mesh management could not repair the curve that every trial step left (a fold it could \
                 not resolve)"
            }
        }
    }
}

impl Rejection {
    /// Whether the rejection is a backtracking one (the energy rose, or the shape
    /// was inadmissible), counted in [`StepReport::backtracks`]; the others count
    /// in [`StepReport::reductions`].
    pub fn is_backtrack(&self) -> bool {
        matches!(self, Rejection::EnergyIncrease | Rejection::Inadmissible)
    }
}

impl StepReport {
    /// A report of no step yet.
    pub(super) fn new() -> Self {
        StepReport {
            stop: None,
            accepted: false,
            backtracks: 0,
            reductions: 0,
            rejected: None,
            contact: false,
            rediscretized: false,
            merged: false,
        }
    }
}
