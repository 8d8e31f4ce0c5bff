//! The interface between the flow and an application (implemented in `problems`).

use crate::fem::{Matrices, Pattern, Weight};
use crate::geometry::{Mesh, PatchSearch, Point};

use super::ScalarProduct;

/// The shape gradient `G = g κ + f` (paper eq. 13) at the vertices of `Γ`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeGradient {
    pub g: Vec<f64>,
    pub f: Vec<f64>,
    /// Per-vertex values a problem computes along with `g` and `f` for its own
    /// [`Problem::h1_weights`] (segmentation: `∂_ν H` and `ν·D²H·ν`); empty if unused.
    pub aux: Vec<f64>,
}

/// A problem's own per-vertex field ([`Problem::own_field`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OwnField {
    /// The glTF attribute name (`_EDGE_INDICATOR`, `_ELASTIC_ENERGY_DENSITY`, …).
    pub name: &'static str,
    pub values: Vec<f64>,
}

/// Weights of the weighted H1 product `b(V, W) = ∫ α ∇V·∇W + β V W`.
#[derive(Debug, Clone, PartialEq)]
pub struct H1Weights {
    pub alpha: Weight,
    pub beta: Weight,
}

/// What a problem may look at on `Γ_n`: the mesh, its P1 matrices, the discrete
/// curvature `κ_i = N⃗_i·(A X)_i / |N⃗_i|²` and unit vertex normals.
pub struct SurfaceState<'a, const D: usize> {
    pub mesh: &'a Mesh<D>,
    pub matrices: &'a Matrices<D>,
    pub curvature: &'a [f64],
    pub normals: &'a [Point<D>],
}

/// A problem's own defaults of the flow settings; `None` takes the flow's
/// ([`super::FlowSettings::default`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlowDefaults {
    /// `flow.tau`, the step (or the cap of the adaptive step).
    pub tau: Option<f64>,
    /// `flow.tau_min`.
    pub tau_min: Option<f64>,
    /// `flow.conservation`: the enclosed measure kept to this relative change per
    /// step.
    pub conservation: Option<f64>,
    /// `flow.tolerance` of a run without an end time.
    pub tolerance: Option<f64>,
}

/// An error raised by a problem (bad data met during a run).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ProblemError(pub String);

/// A shape functional `J(Ω)` with shape derivative `dJ(Ω; V) = ∫_Γ (g κ + f) V`.
///
/// The driver holds the problem it runs as `&mut`: `energy`, `shape_gradient` and
/// `rediscretize` may update state that follows the shape from call to call (shape
/// design: the bulk mesh that trial curves reuse; the film: the last field). Such a
/// problem keeps that state in a run of its own, apart from its description (see
/// `problems::ShapeDesign::start`), so that a description is plain data.
pub trait Problem<const D: usize>: Send {
    /// Name as in the job spec (`problem.type`).
    fn name(&self) -> &'static str;
    /// `J(Γ)`; `+∞` marks an inadmissible shape (the flow then shortens the step).
    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError>;
    /// `g` and `f` at the vertices of `Γ_n`.
    fn shape_gradient(&mut self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError>;
    /// α and β of the problem's own weighted H1 product (`h1_newton`), if it has one.
    fn h1_weights(&self, _state: &SurfaceState<'_, D>, _grad: &ShapeGradient) -> Option<H1Weights> {
        None
    }
    /// The problem's own per-vertex field for output (the glTF attribute it is
    /// written as, and its values), if it has one: segmentation's edge indicator
    /// `H`, the stressed film's elastic energy density `|∇y|²`. From the samples
    /// taken for the gradient `grad`.
    fn own_field(&self, _state: &SurfaceState<'_, D>, _grad: &ShapeGradient) -> Option<OwnField> {
        None
    }
    /// The scalar product used when the spec does not name one.
    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::L2
    }
    /// The problem's defaults of `flow.tau`, `flow.tau_min` and `flow.conservation`
    /// for a run with the scalar product `product`.
    fn flow_defaults(&self, _product: ScalarProduct) -> FlowDefaults {
        FlowDefaults::default()
    }
    /// Physical flows (surface diffusion, the film) follow time accurately: a job's
    /// defaults then have no backtracking and a tolerance per unit time.
    fn is_physical(&self) -> bool {
        false
    }
    /// Whether [`Problem::energy`] evaluates `mesh` as the union of two of its
    /// components that cross: a step to it merges them. The driver then takes the
    /// step at the first contact even if the energy rises (a curve touching itself
    /// is not a merge: such steps are backtracked as usual).
    fn merges(&self, _mesh: &Mesh<D>) -> bool {
        false
    }
    /// Drop whatever discretization follows the shape from step to step (shape
    /// design: the bulk mesh that trial curves reuse) and evaluate `J(mesh)` on a
    /// fresh one. `None` if the problem keeps no such state. The driver calls this
    /// when backtracking fails: the trials may then differ from the current shape
    /// by the discretization error of a new bulk mesh rather than by the step.
    fn rediscretize(&mut self, _mesh: &Mesh<D>) -> Result<Option<f64>, ProblemError> {
        Ok(None)
    }
    /// `ε ≥ 0` of an added bending energy `ε/2 ∫_Γ κ²` (an addition to the paper's
    /// functionals; curves only, `H^{-1}` product, lumped solver). Its gradient is
    /// `ε(−Δ_Γκ − κ³/2)`: the flow keeps `−εΔ_Γκ` implicit in the step (the system
    /// then reads `M̂ V + A((g + ε M̂⁻¹A) K + f) = 0`), while the problem itself adds
    /// `ε/2 ∫ κ²` to [`Problem::energy`] and `−εκ³/2` to `f`.
    fn bending(&self) -> f64 {
        0.0
    }
    /// Limits on where a step from `mesh` may take each vertex (segmentation: the
    /// image's box), which the step's solve keeps by an active set (the lumped solver with the L2 and H1 products; see
    /// [`super::StepLimits`]); [`Problem::constrain_step`] then enforces what is
    /// left. `None` by default.
    fn step_limits(&self, _mesh: &Mesh<D>) -> Option<Box<dyn super::StepLimits<D>>> {
        None
    }
    /// A trial step's shape with the problem's constraints enforced (stressed film:
    /// the wetting layer as an obstacle); by default unchanged.
    fn constrain(&self, candidate: Mesh<D>) -> Mesh<D> {
        candidate
    }
    /// [`Problem::constrain`] with the shape the step starts from (the same
    /// connectivity), for constraints between parts of the shape (segmentation:
    /// objects that meet stop where they meet); by default `constrain(candidate)`.
    /// `search` is the flow's intersection search of surfaces, which then checks
    /// the result: a constraint that searches the result in full leaves its
    /// answer there.
    fn constrain_step(&self, _current: &Mesh<D>, candidate: Mesh<D>, _search: &mut PatchSearch) -> Mesh<D> {
        self.constrain(candidate)
    }
}

/// The discrete curvature `κ_i = N⃗_i·(A X)_i / |N⃗_i|²` and the unit vertex normals
/// `N⃗_i/|N⃗_i|` of [`SurfaceState`], from the matrices and `A X`.
pub(crate) fn curvature_and_normals<const D: usize>(
    matrices: &Matrices<D>,
    ax: &[Point<D>],
) -> (Vec<f64>, Vec<Point<D>>) {
    let n = &matrices.lumped_normal;
    (n.iter().zip(ax).map(|(n, a)| n.dot(a) / n.norm_squared()).collect(), n.iter().map(|n| n.normalize()).collect())
}

/// The discrete shape derivative of `problem` at `mesh` along the vertex field `V⃗`:
/// `dJ(Γ; V⃗) = ∫_Γ G V⃗·ν ≈ Σ_i (g_i κ_i + f_i) N⃗_i·V⃗_i`, with `N⃗_i = ∫_Γ φ_i ν` and the
/// discrete curvature of the flow. Used to check shape gradients against finite
/// differences of `J`.
pub fn shape_derivative<const D: usize>(
    problem: &mut dyn Problem<D>,
    mesh: &Mesh<D>,
    field: &[Point<D>],
) -> Result<f64, ProblemError> {
    let pattern = Pattern::new(mesh.num_vertices(), mesh.elements());
    let matrices = Matrices::assemble(mesh, &pattern);
    let ax = matrices.stiffness_times_positions(mesh, &pattern);
    let (curvature, normals) = curvature_and_normals(&matrices, &ax);
    let state = SurfaceState { mesh, matrices: &matrices, curvature: &curvature, normals: &normals };
    let grad = problem.shape_gradient(&state)?;
    Ok((0..mesh.num_vertices())
        .map(|i| (grad.g[i] * curvature[i] + grad.f[i]) * matrices.lumped_normal[i].dot(&field[i]))
        .sum())
}
