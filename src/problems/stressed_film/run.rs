//! A run of the stressed film: the film mesh and field of the last curve, owned by
//! the flow that runs it (energy and shape gradient of one state share one solve).

use super::{film_mesh, solve_stress, StressField, StressedFilm};
use crate::bulk::{BulkError, DomainMesh};
use crate::fem::{tangential_derivative, Matrices, Pattern};
use crate::flow::{
    curvature_and_normals, FlowDefaults, OwnField, Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState,
};
use crate::geometry::{resolve_intersections, CurveMesh, Point};
use std::sync::Arc;

/// The last solve: its curve, film mesh and field.
#[derive(Debug, Clone)]
struct Solved {
    positions: Vec<Point<2>>,
    elements: Vec<[usize; 2]>,
    field: Arc<(DomainMesh, StressField)>,
}

/// The stressed film as the flow runs it: the problem and its per-run state.
#[derive(Debug, Clone)]
pub struct FilmRun {
    pub film: StressedFilm,
    last: Option<Solved>,
}

impl FilmRun {
    pub fn new(film: StressedFilm) -> Self {
        FilmRun { film, last: None }
    }

    /// The film mesh and field of a curve (kept for the last curve); `None` when
    /// `g` is constant.
    pub fn solve(&mut self, curve: &CurveMesh) -> Result<Option<Arc<(DomainMesh, StressField)>>, BulkError> {
        let film = &self.film;
        if film.cell.boundary.is_constant() {
            return Ok(None);
        }
        if let Some(s) = &self.last {
            if s.positions == curve.positions() && s.elements == curve.elements() {
                return Ok(Some(s.field.clone()));
            }
        }
        let mesh = film_mesh(&film.cell, curve, &film.meshing)?;
        let field = solve_stress(&mesh, &film.cell)?;
        let field = Arc::new((mesh, field));
        self.last = Some(Solved {
            positions: curve.positions().to_vec(),
            elements: curve.elements().to_vec(),
            field: field.clone(),
        });
        Ok(Some(field))
    }
}

/// Unit tangents at the vertices: the normalized sum of the adjacent unit segment
/// directions.
fn unit_tangents(c: &CurveMesh) -> Vec<Point<2>> {
    let mut t = vec![Point::<2>::zeros(); c.num_vertices()];
    for (e, &[a, b]) in c.elements().iter().enumerate() {
        let [p, q] = c.element_points(e);
        let d = (q - p).normalize();
        t[a] += d;
        t[b] += d;
    }
    t.iter().map(|v| v.normalize()).collect()
}

/// `∫_Γ κ² ≈ Σ_i m̂_i κ_i²` with the flow's discrete curvature
/// `κ_i = N⃗_i·(A X)_i / |N⃗_i|²` and `m̂_i = |N⃗_i|² / m_i`.
fn curvature_squared(c: &CurveMesh) -> f64 {
    let pattern = Pattern::new(c.num_vertices(), c.elements());
    let m = Matrices::assemble(c, &pattern);
    let ax = m.stiffness_times_positions(c, &pattern);
    let (kappa, _) = curvature_and_normals(&m, &ax);
    kappa.iter().zip(&m.scalar_mass).map(|(k, mh)| mh * k * k).sum()
}

fn problem_error(e: BulkError) -> ProblemError {
    ProblemError(format!("stressed film: {e}"))
}

/// The film lives in the plane: it is a problem on curves only.
impl Problem<2> for FilmRun {
    fn name(&self) -> &'static str {
        "stressed_film"
    }

    /// A candidate whose curves cross is evaluated as the curve it becomes (the mesh
    /// manager reconnects it after the step) when topology changes are on; `+∞` if it
    /// crosses otherwise or leaves the cell (then the step is shortened).
    fn energy(&mut self, mesh: &CurveMesh) -> Result<f64, ProblemError> {
        let mut c = mesh;
        let resolved;
        if self.film.merge {
            match resolve_intersections(c, self.film.min_area, false) {
                Ok(Some(m)) => {
                    resolved = m;
                    c = &resolved;
                }
                Ok(None) => {}
                Err(_) => return Ok(f64::INFINITY),
            }
        } else if !c.crossings().is_empty() {
            return Ok(f64::INFINITY);
        }
        let bending = if self.film.bending > 0.0 { self.film.bending * 0.5 * curvature_squared(c) } else { 0.0 };
        match self.solve(c) {
            Ok(s) => Ok(s.map_or(0.0, |s| s.1.energy) + self.film.gamma * c.boundary_measure() + bending),
            Err(BulkError::Inadmissible(_)) => Ok(f64::INFINITY),
            Err(e) => Err(problem_error(e)),
        }
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, 2>) -> Result<ShapeGradient, ProblemError> {
        let c = state.mesh;
        let n = c.num_vertices();
        // ∂_ν y = 0 on Γ: |∇y|² = (∂_s y)², recovered from the trace of y on Γ. The
        // trace jumps by bL across the walls (g = a + bx + cy there), w = y − bx does
        // not: ∂_s y = ∂_s w + b t_x.
        let f = match self.solve(c).map_err(problem_error)? {
            None => vec![0.0; n],
            Some(s) => {
                let (mesh, field) = (&s.0, &s.1);
                let b = self.film.cell.boundary.b;
                let w: Vec<f64> = (0..n).map(|i| field.y[i] - b * mesh.points[i].x).collect();
                let dw = tangential_derivative(c, &w);
                let t = unit_tangents(c);
                dw.iter().zip(&t).map(|(d, t)| -(d + b * t.x).powi(2)).collect()
            }
        };
        let mut f = f;
        if self.film.bending > 0.0 {
            // ε(−Δ_Γκ − κ³/2): the first term is implicit in the step (Problem::bending)
            f.iter_mut().zip(state.curvature).for_each(|(fi, k)| *fi -= 0.5 * self.film.bending * k.powi(3));
        }
        Ok(ShapeGradient { g: vec![self.film.gamma; n], f, aux: Vec::new() })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::HMinus1
    }

    fn flow_defaults(&self, _product: ScalarProduct) -> FlowDefaults {
        FlowDefaults {
            tau: Some(super::DEFAULT_TAU),
            tau_min: Some(super::DEFAULT_TAU_MIN),
            conservation: Some(super::DEFAULT_CONSERVATION),
            tolerance: None,
        }
    }

    /// The elastic energy density `|∇y|²` on `Γ` (`f` without the bending term).
    fn own_field(&self, state: &SurfaceState<'_, 2>, grad: &ShapeGradient) -> Option<OwnField> {
        let e = self.film.bending;
        let values = grad.f.iter().zip(state.curvature).map(|(f, k)| -(f + 0.5 * e * k.powi(3))).collect();
        Some(OwnField { name: "_ELASTIC_ENERGY_DENSITY", values })
    }

    /// The wetting layer as an obstacle: vertices of the trial step below `y = δ`
    /// are put on it.
    fn constrain(&self, candidate: CurveMesh) -> CurveMesh {
        let Some(delta) = self.film.wetting_layer else { return candidate };
        if candidate.positions().iter().all(|p| p[1] >= delta) {
            return candidate;
        }
        let positions = candidate
            .positions()
            .iter()
            .map(|p| {
                let mut q = *p;
                q[1] = q[1].max(delta);
                q
            })
            .collect();
        candidate.with_positions(positions)
    }

    fn is_physical(&self) -> bool {
        true
    }

    fn bending(&self) -> f64 {
        self.film.bending
    }
}
