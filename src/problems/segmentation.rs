//! Image segmentation by geodesic active contours (paper §1.1, §2.2.1, §4.2):
//!
//! `J(Ω) = ∫_Γ H + λ ∫_Ω H`, `G = (κ + λ) H + ∂_ν H` (`g = H`, `f = λH + ∂_ν H`),
//!
//! with `H` the edge indicator of the image ([`EdgeField`]). The Newton-type weighted
//! H1 product (paper eq. 81, after Hintermüller–Ring) has `α = H` and
//! `β = (ν·D²H·ν + (2κ + λ) ∂_ν H + λκH)₊ε`, `(x)₊ε = max(x, ε)`.
//!
//! The energy is integrated with two Gauss points per pixel of segment length on
//! curves, and on triangles with the 3-point rule on sub-triangles of about `2s`
//! pixels (`s² = σ² + 2/3` the variance of the blur behind `H`); the domain term
//! uses `∫_Ω H = ∫_Γ Φ ν₁` with the exact antiderivative `Φ` of the spline of `H`
//! in `x₁`.

use crate::fem::Weight;
use crate::flow::{
    FlowDefaults, H1Weights, OwnField, Problem, ProblemError, ScalarProduct, ShapeGradient, SurfaceState,
};
use crate::geometry::{Mesh, Point};
use crate::imaging::{EdgeField, EdgeSample};
use std::sync::Arc;

/// The geodesic active contour functional of one image.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    pub field: Arc<EdgeField>,
    /// Weight `λ ≥ 0` of the region term (balloon force).
    pub lambda: f64,
    /// Lower threshold `ε > 0` of the Newton weight β.
    pub epsilon: f64,
}

/// Default `flow.tau` with the Newton-type H1 product.
pub const NEWTON_TAU: f64 = 10.0;
/// Default `flow.tau` with the L2 (and plain H1) product.
pub const L2_TAU: f64 = 1e-3;

/// Two-point Gauss rule on `[0, 1]`.
const GAUSS2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

impl Segmentation {
    fn check_dimension<const D: usize>(&self) -> Result<(), ProblemError> {
        super::check_image_dimension::<D>(self.field.dimension())
    }

    /// `(∫_e H, ∫_e Φ ν₁)` over element `e`.
    #[inline(always)]
    fn element_integrals<const D: usize>(&self, p: &[Point<D>; D]) -> (f64, f64) {
        let l = self.field.scale();
        let f = &*self.field;
        if D == 2 {
            let e = p[1] - p[0];
            let len = e.norm();
            let m = (len * l).ceil().clamp(1.0, 4096.0) as usize;
            let mut batch = Batch::new(f);
            for s in 0..m {
                for g in GAUSS2 {
                    let x = p[0] + e * ((s as f64 + g) / m as f64);
                    batch.push([x[0], x[1], 0.0]);
                }
            }
            let (sh, sphi, _) = batch.finish();
            let n = (2 * m) as f64;
            (len * sh / n, e[1] * sphi / n)
        } else {
            let (u, v) = (p[1] - p[0], p[2] - p[0]);
            let (u3, v3) = (nalgebra::Vector3::new(u[0], u[1], u[2]), nalgebra::Vector3::new(v[0], v[1], v[2]));
            let area_vec = u3.cross(&v3) * 0.5;
            let hmax = u.norm().max(v.norm()).max((p[2] - p[1]).norm());
            // sub-triangles of about 2s pixels (`s²` = σ² + 2/3, the variance of the
            // blur behind H: the spline of H is smooth on that scale; 3.4 px at the
            // default σ = 1.5)
            let cell = 2.0 * crate::problems::blur_variance(f).sqrt();
            let m = (hmax * l / cell).ceil().clamp(1.0, 256.0) as usize;
            let step = 1.0 / m as f64;
            let mut batch = Batch::new(f);
            let x0 = [p[0][0], p[0][1], p[0][2]];
            let (u, v) = ([u[0], u[1], u[2]], [v[0], v[1], v[2]]);
            // the m² sub-triangles of the barycentric lattice, 3-point rule on each
            for i in 0..m {
                for j in 0..m - i {
                    let (s0, t0) = (i as f64 * step, j as f64 * step);
                    batch.sub_triangle(&x0, &u, &v, (s0, t0), (s0 + step, t0), (s0, t0 + step));
                    if i + j + 1 < m {
                        batch.sub_triangle(&x0, &u, &v, (s0 + step, t0), (s0 + step, t0 + step), (s0, t0 + step));
                    }
                }
            }
            let (sh, sphi, count) = batch.finish();
            let n = count as f64;
            (area_vec.norm() * sh / n, area_vec[0] * sphi / n)
        }
    }
}

/// The quadrature points of an element, evaluated four at a time (their grid
/// coordinates and weights as vectors) and summed in order; plain inlined methods,
/// so that they compile into [`integrals`]' AVX2 version (a closure would be
/// compiled on its own).
struct Batch<'a> {
    field: &'a EdgeField,
    lanes: [[f64; 4]; 3],
    filled: usize,
    sh: f64,
    sphi: f64,
    count: usize,
}

impl<'a> Batch<'a> {
    #[inline(always)]
    fn new(field: &'a EdgeField) -> Self {
        Batch { field, lanes: [[0.0; 4]; 3], filled: 0, sh: 0.0, sphi: 0.0, count: 0 }
    }

    /// Add the point `x` (its third coordinate unused in 2D).
    #[inline(always)]
    fn push(&mut self, x: [f64; 3]) {
        for k in 0..3 {
            self.lanes[k][self.filled] = x[k];
        }
        self.filled += 1;
        self.count += 1;
        if self.filled == 4 {
            let (h, phi) = if self.field.dimension() == 2 {
                self.field.values_and_antiderivatives_2d(self.lanes[0], self.lanes[1])
            } else {
                self.field.values_and_antiderivatives_3d(self.lanes)
            };
            for j in 0..4 {
                self.sh += h[j];
                self.sphi += phi[j];
            }
            self.filled = 0;
        }
    }

    /// The 3-point rule (points at barycentric `(2/3, 1/6, 1/6)` and permutations) on
    /// the sub-triangle with lattice corners `a, b, c` of `x₀ + s u + t v`.
    #[inline(always)]
    fn sub_triangle(&mut self, x0: &[f64; 3], u: &[f64; 3], v: &[f64; 3], a: (f64, f64), b: (f64, f64), c: (f64, f64)) {
        for (wa, wb, wc) in
            [(2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0), (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0), (1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0)]
        {
            let s = wa * a.0 + wb * b.0 + wc * c.0;
            let t = wa * a.1 + wb * b.1 + wc * c.1;
            self.push(std::array::from_fn(|k| x0[k] + u[k] * s + v[k] * t));
        }
    }

    /// `(Σ H, Σ Φ, number of points)`.
    #[inline(always)]
    fn finish(mut self) -> (f64, f64, usize) {
        for j in 0..self.filled {
            let [x, y, z] = [self.lanes[0][j], self.lanes[1][j], self.lanes[2][j]];
            let (h, phi) = if self.field.dimension() == 2 {
                self.field.value_and_antiderivative(&nalgebra::Vector2::new(x, y))
            } else {
                self.field.value_and_antiderivative(&nalgebra::Vector3::new(x, y, z))
            };
            self.sh += h;
            self.sphi += phi;
        }
        (self.sh, self.sphi, self.count)
    }
}

/// `(∫_Γ H, ∫_Γ Φ ν₁)`, element by element; compiled a second time for AVX2 and
/// picked at run time (the quadrature is most of a 2D run; rounding to the grid is
/// a call without SSE4.1), with the same numbers.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn integrals<const D: usize>(s: &Segmentation, mesh: &Mesh<D>) -> (f64, f64) {
    let (mut boundary, mut region) = (0.0, 0.0);
    for e in 0..mesh.num_elements() {
        let (b, r) = s.element_integrals(&mesh.element_points(e));
        boundary += b;
        region += r;
    }
    (boundary, region)
}

/// `H`, `∇H`, `D²H` at every vertex (AVX2 version as for [`integrals`]).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn samples<const D: usize>(field: &EdgeField, x: &[Point<D>]) -> Vec<EdgeSample<D>> {
    // a plain loop: an iterator adapter would be compiled outside this version
    let mut out = Vec::with_capacity(x.len());
    for x in x {
        out.push(field.sample(x));
    }
    out
}

impl<const D: usize> Problem<D> for Segmentation {
    fn name(&self) -> &'static str {
        "segmentation"
    }

    fn energy(&mut self, mesh: &Mesh<D>) -> Result<f64, ProblemError> {
        self.check_dimension::<D>()?;
        let (boundary, region) = integrals(self, mesh);
        Ok(boundary + self.lambda * region)
    }

    fn shape_gradient(&mut self, state: &SurfaceState<'_, D>) -> Result<ShapeGradient, ProblemError> {
        self.check_dimension::<D>()?;
        let n = state.mesh.num_vertices();
        let (mut g, mut f, mut aux) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(2 * n));
        for (s, nu) in samples(&self.field, state.mesh.positions()).iter().zip(state.normals) {
            let dn = s.grad.dot(nu);
            g.push(s.h);
            f.push(self.lambda * s.h + dn);
            aux.extend([dn, nu.dot(&(s.hess * nu))]);
        }
        Ok(ShapeGradient { g, f, aux })
    }

    /// From the samples taken for the gradient: `H = g`, and `aux` holds `∂_ν H` and
    /// `ν·D²H·ν` per vertex.
    fn h1_weights(&self, state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<H1Weights> {
        let n = state.mesh.num_vertices();
        if grad.g.len() != n || grad.aux.len() != 2 * n {
            return None;
        }
        let mut beta = Vec::with_capacity(n);
        for i in 0..n {
            let (h, k, dn) = (grad.g[i], state.curvature[i], grad.aux[2 * i]);
            let b = grad.aux[2 * i + 1] + (2.0 * k + self.lambda) * dn + self.lambda * k * h;
            beta.push(if b > self.epsilon { b } else { self.epsilon });
        }
        Some(H1Weights { alpha: Weight::Vertex(grad.g.clone()), beta: Weight::Vertex(beta) })
    }

    fn default_scalar_product(&self) -> ScalarProduct {
        ScalarProduct::H1Newton
    }

    /// The Newton-type product scales `V` like a Newton step (`τ = 1`); far from
    /// edges β is clipped at ε and `V = −G/ε`, so a larger cap lets the step control
    /// decide.
    fn flow_defaults(&self, product: ScalarProduct) -> FlowDefaults {
        let tau = if product == ScalarProduct::H1Newton { NEWTON_TAU } else { L2_TAU };
        FlowDefaults { tau: Some(tau), ..FlowDefaults::default() }
    }

    /// The edge indicator `H` (`g` of the gradient).
    fn own_field(&self, _state: &SurfaceState<'_, D>, grad: &ShapeGradient) -> Option<OwnField> {
        Some(OwnField { name: "_EDGE_INDICATOR", values: grad.g.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere};

    /// With `H ≡ c`, `J = c|Γ| + λc|Ω|` exactly (up to the polygon).
    #[test]
    fn constant_field_gives_perimeter_and_area() {
        let c = 0.7;
        let f2 = Arc::new(EdgeField::from_coefficients(2, [20, 10, 1], vec![c; 200]));
        let mut seg = Segmentation { field: f2, lambda: 3.0, epsilon: 1e3 };
        let m = circle([0.4, 0.3], 0.2, 64).unwrap();
        let j = Problem::<2>::energy(&mut seg, &m).unwrap();
        let want = c * m.boundary_measure() + 3.0 * c * m.enclosed_measure();
        assert!((j - want).abs() < 1e-12 * want, "{j} {want}");
        let f3 = Arc::new(EdgeField::from_coefficients(3, [8, 8, 8], vec![c; 512]));
        let mut seg = Segmentation { field: f3, lambda: 3.0, epsilon: 1e3 };
        let s = icosphere([0.5, 0.5, 0.5], 0.3, 2).unwrap();
        let j = Problem::<3>::energy(&mut seg, &s).unwrap();
        let want = c * s.boundary_measure() + 3.0 * c * s.enclosed_measure();
        assert!((j - want).abs() < 1e-12 * want, "{j} {want}");
    }

    /// `J` of a circle of radius `r` in a field `H(x) = a + b x₁` (linear along x):
    /// compare the region term with `∫_Ω H` computed in closed form.
    #[test]
    fn linear_field_region_integral() {
        let n = 32;
        let coef: Vec<f64> = (0..n * n).map(|i| 1.0 + 0.05 * (i % n) as f64).collect();
        let field = Arc::new(EdgeField::from_coefficients(2, [n, n, 1], coef));
        let mut seg = Segmentation { field: field.clone(), lambda: 1.0, epsilon: 1.0 };
        let m = circle([0.5, 0.5], 0.25, 2000).unwrap();
        // H(x, y) = 1 + 0.05 (x n - 1/2) exactly (B-splines reproduce linears)
        let h = |x: f64| 1.0 + 0.05 * (x * n as f64 - 0.5);
        let area = m.enclosed_measure();
        let region = Problem::<2>::energy(&mut seg, &m).unwrap() - {
            // boundary term by the same quadrature with λ = 0
            let mut s0 = Segmentation { lambda: 0.0, ..seg.clone() };
            Problem::<2>::energy(&mut s0, &m).unwrap()
        };
        assert!((region - area * h(0.5)).abs() < 1e-6, "{region} {}", area * h(0.5));
    }
}
