//! The region integrals of the Chan–Vese functional: per object `(∫ I, ∫ Q, |Ω|)`
//! as boundary integrals of the antiderivatives of the image splines, by Gauss
//! quadrature on every element, four points at a time.

use super::ChanVese;
use crate::geometry::{Mesh, Point};
use crate::imaging::EdgeField;

/// `(∫ I, ∫ Q, |Ω|)` of one object.
pub(super) type Moments = [f64; 3];

/// Two-point Gauss rule on `[0, 1]`.
const GAUSS2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

impl ChanVese {
    /// `(∫_e Φ_I ν₁, ∫_e Φ_Q ν₁, ∫_e x₁ ν₁)` over element `e`: two Gauss points per
    /// pixel of length on segments, the 3-point rule on sub-triangles of about two
    /// pixels on triangles (equal weights within an element: the sums are scaled
    /// once).
    #[inline(always)]
    pub(super) fn element_moments<const D: usize>(&self, p: &[Point<D>; D]) -> Moments {
        let l = self.intensity.scale();
        let mut lanes = Lanes::new(self);
        let w = if D == 2 {
            let e = p[1] - p[0];
            let m = (e.norm() * l).ceil().clamp(1.0, 4096.0) as usize;
            for s in 0..m {
                for g in GAUSS2 {
                    let x = p[0] + e * ((s as f64 + g) / m as f64);
                    lanes.push([x[0], x[1], 0.0]);
                }
            }
            e[1] / (2 * m) as f64
        } else {
            let (u, v) = (p[1] - p[0], p[2] - p[0]);
            let nu1 = 0.5 * (u[1] * v[2] - u[2] * v[1]);
            let hmax = u.norm().max(v.norm()).max((p[2] - p[1]).norm());
            let m = (hmax * l / 2.0).ceil().clamp(1.0, 256.0) as usize;
            let step = 1.0 / m as f64;
            let third = [
                (2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
                (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
                (1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0),
            ];
            for i in 0..m {
                for j in 0..m - i {
                    let (s0, t0) = (i as f64 * step, j as f64 * step);
                    let mut tri = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
                        for (wa, wb, wc) in third {
                            let s = wa * a.0 + wb * b.0 + wc * c.0;
                            let t = wa * a.1 + wb * b.1 + wc * c.1;
                            let x = p[0] + u * s + v * t;
                            lanes.push([x[0], x[1], x[2]]);
                        }
                    };
                    tri((s0, t0), (s0 + step, t0), (s0, t0 + step));
                    if i + j + 1 < m {
                        tri((s0 + step, t0), (s0 + step, t0 + step), (s0, t0 + step));
                    }
                }
            }
            nu1 / (3 * m * m) as f64
        };
        lanes.finish().map(|sum| w * sum)
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
    for (e, &o) in element_object.iter().enumerate() {
        let m = cv.element_moments(&mesh.element_points(e));
        for k in 0..3 {
            moments[o][k] += m[k];
        }
    }
}

/// Quadrature points evaluated four at a time on both splines (the lanes of
/// [`EdgeField::lanes_2d`], one set of weights for both), summed in order: `(Σ Φ_I, Σ Φ_Q, Σ x₁)`.
struct Lanes<'a> {
    cv: &'a ChanVese,
    lanes: [[f64; 4]; 3],
    filled: usize,
    sums: Moments,
}

impl<'a> Lanes<'a> {
    #[inline(always)]
    fn new(cv: &'a ChanVese) -> Self {
        Lanes { cv, lanes: [[0.0; 4]; 3], filled: 0, sums: [0.0; 3] }
    }

    #[inline(always)]
    fn push(&mut self, x: [f64; 3]) {
        for k in 0..3 {
            self.lanes[k][self.filled] = x[k];
        }
        self.filled += 1;
        if self.filled == 4 {
            // both splines are on the image's grid: one set of weights serves both
            let fields = [&*self.cv.intensity, &*self.cv.squares];
            let [(_, pi), (_, pq)] = if fields[0].dimension() == 2 {
                EdgeField::lanes_2d(fields, self.lanes[0], self.lanes[1])
            } else {
                EdgeField::lanes_3d(fields, self.lanes)
            };
            for j in 0..4 {
                self.sums[0] += pi[j];
                self.sums[1] += pq[j];
                self.sums[2] += self.lanes[0][j];
            }
            self.filled = 0;
        }
    }

    #[inline(always)]
    fn finish(mut self) -> Moments {
        let (fi, fq) = (&*self.cv.intensity, &*self.cv.squares);
        for j in 0..self.filled {
            let [x, y, z] = [self.lanes[0][j], self.lanes[1][j], self.lanes[2][j]];
            let (pi, pq) = if fi.dimension() == 2 {
                let p = nalgebra::Vector2::new(x, y);
                (fi.value_and_antiderivative(&p).1, fq.value_and_antiderivative(&p).1)
            } else {
                let p = nalgebra::Vector3::new(x, y, z);
                (fi.value_and_antiderivative(&p).1, fq.value_and_antiderivative(&p).1)
            };
            self.sums[0] += pi;
            self.sums[1] += pq;
            self.sums[2] += x;
        }
        self.sums
    }
}
