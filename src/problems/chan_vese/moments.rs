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

/// The quadrature points of element `e` (corners `p`) with their weights, to
/// `push`: two Gauss points per pixel of length on segments, the 3-point rule on
/// sub-triangles of about two pixels on triangles. A point's weight is its share
/// of `ν₁` times the element's measure (equal within an element).
#[inline(always)]
fn element_points<const D: usize>(l: f64, p: &[Point<D>; D], mut push: impl FnMut([f64; 3], f64)) {
    if D == 2 {
        let e = p[1] - p[0];
        let m = (e.norm() * l).ceil().clamp(1.0, 4096.0) as usize;
        let w = e[1] / (2 * m) as f64;
        for s in 0..m {
            for g in GAUSS2 {
                let x = p[0] + e * ((s as f64 + g) / m as f64);
                push([x[0], x[1], 0.0], w);
            }
        }
    } else {
        let (u, v) = (p[1] - p[0], p[2] - p[0]);
        let nu1 = 0.5 * (u[1] * v[2] - u[2] * v[1]);
        let hmax = u.norm().max(v.norm()).max((p[2] - p[1]).norm());
        let m = (hmax * l / 2.0).ceil().clamp(1.0, 256.0) as usize;
        let (step, w) = (1.0 / m as f64, nu1 / (3 * m * m) as f64);
        let third =
            [(2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0), (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0), (1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0)];
        for i in 0..m {
            for j in 0..m - i {
                let (s0, t0) = (i as f64 * step, j as f64 * step);
                let mut tri = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
                    for (wa, wb, wc) in third {
                        let s = wa * a.0 + wb * b.0 + wc * c.0;
                        let t = wa * a.1 + wb * b.1 + wc * c.1;
                        let x = p[0] + u * s + v * t;
                        push([x[0], x[1], x[2]], w);
                    }
                };
                tri((s0, t0), (s0 + step, t0), (s0, t0 + step));
                if i + j + 1 < m {
                    tri((s0 + step, t0), (s0 + step, t0 + step), (s0, t0 + step));
                }
            }
        }
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
        element_points(l, &mesh.element_points(e), |x, w| lanes.push(x, w, o));
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
        for k in 0..3 {
            self.x[k][j] = x[k];
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
