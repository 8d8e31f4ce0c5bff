//! The region integrals of the Chan–Vese functional: per object `(∫ I, ∫ Q, |Ω|)`
//! as boundary integrals of the antiderivatives of the image splines, by Gauss
//! quadrature on every element, four points at a time across elements.

use super::ChanVese;
use crate::geometry::{Mesh, Point};
use crate::imaging::EdgeField;

/// `(∫ I, ∫ Q, |Ω|)` of one object.
pub(super) type Moments = [f64; 3];

/// Two-point Gauss rule on `[0, 1]`.
const GAUSS2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

/// The quadrature points of the element with corners `p`, with their weights,
/// into `lanes` for `object`: two Gauss points per pixel of length on segments,
/// the 3-point rule on sub-triangles of about two pixels on triangles. A point's
/// weight is its share of `ν₁` times the element's measure (equal within an
/// element). Plain inlined functions, no closures: they compile into
/// [`accumulate_moments`]' AVX2 version (a closure would be compiled on its own).
#[inline(always)]
fn element_points<const D: usize>(l: f64, p: &[Point<D>; D], lanes: &mut Lanes<'_>, object: usize) {
    if D == 2 {
        let e = p[1] - p[0];
        let m = (e.norm() * l).ceil().clamp(1.0, 4096.0) as usize;
        let w = e[1] / (2 * m) as f64;
        for s in 0..m {
            for g in GAUSS2 {
                let x = p[0] + e * ((s as f64 + g) / m as f64);
                lanes.push([x[0], x[1], 0.0], w, object);
            }
        }
    } else {
        let (u, v) = (p[1] - p[0], p[2] - p[0]);
        let nu1 = 0.5 * (u[1] * v[2] - u[2] * v[1]);
        let hmax = u.norm().max(v.norm()).max((p[2] - p[1]).norm());
        let m = (hmax * l / 2.0).ceil().clamp(1.0, 256.0) as usize;
        let (step, w) = (1.0 / m as f64, nu1 / (3 * m * m) as f64);
        let (x0, u, v) = ([p[0][0], p[0][1], p[0][2]], [u[0], u[1], u[2]], [v[0], v[1], v[2]]);
        for i in 0..m {
            for j in 0..m - i {
                let (s0, t0) = (i as f64 * step, j as f64 * step);
                let corners = [(s0, t0), (s0 + step, t0), (s0, t0 + step)];
                sub_triangle(&x0, &u, &v, corners, w, lanes, object);
                if i + j + 1 < m {
                    let corners = [(s0 + step, t0), (s0 + step, t0 + step), (s0, t0 + step)];
                    sub_triangle(&x0, &u, &v, corners, w, lanes, object);
                }
            }
        }
    }
}

/// The 3-point rule (barycentric `(2/3, 1/6, 1/6)` and permutations) on the
/// sub-triangle with lattice corners `c` of `x₀ + s u + t v`.
#[inline(always)]
fn sub_triangle(
    x0: &[f64; 3],
    u: &[f64; 3],
    v: &[f64; 3],
    c: [(f64, f64); 3],
    w: f64,
    lanes: &mut Lanes<'_>,
    object: usize,
) {
    const THIRD: [[f64; 3]; 3] =
        [[2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0], [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0]];
    for b in THIRD {
        let s = b[0] * c[0].0 + b[1] * c[1].0 + b[2] * c[2].0;
        let t = b[0] * c[0].1 + b[1] * c[1].1 + b[2] * c[2].1;
        let x = [x0[0] + u[0] * s + v[0] * t, x0[1] + u[1] * s + v[1] * t, x0[2] + u[2] * s + v[2] * t];
        lanes.push(x, w, object);
    }
}

/// The moments of the elements of `mesh` added to their objects'; compiled a
/// second time for AVX2 and picked at run time, as the geodesic quadrature.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn accumulate_moments<const D: usize>(
    cv: &ChanVese,
    mesh: &Mesh<D>,
    element_object: &[usize],
    moments: &mut [Moments],
) {
    let l = cv.intensity.scale();
    let mut lanes = Lanes::new(cv, moments);
    for (e, &o) in element_object.iter().enumerate() {
        element_points(l, &mesh.element_points(e), &mut lanes, o);
    }
    lanes.finish();
}

/// Quadrature points of any elements, evaluated four at a time on both splines
/// ([`EdgeField::antiderivatives`]: one set of weights for both), each added with
/// its weight to its object's `(∫ I, ∫ Q, |Ω|)` as `(Φ_I, Φ_Q, x₁)`.
struct Lanes<'a> {
    cv: &'a ChanVese,
    moments: &'a mut [Moments],
    x: [[f64; 4]; 3],
    w: [f64; 4],
    object: [usize; 4],
    filled: usize,
}

impl<'a> Lanes<'a> {
    #[inline(always)]
    fn new(cv: &'a ChanVese, moments: &'a mut [Moments]) -> Self {
        Lanes { cv, moments, x: [[0.0; 4]; 3], w: [0.0; 4], object: [0; 4], filled: 0 }
    }

    #[inline(always)]
    fn push(&mut self, x: [f64; 3], w: f64, object: usize) {
        let j = self.filled;
        for (lane, v) in self.x.iter_mut().zip(x) {
            lane[j] = v;
        }
        (self.w[j], self.object[j]) = (w, object);
        self.filled += 1;
        if self.filled == 4 {
            self.add();
        }
    }

    /// The filled lanes evaluated and added to their objects.
    #[inline(always)]
    fn add(&mut self) {
        let [pi, pq] = EdgeField::antiderivatives([&*self.cv.intensity, &*self.cv.squares], self.x);
        for j in 0..self.filled {
            let m = &mut self.moments[self.object[j]];
            m[0] += self.w[j] * pi[j];
            m[1] += self.w[j] * pq[j];
            m[2] += self.w[j] * self.x[0][j];
        }
        self.filled = 0;
    }

    /// The last, partly filled lanes (the rest repeat the first point).
    #[inline(always)]
    fn finish(mut self) {
        if self.filled > 0 {
            for j in self.filled..4 {
                for k in 0..3 {
                    self.x[k][j] = self.x[k][0];
                }
            }
            self.add();
        }
    }
}
