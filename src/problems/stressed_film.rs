//! The epitaxially stressed film (paper §1.3, §2.2.3, §4.4.2): the `H^{-1}` gradient
//! flow of `J = ∫_Ω |∇y|² + γ|Γ|` on the film's free surface and voids, i.e.
//! `V = Δ_Γ(γκ + |∇y|²)` along the outward normal `ν` of `Ω`.
//!
//! Signs: the curve mesh has the gas as its interior (see [`crate::film`]), so its
//! normal is `n = −ν`, its curvature `κ_Γ = −κ` and its velocity `V_Γ = −V`; along `n`,
//! `G_Γ = γκ_Γ − |∇y|²` (`g = γ`, `f = −|∇y|²`). Since `∂_ν y = 0` on `Γ`,
//! `|∇y|² = (∂_s y)²`, and `∂_s y` is recovered from the P1 trace of `y` on `Γ`
//! ([`tangential_derivative`], second order); the gradients of the triangles at `Γ`
//! are only first-order accurate there, and the exact gradient of the discrete
//! energy (with the bulk vertices held) carries an `O(1)` mesh-distortion bias that
//! shifts the growth rate of the linear instability (measured; not used). With `g`
//! constant the field is constant and the flow is plain surface diffusion of the
//! periodic curve (no bulk mesh is built).
//!
//! Optionally (an addition, `problem.bending`) `J` gains a bending energy
//! `ε/2 ∫_Γ κ²`, whose gradient `ε(−Δ_Γκ − κ³/2)` gives the groove's tip a radius of
//! about `√(ε/γ)` instead of a segment; `−εΔ_Γκ` is implicit in the step
//! ([`Problem::bending`]), `−εκ³/2` is added to `f`.

use crate::bulk::{BulkError, MeshingOptions};
use crate::fem::{tangential_derivative, Matrices, Pattern};
use crate::film::{solve_stress, FilmCell, FilmMesh, StressField};
use crate::flow::{curvature_and_normals, OwnField, Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState};
use crate::geometry::{resolve_intersections, CurveMesh, Mesh, Point};
use std::sync::{Arc, Mutex};

/// The stressed film in its cell.
pub struct StressedFilm {
    pub cell: FilmCell,
    /// Surface tension `γ > 0`.
    pub gamma: f64,
    pub meshing: MeshingOptions,
    /// Topology changes on: crossing candidates are reconnected (voids pinch off).
    pub merge: bool,
    /// Loops below this area are dropped when curves are reconnected.
    pub min_area: f64,
    /// Thickness `δ` of a wetting layer: every vertex of a trial step is put at
    /// `y ≥ δ` (the driver's per-step area correction then offsets it by ~1e-4).
    pub wetting_layer: Option<f64>,
    /// `ε ≥ 0` of an added bending energy `ε/2 ∫_Γ κ²` (an addition): a curvature
    /// regularization of the crack tip; see [`Problem::bending`].
    pub bending: f64,
    cache: Mutex<Option<(Vec<Point<2>>, Vec<[usize; 2]>, Arc<(FilmMesh, StressField)>)>>,
}

impl std::fmt::Debug for StressedFilm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StressedFilm").field("cell", &self.cell).field("gamma", &self.gamma).finish_non_exhaustive()
    }
}

impl Clone for StressedFilm {
    /// A copy with an empty cache.
    fn clone(&self) -> Self {
        StressedFilm::new(self.cell, self.gamma, self.meshing, self.merge, self.min_area)
            .with_wetting_layer(self.wetting_layer)
            .with_bending(self.bending)
    }
}

impl PartialEq for StressedFilm {
    fn eq(&self, o: &Self) -> bool {
        self.cell == o.cell
            && self.gamma == o.gamma
            && self.meshing == o.meshing
            && self.merge == o.merge
            && self.min_area == o.min_area
            && self.wetting_layer == o.wetting_layer
            && self.bending == o.bending
    }
}

impl StressedFilm {
    pub fn new(cell: FilmCell, gamma: f64, meshing: MeshingOptions, merge: bool, min_area: f64) -> Self {
        StressedFilm {
            cell,
            gamma,
            meshing,
            merge,
            min_area,
            wetting_layer: None,
            bending: 0.0,
            cache: Mutex::new(None),
        }
    }

    /// With a wetting layer of thickness `δ` (an obstacle `y ≥ δ` for the surface).
    pub fn with_wetting_layer(mut self, delta: Option<f64>) -> Self {
        self.wetting_layer = delta;
        self
    }

    /// With a bending energy `ε/2 ∫_Γ κ²` added to `J`.
    pub fn with_bending(mut self, eps: f64) -> Self {
        self.bending = eps;
        self
    }

    /// Meshing options for a curve of mean segment length `h`: 28°, triangle areas
    /// at most `h²` (the field's perturbation decays over `1/k` below the surface;
    /// with areas up to `(4h)²` the growth rate of the instability was 1.5 % lower at
    /// 128 vertices).
    pub fn meshing_for(h: f64) -> MeshingOptions {
        MeshingOptions { min_angle_deg: 28.0, max_area: h * h, min_area: 0.0025 * h * h }
    }

    /// The film mesh and field of a curve (cached for the last curve); `None` when
    /// `g` is constant.
    pub fn solve(&self, curve: &CurveMesh) -> Result<Option<Arc<(FilmMesh, StressField)>>, BulkError> {
        if self.cell.boundary.is_constant() {
            return Ok(None);
        }
        let mut cache = self.cache.lock().expect("cache");
        if let Some((p, e, s)) = cache.as_ref() {
            if p == curve.positions() && e == curve.elements() {
                return Ok(Some(s.clone()));
            }
        }
        let mesh = FilmMesh::build(&self.cell, curve, &self.meshing)?;
        let field = solve_stress(&mesh, &self.cell)?;
        let s = Arc::new((mesh, field));
        *cache = Some((curve.positions().to_vec(), curve.elements().to_vec(), s.clone()));
        Ok(Some(s))
    }
}

fn curve<const D: usize>(mesh: &Mesh<D>) -> Result<&CurveMesh, ProblemError> {
    (mesh as &dyn std::any::Any)
        .downcast_ref::<CurveMesh>()
        .ok_or_else(|| ProblemError("the stressed film needs a curve (2D)".into()))
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

impl<const D: usize> Problem<D> for StressedFilm {
    fn name(&self) -> &'static str {
        "stressed_film"
    }

    /// A candidate whose curves cross is evaluated as the curve it becomes (the mesh
    /// manager reconnects it after the step) when topology changes are on; `+∞` if it
    /// crosses otherwise or leaves the cell (then the step is shortened).
    fn energy(&self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        let mut c = curve(mesh)?;
        let resolved;
        if self.merge {
            match resolve_intersections(c, self.min_area, false) {
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
        let bending = if self.bending > 0.0 { self.bending * 0.5 * curvature_squared(c) } else { 0.0 };
        match self.solve(c) {
            Ok(s) => Ok(s.map_or(0.0, |s| s.1.energy) + self.gamma * c.boundary_measure() + bending),
            Err(BulkError::Inadmissible(_)) => Ok(f64::INFINITY),
            Err(e) => Err(problem_error(e)),
        }
    }

    fn shape_gradient(&self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        let c = curve(state.mesh)?;
        let n = c.num_vertices();
        // ∂_ν y = 0 on Γ: |∇y|² = (∂_s y)², recovered from the trace of y on Γ. The
        // trace jumps by bL across the walls (g = a + bx + cy there), w = y − bx does
        // not: ∂_s y = ∂_s w + b t_x.
        let f = match self.solve(c).map_err(problem_error)? {
            None => vec![0.0; n],
            Some(s) => {
                let (mesh, field) = (&s.0, &s.1);
                let b = self.cell.boundary.b;
                let w: Vec<f64> = (0..n).map(|i| field.y[i] - b * mesh.points[i].x).collect();
                let dw = tangential_derivative(c, &w);
                let t = unit_tangents(c);
                dw.iter().zip(&t).map(|(d, t)| -(d + b * t.x).powi(2)).collect()
            }
        };
        let mut f = f;
        if self.bending > 0.0 {
            // ε(−Δ_Γκ − κ³/2): the first term is implicit in the step (Problem::bending)
            f.iter_mut().zip(state.curvature).for_each(|(fi, k)| *fi -= 0.5 * self.bending * k.powi(3));
        }
        Ok(ShapeGradient { g: vec![self.gamma; n], f, aux: Vec::new() })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::HMinus1
    }

    /// The elastic energy density `|∇y|²` on `Γ` (`f` without the bending term).
    fn own_field(&self, state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<OwnField> {
        let e = self.bending;
        let values = grad.f.iter().zip(state.curvature).map(|(f, k)| -(f + 0.5 * e * k.powi(3))).collect();
        Some(OwnField { name: "_ELASTIC_ENERGY_DENSITY", values })
    }

    /// The wetting layer as an obstacle: vertices of the trial step below `y = δ`
    /// are put on it.
    fn constrain(&self, candidate: Mesh<D>) -> Mesh<D> {
        let Some(delta) = self.wetting_layer else { return candidate };
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
        self.bending
    }
}
