//! Region-based segmentation (Chan–Vese, piecewise constant) in the framework of
//! the paper: with `I` the normalized, smoothed image and objects `Ω_k` (the
//! components of `Γ`, holes belonging to the curve around them),
//!
//! `J = μ|Γ| + λ_in Σ_k ∫_{Ω_k} (I − c_k)² + λ_out ∫_{D∖Ω} (I − c_out)²`,
//!
//! `c_k`, `c_out` the current means. With one constant per object (the default,
//! `per_object`) a dim object is fitted by its own level rather than by the mean of
//! all objects; with `per_object = false` this is the two-phase model with one
//! `c_in`. Since the means minimize `J` for a fixed shape, the shape gradient is
//!
//! `G = μκ + λ_in (I − c_k)² − λ_out (I − c_out)²` on the boundary of `Ω_k`
//!
//! (`g = μ`, `f` the rest). Every volume integral is a boundary integral,
//! `∫_Ω F = ∫_Γ Φ_F ν₁` with `Φ_F` the exact antiderivative in `x₁` of the cubic
//! spline of `F` ([`EdgeField`]), as for the domain term of geodesic active
//! contours; `(I − c)²` is integrated as `Q − 2cI + c²` with `Q` the spline of the
//! squared samples, and `G` uses the same `Q` and `I`, so that it is the exact
//! shape derivative of the discrete `J`. Optionally the geodesic functional of
//! [`Segmentation`] is added (`problem.model` `both`).

use super::Segmentation;
use crate::fem::Weight;
use crate::flow::{
    Confinement, FlowDefaults, H1Weights, OwnField, Problem, ProblemError, ScalarProduct, ShapeGradient, StepLimits,
    SurfaceState,
};
use crate::geometry::{Mesh, PatchSearch, Point};
use crate::imaging::EdgeField;
use contact::{keep_apart, objects_cross};
use moments::{accumulate_moments, Moments};
pub use run::ChanVeseRun;
use run::Objects;
use std::sync::Arc;
use surface_contact::hold_contacts;
pub use territory::Territories;

mod contact;
mod moments;
mod run;
mod surface_contact;
mod territory;

/// Default `flow.tau`, in pixels: the data term's speed is at most
/// `max(λ_in, λ_out)` (normalized intensities), so a step moves the contour at most
/// about this many pixels; the step control and backtracking shorten it where
/// needed.
pub const TAU_PIXELS: f64 = 8.0;

/// Default `flow.tolerance`: the relative change of `J` per step, twice in a
/// row, at which a run has converged. Measured on the images of
/// docs/segmentation-real-images.md: at 1e-6 the runs take up to twice the steps
/// for changes of Dice within ±0.0007.
pub const TOLERANCE: f64 = 1e-5;

/// The Chan–Vese functional of one image.
#[derive(Debug, Clone, PartialEq)]
pub struct ChanVese {
    /// The spline of the normalized image `I` (values in `[0, 1]`).
    pub intensity: Arc<EdgeField>,
    /// The spline of the squared samples `Q`.
    pub squares: Arc<EdgeField>,
    /// Weight `μ ≥ 0` of the length (area) of `Γ`.
    pub mu: f64,
    pub lambda_in: f64,
    pub lambda_out: f64,
    /// One mean per object (true) or one for all objects.
    pub per_object: bool,
    /// `(∫_D I, ∫_D Q, |D|)` over the image box.
    pub totals: [f64; 3],
    /// The geodesic active contour functional added to `J` (model `both`).
    pub geodesic: Option<Segmentation>,
    /// Curves of different components may not cross (a trial step where two
    /// objects would overlap is inadmissible, `J = +∞`): touching objects stay
    /// separate instead of merging.
    pub separate: bool,
    /// With `separate`, for surfaces: the territory of every initial object,
    /// which its vertices do not leave ([`Territories`]).
    pub territories: Option<Territories>,
}

impl ChanVese {
    /// The problem for the normalized, smoothed image with sample values `values`
    /// on a grid of `dims` (`dimension` 2 or 3).
    pub fn new(dimension: usize, dims: [usize; 3], values: &[f64], mu: f64, lambdas: (f64, f64)) -> ChanVese {
        let l = dims.iter().copied().max().unwrap_or(1) as f64;
        let cell = l.powi(-(dimension as i32));
        let squares: Vec<f64> = values.iter().map(|v| v * v).collect();
        let totals =
            [values.iter().sum::<f64>() * cell, squares.iter().sum::<f64>() * cell, values.len() as f64 * cell];
        ChanVese {
            intensity: Arc::new(EdgeField::from_coefficients(dimension, dims, values.to_vec())),
            squares: Arc::new(EdgeField::from_coefficients(dimension, dims, squares)),
            mu,
            lambda_in: lambdas.0,
            lambda_out: lambdas.1,
            per_object: true,
            totals,
            geodesic: None,
            separate: false,
            territories: None,
        }
    }

    fn check_dimension<const D: usize>(&self) -> Result<(), ProblemError> {
        super::check_image_dimension::<D>(self.intensity.dimension())
    }

    /// The image's box in the unit-square coordinates of the flow.
    fn image_box<const D: usize>(&self) -> Confinement<D> {
        let (l, dims) = (self.intensity.scale(), self.intensity.dims());
        Confinement { lo: Point::<D>::zeros(), hi: Point::<D>::from_fn(|a, _| dims[a] as f64 / l) }
    }

    /// The object of every component of `mesh` (holes and cavities belong to the
    /// component around them, [`Mesh::objects`]) and the moments of every object;
    /// `per_object = false` puts everything in object 0. Returns the component of
    /// every vertex, the object of every component and the moments ([`Objects`]).
    fn objects<const D: usize>(&self, mesh: &Mesh<D>) -> Objects {
        let objects = mesh.objects();
        let nc = objects.owner.len();
        let mut moments = vec![[0.0; 3]; if self.per_object { nc.max(1) } else { 1 }];
        let object_of: Vec<usize> = if self.per_object { objects.owner } else { vec![0; nc] };
        let element_object: Vec<usize> =
            mesh.elements().iter().map(|el| object_of[objects.vertex_component[el[0]]]).collect();
        accumulate_moments(self, mesh, &element_object, &mut moments);
        Objects { vertex_component: objects.vertex_component, object_of, moments }
    }

    /// The fitted means `c_k` of the objects and `c_out`, and the region part of `J`.
    fn means(&self, moments: &[Moments]) -> (Vec<f64>, f64, f64) {
        // an object under a hundredth of a sample carries no mean of its own
        let tiny = 0.01 * self.totals[2] / (self.intensity.dims().iter().product::<usize>() as f64);
        let mut out = self.totals;
        let mut region = 0.0;
        let mut inside = Vec::with_capacity(moments.len());
        for m in moments {
            for k in 0..3 {
                out[k] -= m[k];
            }
        }
        let c_out = if out[2] > tiny { out[0] / out[2] } else { 0.0 };
        if out[2] > tiny {
            region += self.lambda_out * (out[1] - out[0] * out[0] / out[2]).max(0.0);
        }
        for m in moments {
            if m[2] > tiny {
                inside.push(m[0] / m[2]);
                region += self.lambda_in * (m[1] - m[0] * m[0] / m[2]).max(0.0);
            } else {
                inside.push(c_out);
            }
        }
        (inside, c_out, region)
    }

    /// The fitted mean of every component of `mesh` and the mean outside.
    pub fn component_means<const D: usize>(&self, mesh: &Mesh<D>) -> (Vec<f64>, f64) {
        let objects = self.objects(mesh);
        let (c, c_out, _) = self.means(&objects.moments);
        (objects.object_of.iter().map(|&o| c[o]).collect(), c_out)
    }
}

/// The least distance kept between the surfaces of two objects, in samples: the
/// neck split's parts start 0.8 samples apart, the initial shape's objects a
/// sample.
const CLEARANCE: f64 = 0.25;

impl<const D: usize> Problem<D> for ChanVeseRun {
    fn name(&self) -> &'static str {
        "segmentation"
    }

    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        self.cv.check_dimension::<D>()?;
        if self.cv.separate && D == 2 && objects_cross(mesh) {
            // objects that touch stay the objects they are
            return Ok(f64::INFINITY);
        }
        let objects = self.objects(mesh);
        let (_, _, region) = self.cv.means(&objects.moments);
        let mut j = self.cv.mu * mesh.boundary_measure() + region;
        if let Some(g) = &mut self.cv.geodesic {
            j += Problem::<D>::energy(g, mesh)?;
        }
        Ok(j)
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        self.cv.check_dimension::<D>()?;
        let mesh = state.mesh;
        let objects = self.objects(mesh);
        let (vertex_component, object_of) = (&objects.vertex_component, &objects.object_of);
        let (c, c_out, _) = self.cv.means(&objects.moments);
        let n = mesh.num_vertices();
        let (mut g, mut f, mut aux) = (vec![self.cv.mu; n], Vec::with_capacity(n), Vec::with_capacity(n));
        for (v, x) in mesh.positions().iter().enumerate() {
            let ck = c[object_of[vertex_component[v]]];
            let (si, sq) = (self.cv.intensity.sample(x), self.cv.squares.sample(x));
            let fit = |c: f64| sq.h - 2.0 * c * si.h + c * c;
            f.push(self.cv.lambda_in * fit(ck) - self.cv.lambda_out * fit(c_out));
            // ∂_ν f for the Newton-type weight
            let slope = sq.grad * (self.cv.lambda_in - self.cv.lambda_out)
                - si.grad * (2.0 * (self.cv.lambda_in * ck - self.cv.lambda_out * c_out));
            let dn = slope.dot(&state.normals[v]);
            aux.push(dn);
        }
        if let Some(geo) = &mut self.cv.geodesic {
            let extra = Problem::<D>::shape_gradient(geo, state)?;
            for v in 0..n {
                g[v] += extra.g[v];
                f[v] += extra.f[v];
            }
        }
        Ok(ShapeGradient { g, f, aux })
    }

    /// `α = μ` and `β = max(∂_ν f, ε)` with `ε = 0.01 (λ_in + λ_out) L` (about a tenth
    /// of the data term's slope at an edge of contrast 1/2 over two pixels) (a Newton-type weight as for geodesic contours, without the
    /// nonlocal change of the means).
    fn h1_weights(&self, state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<H1Weights> {
        let n = state.mesh.num_vertices();
        if self.cv.geodesic.is_some() || grad.aux.len() != n {
            return None;
        }
        let l = self.cv.intensity.scale();
        let floor = 0.01 * (self.cv.lambda_in + self.cv.lambda_out) * l;
        let beta = grad.aux.iter().map(|&b| b.max(floor)).collect();
        Some(H1Weights { alpha: Weight::Constant(self.cv.mu.max(1e-12)), beta: Weight::Vertex(beta) })
    }

    /// With the geodesic term (model `both`) its edge indicator `H = g − μ`; otherwise
    /// the normalized image `I` the means are taken of.
    fn own_field(&self, state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<OwnField> {
        Some(match &self.cv.geodesic {
            Some(_) => OwnField { name: "_EDGE_INDICATOR", values: grad.g.iter().map(|g| g - self.cv.mu).collect() },
            None => OwnField {
                name: "_INTENSITY",
                values: state.mesh.positions().iter().map(|x| self.cv.intensity.sample(x).h).collect(),
            },
        })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::L2
    }

    /// `τ` of [`TAU_PIXELS`] pixels (in the unit square's length).
    fn flow_defaults(&self, _product: ScalarProduct) -> FlowDefaults {
        FlowDefaults {
            tau: Some(TAU_PIXELS / self.cv.intensity.scale()),
            tolerance: Some(TOLERANCE),
            ..FlowDefaults::default()
        }
    }

    /// With `separate`: where two objects would cross, the vertices of the
    /// crossing segments go part of their step, or none ([`keep_apart`]: a contact
    /// holds the contours where they meet, and the rest of the step goes on).
    /// Surfaces: the vertices that would enter another object's territory keep
    /// theirs ([`Territories::hold`]), and those of triangles that would meet
    /// triangles they did not meet before too ([`hold_contacts`]: objects that
    /// meet stop where they meet, whatever their territories).
    fn constrain_step(&self, current: &Mesh<D>, candidate: Mesh<D>, search: &mut PatchSearch) -> Mesh<D> {
        let mut candidate = Problem::<D>::constrain(self, candidate);
        if !self.cv.separate || current.num_vertices() != candidate.num_vertices() {
            return candidate;
        }
        if D == 3 {
            let candidate = match &self.cv.territories {
                Some(t) => t.hold(&self.cv.intensity, current, candidate),
                None => candidate,
            };
            let surfaces = (current as &dyn std::any::Any).downcast_ref::<Mesh<3>>();
            let mut candidate = candidate;
            if let (Some(current), Some(c)) = (surfaces, (&mut candidate as &mut dyn std::any::Any).downcast_mut()) {
                hold_contacts(current, c, CLEARANCE / self.cv.intensity.scale(), search);
            }
            return candidate;
        }
        let curves = (current as &dyn std::any::Any).downcast_ref::<Mesh<2>>();
        if let (Some(current), Some(candidate)) = (curves, (&mut candidate as &mut dyn std::any::Any).downcast_mut()) {
            keep_apart(current, candidate);
        }
        candidate
    }

    /// The objects stay in the image box `D` (outside it there is no data: the
    /// spline is continued by the border samples, and an object cut by the border
    /// would grow out of it). The territories of surfaces' objects are kept after
    /// the solve ([`Problem::constrain_step`]): kept in the solve as well, they
    /// made the nuclei volumes slower and their energies higher.
    fn step_limits(&self, _mesh: &Mesh<D>) -> Option<Box<dyn StepLimits<D>>> {
        Some(Box::new(self.cv.image_box::<D>()))
    }

    /// What the step's solve left outside the box ([`Problem::step_limits`])
    /// moved back onto it.
    fn constrain(&self, candidate: Mesh<D>) -> Mesh<D> {
        self.cv.image_box().clamp(candidate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flow::shape_derivative;
    use crate::geometry::{circle, union};

    /// A bright disc (value 1, radius 12 px) in a dark 64² image (value 0.2).
    fn disc_problem() -> ChanVese {
        let n = 64;
        let values: Vec<f64> = (0..n * n)
            .map(|p| {
                let (x, y) = ((p % n) as f64 + 0.5, (p / n) as f64 + 0.5);
                if (x - 32.0).hypot(y - 32.0) < 12.0 {
                    1.0
                } else {
                    0.2
                }
            })
            .collect();
        ChanVese::new(2, [n, n, 1], &values, 1e-3, (1.0, 1.0))
    }

    #[test]
    fn means_of_a_disc() {
        let mut p = disc_problem().start();
        let m = circle([0.5, 0.5], 11.0 / 64.0, 200).unwrap();
        let (c, c_out) = p.problem().component_means(&m);
        assert!((c[0] - 1.0).abs() < 0.01, "{c:?}");
        assert!((c_out - 0.2).abs() < 0.02, "{c_out}");
        // the energy is least near the true radius
        let mut j = |r: f64| Problem::<2>::energy(&mut p, &circle([0.5, 0.5], r / 64.0, 200).unwrap()).unwrap();
        assert!(j(12.0) < j(10.0) && j(12.0) < j(14.0), "{} {} {}", j(10.0), j(12.0), j(14.0));
    }

    /// The shape gradient against finite differences of `J`, with two objects.
    #[test]
    fn shape_gradient_matches_finite_differences() {
        let mut p = disc_problem().start();
        let a = circle([0.45, 0.5], 9.0 / 64.0, 120).unwrap();
        let b = circle([0.8, 0.2], 5.0 / 64.0, 60).unwrap();
        let m = union(&[a, b]).unwrap();
        let field: Vec<Point<2>> =
            m.positions().iter().map(|x| Point::<2>::new((x[1] * 9.0).sin(), x[0] - 0.3)).collect();
        let d = shape_derivative(&mut p, &m, &field).unwrap();
        let h = 1e-6;
        let moved = |s: f64| m.with_positions(m.positions().iter().zip(&field).map(|(x, v)| x + v * s).collect());
        let fd = (Problem::<2>::energy(&mut p, &moved(h)).unwrap() - Problem::<2>::energy(&mut p, &moved(-h)).unwrap())
            / (2.0 * h);
        assert!((d - fd).abs() < 0.02 * fd.abs(), "{d} {fd}");
    }
}
