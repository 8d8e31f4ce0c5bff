//! Evaluation of the edge indicator: `H`, `∇H`, `D²H` at points from the
//! B-spline coefficients, and the grid coordinates and taps that the
//! antiderivative's sums ([`super::antiderivative`]) share.

use super::{EdgeField, EdgeSample};
use crate::imaging::bspline;
use nalgebra::{SMatrix, SVector};

/// One axis of an evaluation: first tap, local coordinate, whether `u` was clamped.
pub(super) struct Axis {
    pub(super) i0: isize,
    pub(super) t: f64,
    pub(super) excess: f64,
}

impl EdgeField {
    #[inline(always)]
    pub(super) fn axis(&self, x: f64, a: usize) -> Axis {
        let (i0, t, excess) = self.grid_coordinate(x, a);
        Axis { i0: i0 as isize, t, excess }
    }

    /// `u = xL − ½` along axis `a`, clamped to `[−2, n + 1]`: its integer part (as a
    /// float), the fraction, and what the clamp cut off. Plain comparisons, so that
    /// several points at once run as vectors.
    #[inline(always)]
    pub(super) fn grid_coordinate(&self, x: f64, a: usize) -> (f64, f64, f64) {
        let n = self.dims[a] as f64;
        let u = x * self.scale - 0.5;
        let uc = if u < -2.0 {
            -2.0
        } else if u > n + 1.0 {
            n + 1.0
        } else {
            u
        };
        let i0 = uc.floor();
        (i0, uc - i0, u - uc)
    }

    /// The four sample indices of the taps of `ax` along axis `a`, clamped to the grid.
    #[inline(always)]
    pub(super) fn tap_indices(&self, ax: &Axis, a: usize) -> [usize; 4] {
        let n = self.dims[a] as isize;
        std::array::from_fn(|q| (ax.i0 - 1 + q as isize).clamp(0, n - 1) as usize)
    }

    /// Taps along axis `a`: clamped sample indices, weights `[w, w', w'']` and the
    /// number of taps (`1` with weight 1 for the unused third axis of a 2D field).
    #[inline(always)]
    fn taps(&self, x: &[f64; 3], a: usize, derivatives: bool) -> Taps {
        if a >= self.dimension {
            return Taps { index: [0; 4], w: [[1.0, 0.0, 0.0, 0.0], [0.0; 4], [0.0; 4]], count: 1 };
        }
        let ax = self.axis(x[a], a);
        let index = self.tap_indices(&ax, a);
        let clamped = ax.excess != 0.0;
        // outside the grid the field is constant along this axis
        let w = if !derivatives || clamped {
            [bspline::w(ax.t), [0.0; 4], [0.0; 4]]
        } else {
            [bspline::w(ax.t), bspline::dw(ax.t), bspline::ddw(ax.t)]
        };
        Taps { index, w, count: 4 }
    }

    #[inline]
    pub(super) fn strides(&self) -> (usize, usize) {
        (self.dims[0], self.dims[0] * self.dims[1])
    }

    /// `H`, `∇H`, `D²H` at `p` (unit-box coordinates; `D` must be the field's dimension).
    #[inline(always)]
    pub fn sample<const D: usize>(&self, p: &SVector<f64, D>) -> EdgeSample<D> {
        debug_assert_eq!(D, self.dimension);
        if D == 2 {
            let (h, g, k) = self.sample_2d(p[0], p[1]);
            let grad = SVector::<f64, D>::from_fn(|a, _| g[a]);
            let hess = SMatrix::<f64, D, D>::from_fn(|a, b| k[a][b]);
            return EdgeSample { h, grad, hess };
        }
        let x: [f64; 3] = std::array::from_fn(|a| if a < D { p[a] } else { 0.0 });
        let (tx, ty, tz) = (self.taps(&x, 0, true), self.taps(&x, 1, true), self.taps(&x, 2, true));
        let (sy, sz) = self.strides();
        // value, gradient (3), Hessian (xx, yy, zz, xy, xz, yz)
        let mut acc = [0.0f64; 10];
        for c in 0..tz.count {
            for b in 0..ty.count {
                let base = sy * ty.index[b] + sz * tz.index[c];
                let (y0, y1, y2) = (ty.w[0][b], ty.w[1][b], ty.w[2][b]);
                let (z0, z1, z2) = (tz.w[0][c], tz.w[1][c], tz.w[2][c]);
                let (s0, s1, s2) = self.row_sums(base, &tx);
                acc[0] += s0 * y0 * z0;
                acc[1] += s1 * y0 * z0;
                acc[2] += s0 * y1 * z0;
                acc[3] += s0 * y0 * z1;
                acc[4] += s2 * y0 * z0;
                acc[5] += s0 * y2 * z0;
                acc[6] += s0 * y0 * z2;
                acc[7] += s1 * y1 * z0;
                acc[8] += s1 * y0 * z1;
                acc[9] += s0 * y1 * z1;
            }
        }
        let l = self.scale;
        let mut grad = SVector::<f64, D>::zeros();
        let mut hess = SMatrix::<f64, D, D>::zeros();
        let full = [[acc[4], acc[7], acc[8]], [acc[7], acc[5], acc[9]], [acc[8], acc[9], acc[6]]];
        for a in 0..D {
            grad[a] = l * acc[1 + a];
            for b in 0..D {
                hess[(a, b)] = l * l * full[a][b];
            }
        }
        EdgeSample { h: acc[0], grad, hess }
    }

    /// Sums over the x taps of one row (from `base`) of `v w`, `v w'`, `v w''`.
    #[inline(always)]
    fn row_sums(&self, base: usize, tx: &Taps) -> (f64, f64, f64) {
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for a in 0..4 {
            let v = self.coef[base + tx.index[a]];
            s0 += v * tx.w[0][a];
            s1 += v * tx.w[1][a];
            s2 += v * tx.w[2][a];
        }
        (s0, s1, s2)
    }

    /// [`Self::sample`] of a 2D field: the same sums in the same order (the
    /// general path's factors of the unused third axis are 1 and 0), written out.
    #[inline(always)]
    fn sample_2d(&self, x: f64, y: f64) -> (f64, [f64; 2], [[f64; 2]; 2]) {
        let xs = [x, y, 0.0];
        let (tx, ty) = (self.taps(&xs, 0, true), self.taps(&xs, 1, true));
        let sy = self.dims[0];
        let (mut h, mut hx, mut hy, mut hxx, mut hyy, mut hxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for b in 0..4 {
            let base = sy * ty.index[b];
            let (y0, y1, y2) = (ty.w[0][b], ty.w[1][b], ty.w[2][b]);
            let (s0, s1, s2) = self.row_sums(base, &tx);
            h += s0 * y0;
            hx += s1 * y0;
            hy += s0 * y1;
            hxx += s2 * y0;
            hyy += s0 * y2;
            hxy += s1 * y1;
        }
        let l = self.scale;
        (h, [l * hx, l * hy], [[l * l * hxx, l * l * hxy], [l * l * hxy, l * l * hyy]])
    }
}

/// The taps of one axis of an evaluation.
struct Taps {
    index: [usize; 4],
    w: [[f64; 4]; 3],
    count: usize,
}
