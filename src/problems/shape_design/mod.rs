//! Optimal shape design for an elliptic PDE (paper §1.2, §2.2.2, §4.3):
//!
//! ```text
//! J(Ω) = ½ ∫_D (y − z_g)² + γ|Γ|,    −Δy = 0 in Ω, y = 0 on Σ, ∂_ν y = 1 on Γ,
//! ```
//!
//! with the adjoint `−Δp = χ_D (y − z_g)`, `p = 0` on `Σ`, `∂_ν p = 0` on `Γ`.
//!
//! Signs: the paper writes `G = −∇_Γ y·∇_Γ p + κ(p + γ)` for velocities along the
//! outward normal `ν` of `Ω`, which on `Γ` points into the hole. Our curves carry their
//! own outward normal `n = −ν` (away from the hole) and their curvature `κ_Γ = −κ`,
//! and the velocity is `V_Γ = −V`; hence along `n`
//!
//! ```text
//! G_Γ = (p + γ) κ_Γ + ∇_Γ y·∇_Γ p      (g = p + γ, f = ∇_Γ y·∇_Γ p).
//! ```
//!
//! The tangential derivatives are the lumped L2 projections of the elementwise
//! difference quotients of the P1 traces onto P1 (length-weighted averages at the
//! vertices). The weighted H1 product of the paper (eq. 84) has `β = 1` and `α`
//! per edge from `g` at its ends (`p` in the paper, where `γ = 0`): 1 where `g` takes
//! negative values (there the L2 flow is backward parabolic), `h_e²` where `g` is
//! well above its oscillation, and a linear blend in between.

use crate::bulk::{curve_sensitivity, solve_design_fields, BulkError, BulkMesh, DesignDomain, MeshingOptions};
use crate::fem::{tangential_derivative, Weight};
use crate::flow::{H1Weights, Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState};
use crate::geometry::{resolve_intersections, winding_number, CurveMesh, Mesh, Point};
use serde::{Deserialize, Serialize};
use std::sync::{Arc, Mutex};

mod target;

pub use target::Target;

/// How the shape gradient `G` is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GradientKind {
    /// The exact gradient of the discrete `J_h`, its normal
    /// part per vertex: `G_i = ∂J_h/∂X_i · N⃗_i / |N⃗_i|²`.
    #[default]
    Discrete,
    /// The paper's formula `G = (p + γ)κ + ∇_Γy·∇_Γp` with recovered tangential
    /// derivatives.
    Continuous,
}

/// State, adjoint and energy of one curve.
#[derive(Debug, Clone)]
pub struct DesignSolution {
    /// `y` and `p` at the curve's vertices.
    pub y: Vec<f64>,
    pub p: Vec<f64>,
    /// `½ ∫_D (y − z_g)²`.
    pub misfit: f64,
    /// `J = misfit + γ|Γ|`.
    pub energy: f64,
    /// `∂J_h/∂X_i` at the curve's vertices (see [`curve_sensitivity`]).
    pub sensitivity: Vec<Point<2>>,
}

/// The last solve: its curve, bulk mesh and solution.
struct Cached {
    positions: Vec<Point<2>>,
    elements: Vec<[usize; 2]>,
    bulk: Arc<BulkMesh>,
    solution: Arc<DesignSolution>,
}

/// Smallest angle (degrees) of the triangles at `Γ` for which a bulk mesh follows the
/// moving curve instead of being rebuilt.
pub const FOLLOW_MIN_ANGLE: f64 = 5.0;

/// The shape-design functional on a fixed domain.
pub struct ShapeDesign {
    pub domain: Arc<DesignDomain>,
    pub target: Target,
    /// Weight `γ ≥ 0` of the length of `Γ`.
    pub gamma: f64,
    /// Topology changes on: a candidate whose curves cross is evaluated as the union
    /// it becomes (the mesh manager merges it after the step). Off: crossing is
    /// inadmissible.
    pub merge: bool,
    /// Loops below this area are dropped when crossing curves are merged.
    pub min_area: f64,
    pub meshing: MeshingOptions,
    /// How `G` is computed (default: the exact gradient of the discrete functional).
    pub gradient: GradientKind,
    cache: Mutex<Option<Cached>>,
    /// The curve connectivity and bulk mesh of the state the last shape gradient was
    /// taken at (the current step's), which trial curves follow.
    base: Mutex<Option<(Vec<[usize; 2]>, Arc<BulkMesh>)>>,
    /// The free vertices of the first triangulation: seeds of the later ones, away
    /// from `Γ` (see [`BulkMesh::build_seeded`]).
    background: Mutex<Option<Vec<Point<2>>>>,
}

impl std::fmt::Debug for ShapeDesign {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShapeDesign").field("target", &self.target).field("gamma", &self.gamma).finish_non_exhaustive()
    }
}

impl Clone for ShapeDesign {
    /// A copy with an empty solution cache.
    fn clone(&self) -> Self {
        let mut copy =
            ShapeDesign::new(self.domain.clone(), self.target, self.gamma, self.merge, self.min_area, self.meshing);
        copy.gradient = self.gradient;
        copy
    }
}

impl PartialEq for ShapeDesign {
    fn eq(&self, o: &Self) -> bool {
        self.domain == o.domain
            && self.target == o.target
            && self.gamma == o.gamma
            && self.merge == o.merge
            && self.min_area == o.min_area
            && self.meshing == o.meshing
            && self.gradient == o.gradient
    }
}

impl ShapeDesign {
    pub fn new(
        domain: Arc<DesignDomain>,
        target: Target,
        gamma: f64,
        merge: bool,
        min_area: f64,
        meshing: MeshingOptions,
    ) -> Self {
        ShapeDesign {
            domain,
            target,
            gamma,
            merge,
            min_area,
            meshing,
            gradient: GradientKind::Discrete,
            cache: Mutex::new(None),
            base: Mutex::new(None),
            background: Mutex::new(None),
        }
    }

    /// Solves state and adjoint for a curve without crossings. `Err(Inadmissible)` if
    /// it leaves `Σ`, meets `D` or touches itself.
    ///
    /// The bulk mesh follows the curve: while the connectivity of `Γ` stays that of
    /// the state of the current step and the triangles at `Γ` keep angles of at least
    /// `FOLLOW_MIN_ANGLE`, that state's triangulation is reused with the curve's
    /// vertices moved. `J_h` is then a smooth function of the vertex positions with
    /// the exact gradient [`curve_sensitivity`], and backtracking compares trial
    /// curves with the current one on the same mesh; otherwise `Ω` is triangulated
    /// afresh.
    pub fn solve(&self, mesh: &CurveMesh) -> Result<Arc<DesignSolution>, BulkError> {
        let mut cache = self.cache.lock().expect("cache");
        if let Some(c) = cache.as_ref() {
            if c.positions == mesh.positions() && c.elements == mesh.elements() {
                return Ok(c.solution.clone());
            }
        }
        self.domain.check_curve(mesh)?;
        let base = self.base.lock().expect("base").clone();
        let followed = base
            .filter(|(elements, _)| elements.as_slice() == mesh.elements())
            .and_then(|(_, bulk)| bulk.with_curve_positions(mesh.positions(), FOLLOW_MIN_ANGLE));
        let bulk = match followed {
            Some(b) => b,
            None => self.triangulate(mesh)?,
        };
        let target = |x: Point<2>| self.target.value(x);
        let fields = solve_design_fields(&bulk, &target)?;
        let n = bulk.curve_vertices;
        let solution = Arc::new(DesignSolution {
            sensitivity: curve_sensitivity(&bulk, &fields, self.gamma),
            y: fields.y[..n].to_vec(),
            p: fields.p[..n].to_vec(),
            misfit: fields.misfit,
            energy: fields.misfit + self.gamma * mesh.boundary_measure(),
        });
        *cache = Some(Cached {
            positions: mesh.positions().to_vec(),
            elements: mesh.elements().to_vec(),
            bulk: Arc::new(bulk),
            solution: solution.clone(),
        });
        Ok(solution)
    }

    /// `Ω` triangulated afresh for `curve`, seeded with the first triangulation's
    /// free vertices that lie in `Ω` at least two segment lengths away from `Γ`
    /// (unseeded if that fails).
    fn triangulate(&self, curve: &CurveMesh) -> Result<BulkMesh, BulkError> {
        let mut background = self.background.lock().expect("background");
        if let Some(points) = background.as_ref() {
            let seeds = seeds_away_from(points, curve);
            if let Ok(bulk) = BulkMesh::build_seeded(&self.domain, curve, &self.meshing, &seeds) {
                return Ok(bulk);
            }
            return BulkMesh::build(&self.domain, curve, &self.meshing);
        }
        let bulk = BulkMesh::build(&self.domain, curve, &self.meshing)?;
        *background = Some(bulk.points.iter().zip(&bulk.free).filter(|(_, &f)| f).map(|(p, _)| *p).collect());
        Ok(bulk)
    }

    fn to_problem_error(e: BulkError) -> ProblemError {
        ProblemError(e.to_string())
    }
}

/// The points of `background` outside the holes of `curve` (winding number 0) and
/// farther than `2 h_max` from it (`h_max` its longest segment).
fn seeds_away_from(background: &[Point<2>], curve: &CurveMesh) -> Vec<Point<2>> {
    let x = curve.positions();
    let segments: Vec<(Point<2>, Point<2>)> = curve.elements().iter().map(|s| (x[s[0]], x[s[1]])).collect();
    let loops: Vec<Vec<Point<2>>> = curve.lifted_cycles().into_iter().map(|(l, _)| l).collect();
    let delta = 2.0 * segments.iter().map(|(a, b)| (b - a).norm()).fold(0.0, f64::max);
    let (mut lo, mut hi) = (Point::<2>::repeat(f64::INFINITY), Point::<2>::repeat(f64::NEG_INFINITY));
    for p in x {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let (lo, hi) = (lo.add_scalar(-delta), hi.add_scalar(delta));
    let near = |p: &Point<2>| {
        segments.iter().any(|(a, b)| {
            let (ab, ap) = (b - a, p - a);
            let t = (ap.dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            (ap - ab * t).norm_squared() <= delta * delta
        })
    };
    let outside_box = |p: &Point<2>| p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y;
    background.iter().filter(|p| outside_box(p) || (!near(p) && winding_number(&loops, **p) == 0)).copied().collect()
}

/// The curve behind a mesh of dimension `D` (shape design is two-dimensional; the
/// job builder only pairs it with curves).
fn curve<const D: usize>(mesh: &Mesh<D>) -> Result<&CurveMesh, ProblemError> {
    (mesh as &dyn std::any::Any)
        .downcast_ref::<CurveMesh>()
        .ok_or_else(|| ProblemError("shape design needs a curve (2D)".into()))
}

impl<const D: usize> Problem<D> for ShapeDesign {
    fn name(&self) -> &'static str {
        "shape_design"
    }

    /// `+∞` for inadmissible curves (the step is then shortened).
    fn energy(&self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        let mesh = curve(mesh)?;
        let merged;
        let mut c = mesh;
        if self.merge {
            if let Some(m) =
                resolve_intersections(mesh, self.min_area, true).map_err(|e| ProblemError(e.to_string()))?
            {
                merged = m;
                c = &merged;
            }
        }
        match self.solve(c) {
            Ok(s) => Ok(s.energy),
            Err(BulkError::Inadmissible(_)) => Ok(f64::INFINITY),
            Err(e) => Err(Self::to_problem_error(e)),
        }
    }

    /// With merging on, curves that cross are evaluated as their union.
    fn merges(&self, mesh: &Mesh<D>) -> bool {
        self.merge
            && curve(mesh).is_ok_and(|c| {
                let (component, _) = c.component_labels();
                let segments = c.elements();
                c.crossings().iter().any(|h| component[segments[h.a][0]] != component[segments[h.b][0]])
            })
    }

    /// A fresh triangulation of `Ω` for the current curve, which the next step's
    /// trial curves then follow.
    fn rediscretize(&self, mesh: &Mesh<D>) -> Result<Option<f64>, ProblemError> {
        *self.base.lock().expect("base") = None;
        *self.cache.lock().expect("cache") = None;
        self.energy(mesh).map(Some)
    }

    fn shape_gradient(&self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        let mesh = curve(state.mesh)?;
        let s = self.solve(mesh).map_err(Self::to_problem_error)?;
        // the trial curves of this step follow this state's bulk mesh
        if let Some(c) = self.cache.lock().expect("cache").as_ref() {
            *self.base.lock().expect("base") = Some((c.elements.clone(), c.bulk.clone()));
        }
        let g: Vec<f64> = s.p.iter().map(|p| p + self.gamma).collect();
        let f = match self.gradient {
            GradientKind::Continuous => {
                let dy = tangential_derivative(mesh, &s.y);
                let dp = tangential_derivative(mesh, &s.p);
                dy.iter().zip(&dp).map(|(a, b)| a * b).collect()
            }
            // G_i from the discrete gradient; the part g κ stays implicit in the step
            GradientKind::Discrete => (0..mesh.num_vertices())
                .map(|i| {
                    let nd = &state.matrices.lumped_normal[i];
                    let n = Point::<2>::new(nd[0], nd[1]);
                    s.sensitivity[i].dot(&n) / n.norm_squared() - g[i] * state.curvature[i]
                })
                .collect(),
        };
        Ok(ShapeGradient { g, f, aux: Vec::new() })
    }

    /// Paper eq. (84) with `g = p + γ`, `β = 1`.
    fn h1_weights(&self, state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<H1Weights> {
        let mesh = curve(state.mesh).ok()?;
        let alpha = mesh
            .elements()
            .iter()
            .map(|&[a, b]| {
                let h2 = (mesh.positions()[b] - mesh.positions()[a]).norm_squared();
                alpha_84(grad.g[a], grad.g[b], h2)
            })
            .collect();
        Some(H1Weights { alpha: Weight::Element(alpha), beta: Weight::Constant(1.0) })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::H1Newton
    }
}

/// `α_e` of paper eq. (84) from the values of `g` at the ends of edge `e` and `h_e²`.
pub fn alpha_84(g0: f64, g1: f64, h2: f64) -> f64 {
    let (lo, hi) = (g0.min(g1), g0.max(g1));
    if lo < 0.0 {
        return 1.0;
    }
    let (mean, osc) = (0.5 * (hi + lo), hi - lo);
    if mean <= osc {
        // osc > 0 here (mean ≥ lo ≥ 0 and mean ≤ osc, with mean = osc = 0 only if g ≡ 0)
        if osc > 0.0 {
            1.0 - mean * (1.0 - h2) / osc
        } else {
            1.0
        }
    } else {
        h2
    }
}

#[cfg(test)]
mod tests;
