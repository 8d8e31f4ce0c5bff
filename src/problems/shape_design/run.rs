//! A run of shape design: the state that follows the curve from one evaluation to
//! the next (the last solve, the bulk mesh that trial curves follow, the seeds of
//! later triangulations), owned by the flow that runs it.

use super::{DesignSolution, GradientKind, ShapeDesign};
use crate::bulk::{curve_sensitivity, solve_design_fields, BulkError, BulkMesh};
use crate::fem::{tangential_derivative, Weight};
use crate::flow::{FlowDefaults, H1Weights, Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState};
use crate::geometry::{resolve_intersections, winding_number, CurveMesh, Point};
use std::sync::Arc;

/// Smallest angle (degrees) of the triangles at `Γ` for which a bulk mesh follows the
/// moving curve instead of being rebuilt.
pub const FOLLOW_MIN_ANGLE: f64 = 5.0;

/// The last solve: its curve, bulk mesh and solution.
#[derive(Debug, Clone)]
struct Solved {
    positions: Vec<Point<2>>,
    elements: Vec<[usize; 2]>,
    bulk: Arc<BulkMesh>,
    solution: Arc<DesignSolution>,
}

/// Shape design as the flow runs it: the problem and its per-run state.
#[derive(Debug, Clone)]
pub struct DesignRun {
    pub design: ShapeDesign,
    last: Option<Solved>,
    /// The curve connectivity and bulk mesh of the state the last shape gradient was
    /// taken at (the current step's), which trial curves follow.
    base: Option<(Vec<[usize; 2]>, Arc<BulkMesh>)>,
    /// The free vertices of the first triangulation: seeds of the later ones, away
    /// from `Γ` (see [`BulkMesh::build_seeded`]).
    background: Option<Vec<Point<2>>>,
}

impl DesignRun {
    pub fn new(design: ShapeDesign) -> Self {
        DesignRun { design, last: None, base: None, background: None }
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
    pub fn solve(&mut self, mesh: &CurveMesh) -> Result<Arc<DesignSolution>, BulkError> {
        if let Some(c) = &self.last {
            if c.positions == mesh.positions() && c.elements == mesh.elements() {
                return Ok(c.solution.clone());
            }
        }
        let d = &self.design;
        d.domain.check_curve(mesh)?;
        let followed = self
            .base
            .as_ref()
            .filter(|(elements, _)| elements.as_slice() == mesh.elements())
            .and_then(|(_, bulk)| bulk.with_curve_positions(mesh.positions(), FOLLOW_MIN_ANGLE));
        let bulk = match followed {
            Some(b) => b,
            None => self.triangulate(mesh)?,
        };
        let d = &self.design;
        let target = |x: Point<2>| d.target.value(x);
        let fields = solve_design_fields(&bulk, &target)?;
        let n = bulk.mesh.curve_vertices;
        let solution = Arc::new(DesignSolution {
            sensitivity: curve_sensitivity(&bulk, &fields, d.gamma),
            y: fields.y[..n].to_vec(),
            p: fields.p[..n].to_vec(),
            misfit: fields.misfit,
            energy: fields.misfit + d.gamma * mesh.boundary_measure(),
        });
        self.last = Some(Solved {
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
    fn triangulate(&mut self, curve: &CurveMesh) -> Result<BulkMesh, BulkError> {
        let d = &self.design;
        if let Some(points) = &self.background {
            let seeds = seeds_away_from(points, curve);
            if let Ok(bulk) = BulkMesh::build_seeded(&d.domain, curve, &d.meshing, &seeds) {
                return Ok(bulk);
            }
            return BulkMesh::build(&d.domain, curve, &d.meshing);
        }
        let bulk = BulkMesh::build(&d.domain, curve, &d.meshing)?;
        self.background = Some(bulk.mesh.points.iter().zip(&bulk.free).filter(|(_, &f)| f).map(|(p, _)| *p).collect());
        Ok(bulk)
    }
}

/// The points of `background` outside the holes of `curve` (winding number 0) and
/// farther than `2 h_max` from it (`h_max` its longest segment).
pub(super) fn seeds_away_from(background: &[Point<2>], curve: &CurveMesh) -> Vec<Point<2>> {
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

fn problem_error(e: BulkError) -> ProblemError {
    ProblemError(e.to_string())
}

/// Shape design is two-dimensional: it is a problem on curves only.
impl Problem<2> for DesignRun {
    fn name(&self) -> &'static str {
        "shape_design"
    }

    /// `+∞` for inadmissible curves (the step is then shortened).
    fn energy(&mut self, mesh: &CurveMesh) -> Result<f64, ProblemError> {
        let merged;
        let mut c = mesh;
        if self.design.merge {
            if let Some(m) =
                resolve_intersections(mesh, self.design.min_area, true).map_err(|e| ProblemError(e.to_string()))?
            {
                merged = m;
                c = &merged;
            }
        }
        match self.solve(c) {
            Ok(s) => Ok(s.energy),
            Err(BulkError::Inadmissible(_)) => Ok(f64::INFINITY),
            Err(e) => Err(problem_error(e)),
        }
    }

    /// With merging on, curves that cross are evaluated as their union.
    fn merges(&self, c: &CurveMesh) -> bool {
        self.design.merge && {
            let (component, _) = c.component_labels();
            let segments = c.elements();
            c.crossings().iter().any(|h| component[segments[h.a][0]] != component[segments[h.b][0]])
        }
    }

    /// A fresh triangulation of `Ω` for the current curve, which the next step's
    /// trial curves then follow.
    fn rediscretize(&mut self, mesh: &CurveMesh) -> Result<Option<f64>, ProblemError> {
        self.base = None;
        self.last = None;
        self.energy(mesh).map(Some)
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, 2>) -> Result<ShapeGradient, ProblemError> {
        let mesh = state.mesh;
        let s = self.solve(mesh).map_err(problem_error)?;
        // the trial curves of this step follow this state's bulk mesh
        if let Some(c) = &self.last {
            self.base = Some((c.elements.clone(), c.bulk.clone()));
        }
        let gamma = self.design.gamma;
        let g: Vec<f64> = s.p.iter().map(|p| p + gamma).collect();
        let f = match self.design.gradient {
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
    fn h1_weights(&self, state: &SurfaceState<'_, 2>, grad: &ShapeGradient) -> Option<H1Weights> {
        let mesh = state.mesh;
        let alpha = mesh
            .elements()
            .iter()
            .map(|&[a, b]| {
                let h2 = (mesh.positions()[b] - mesh.positions()[a]).norm_squared();
                super::alpha_84(grad.g[a], grad.g[b], h2)
            })
            .collect();
        Some(H1Weights { alpha: Weight::Element(alpha), beta: Weight::Constant(1.0) })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::H1Newton
    }

    /// The step control and backtracking pick the step; `τ` only caps it.
    fn flow_defaults(&self, _product: ScalarProduct) -> FlowDefaults {
        FlowDefaults { tau: Some(super::DEFAULT_TAU), ..FlowDefaults::default() }
    }
}
