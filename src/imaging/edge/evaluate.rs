//! Evaluation of the edge indicator: `H`, `∇H`, `D²H` and the antiderivative `Φ`
//! at points, from the B-spline coefficients and the row prefix sums.

use super::{EdgeField, EdgeSample, PAD};
use crate::imaging::bspline;
use nalgebra::{SMatrix, SVector};

/// One axis of an evaluation: first tap, local coordinate, whether `u` was clamped.
struct Axis {
    i0: isize,
    t: f64,
    excess: f64,
}

impl EdgeField {
    #[inline(always)]
    fn axis(&self, x: f64, a: usize) -> Axis {
        let (i0, t, excess) = self.grid_coordinate(x, a);
        Axis { i0: i0 as isize, t, excess }
    }

    /// `u = xL − ½` along axis `a`, clamped to `[−2, n + 1]`: its integer part (as a
    /// float), the fraction, and what the clamp cut off. Plain comparisons, so that
    /// several points at once run as vectors.
    #[inline(always)]
    fn grid_coordinate(&self, x: f64, a: usize) -> (f64, f64, f64) {
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
    fn tap_indices(&self, ax: &Axis, a: usize) -> [usize; 4] {
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
    fn strides(&self) -> (usize, usize) {
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

    /// `H(p)` and `Φ(p) = ∫^{p₁} H(s, p₂, p₃) ds` (an antiderivative in the first
    /// coordinate, up to a constant that does not matter for closed boundaries).
    #[inline(always)]
    pub fn value_and_antiderivative<const D: usize>(&self, p: &SVector<f64, D>) -> (f64, f64) {
        if D == 2 {
            self.value_and_antiderivative_2d(p[0], p[1])
        } else {
            self.value_and_antiderivative_3d(p[0], p[1], p[2])
        }
    }

    /// [`Self::value_and_antiderivative`] of a 3D field: `Σ_c Σ_b w_b w_c (Σ_a c_abc w_a,
    /// R_bc + Σ_a c_abc iw_a)` over the 4×4×4 taps, one slice per row where the taps
    /// lie inside the grid.
    #[inline(always)]
    fn value_and_antiderivative_3d(&self, x: f64, y: f64, z: f64) -> (f64, f64) {
        let (ax, ay, az) = (self.axis(x, 0), self.axis(y, 1), self.axis(z, 2));
        let (wx, iwx) = (bspline::w(ax.t), bspline::iw(ax.t));
        self.sum_3d::<true>(&ax, &ay, &az, &wx, &iwx, &bspline::w(ay.t), &bspline::w(az.t))
    }

    /// The sums of [`Self::value_and_antiderivative_3d`] with the axes and weights
    /// given; without `VALUE` the value is 0 and only `Φ` is summed.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn sum_3d<const VALUE: bool>(
        &self,
        ax: &Axis,
        ay: &Axis,
        az: &Axis,
        wx: &[f64; 4],
        iwx: &[f64; 4],
        wy: &[f64; 4],
        wz: &[f64; 4],
    ) -> (f64, f64) {
        let nx = self.dims[0] as isize;
        let (ix, iy, iz) = (self.tap_indices(ax, 0), self.tap_indices(ay, 1), self.tap_indices(az, 2));
        let (sy, sz) = self.strides();
        let width = self.dims[0] + 2 * PAD as usize;
        let m = (ax.i0 - 2 + PAD) as usize;
        let inside = ax.i0 >= 1 && ax.i0 + 2 < nx;
        let (mut h, mut phi) = (0.0, 0.0);
        for c in 0..4 {
            for b in 0..4 {
                let row = iy[b] + self.dims[1] * iz[c];
                let base = sy * iy[b] + sz * iz[c];
                let (s0, si) =
                    self.row_sums_with_integral::<VALUE>(base, row * width + m, &ix, inside, ax.excess, wx, iwx);
                let wyz = wy[b] * wz[c];
                if VALUE {
                    h += wyz * s0;
                }
                phi += wyz * si;
            }
        }
        (h, phi / self.scale)
    }

    /// [`Self::value_and_antiderivative_3d`] at four points, with the grid
    /// coordinates and the B-spline weights computed lane by lane (as vectors).
    #[inline(always)]
    pub(crate) fn values_and_antiderivatives_3d(&self, p: [[f64; 4]; 3]) -> ([f64; 4], [f64; 4]) {
        let [(h, phi)] = Self::lanes_3d::<1, true>([self], p);
        (h, phi)
    }

    /// [`Self::values_and_antiderivatives_3d`] of several fields on one grid, as
    /// [`Self::lanes_2d`] (`VALUE` likewise).
    #[inline(always)]
    pub(crate) fn lanes_3d<const K: usize, const VALUE: bool>(
        fields: [&EdgeField; K],
        p: [[f64; 4]; 3],
    ) -> [([f64; 4], [f64; 4]); K] {
        let grid = fields[0];
        debug_assert!(fields.iter().all(|f| f.dims == grid.dims && f.scale == grid.scale));
        let mut axes: [[(f64, f64, f64); 4]; 3] = [[(0.0, 0.0, 0.0); 4]; 3];
        for a in 0..3 {
            for j in 0..4 {
                axes[a][j] = grid.grid_coordinate(p[a][j], a);
            }
        }
        let mut w = [[[0.0; 4]; 4]; 3];
        let mut iwx = [[0.0; 4]; 4];
        for j in 0..4 {
            for a in 0..3 {
                w[a][j] = bspline::w(axes[a][j].1);
            }
            iwx[j] = bspline::iw(axes[0][j].1);
        }
        let mut out = [([0.0; 4], [0.0; 4]); K];
        for (field, (h, phi)) in fields.iter().zip(out.iter_mut()) {
            for j in 0..4 {
                let axis = |a: usize| Axis { i0: axes[a][j].0 as isize, t: axes[a][j].1, excess: axes[a][j].2 };
                (h[j], phi[j]) =
                    field.sum_3d::<VALUE>(&axis(0), &axis(1), &axis(2), &w[0][j], &iwx[j], &w[1][j], &w[2][j]);
            }
        }
        out
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

    /// One row of the value and antiderivative sums from `base`: `(Σ_a c_a w_a,
    /// R + Σ_a c_a iw_a + excess Σ_a c_a w_a)` over the x taps `ix` (read as one
    /// slice when `inside` the grid), `R = prefix[prefix_at]` the row's prefix sum
    /// before the taps, `excess` what the clamp cut off the point's x. Without
    /// `VALUE` the value's sum is made only where `excess ≠ 0` (and returned as 0
    /// elsewhere): `Φ` needs it only beyond the grid.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn row_sums_with_integral<const VALUE: bool>(
        &self,
        base: usize,
        prefix_at: usize,
        ix: &[usize; 4],
        inside: bool,
        excess: f64,
        wx: &[f64; 4],
        iwx: &[f64; 4],
    ) -> (f64, f64) {
        let v: [f64; 4] = if inside {
            let r = &self.coef[base + ix[0]..base + ix[0] + 4];
            [r[0], r[1], r[2], r[3]]
        } else {
            [self.coef[base + ix[0]], self.coef[base + ix[1]], self.coef[base + ix[2]], self.coef[base + ix[3]]]
        };
        let mut si = self.prefix[prefix_at];
        for a in 0..4 {
            si += v[a] * iwx[a];
        }
        let mut s0 = 0.0;
        if VALUE || excess != 0.0 {
            for a in 0..4 {
                s0 += v[a] * wx[a];
            }
        }
        (s0, si + excess * s0)
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

    /// [`Self::value_and_antiderivative`] of a 2D field, the same sums in the same
    /// order, written out for the quadrature of the energy (most of a 2D run):
    /// fixed 4×4 taps, and one slice per row where the taps lie inside the grid.
    #[inline(always)]
    fn value_and_antiderivative_2d(&self, x: f64, y: f64) -> (f64, f64) {
        let (ax, ay) = (self.axis(x, 0), self.axis(y, 1));
        let (wx, iwx, wy) = (bspline::w(ax.t), bspline::iw(ax.t), bspline::w(ay.t));
        self.sum_2d::<true>(&ax, &ay, &wx, &iwx, &wy)
    }

    /// The sums of [`Self::value_and_antiderivative_2d`] with the axes and weights
    /// given; without `VALUE` the value is 0 and only `Φ` is summed.
    #[inline(always)]
    fn sum_2d<const VALUE: bool>(
        &self,
        ax: &Axis,
        ay: &Axis,
        wx: &[f64; 4],
        iwx: &[f64; 4],
        wy: &[f64; 4],
    ) -> (f64, f64) {
        let nx = self.dims[0] as isize;
        let (ix, iy) = (self.tap_indices(ax, 0), self.tap_indices(ay, 1));
        let width = self.dims[0] + 2 * PAD as usize;
        let m = (ax.i0 - 2 + PAD) as usize;
        let inside = ax.i0 >= 1 && ax.i0 + 2 < nx;
        let (mut h, mut phi) = (0.0, 0.0);
        for b in 0..4 {
            let row = iy[b];
            let base = self.dims[0] * row;
            let (s0, si) = self.row_sums_with_integral::<VALUE>(base, row * width + m, &ix, inside, ax.excess, wx, iwx);
            // (the general path's weight is `wy[b]·1` for the unused third axis)
            if VALUE {
                h += wy[b] * s0;
            }
            phi += wy[b] * si;
        }
        (h, phi / self.scale)
    }

    /// [`Self::value_and_antiderivative_2d`] at four points, with the grid
    /// coordinates and the B-spline weights computed lane by lane (as vectors).
    #[inline(always)]
    pub(crate) fn values_and_antiderivatives_2d(&self, xs: [f64; 4], ys: [f64; 4]) -> ([f64; 4], [f64; 4]) {
        let [(h, phi)] = Self::lanes_2d::<1, true>([self], xs, ys);
        (h, phi)
    }

    /// [`Self::values_and_antiderivatives_2d`] of several fields on one grid (the
    /// same dimensions and scale): the coordinates and weights are computed once
    /// and serve every field, with the same sums for each as alone; without
    /// `VALUE` the values are 0 and only `Φ` is summed ([`Self::antiderivatives`]).
    #[inline(always)]
    pub(crate) fn lanes_2d<const K: usize, const VALUE: bool>(
        fields: [&EdgeField; K],
        xs: [f64; 4],
        ys: [f64; 4],
    ) -> [([f64; 4], [f64; 4]); K] {
        let grid = fields[0];
        debug_assert!(fields.iter().all(|f| f.dims == grid.dims && f.scale == grid.scale));
        let lanes = |v: [f64; 4], a: usize| {
            let (mut i0, mut t, mut excess) = ([0.0; 4], [0.0; 4], [0.0; 4]);
            for j in 0..4 {
                (i0[j], t[j], excess[j]) = grid.grid_coordinate(v[j], a);
            }
            (i0, t, excess)
        };
        let (ix0, tx, ex) = lanes(xs, 0);
        let (iy0, ty, _) = lanes(ys, 1);
        let (mut wx, mut iwx, mut wy) = ([[0.0; 4]; 4], [[0.0; 4]; 4], [[0.0; 4]; 4]);
        for j in 0..4 {
            (wx[j], iwx[j], wy[j]) = (bspline::w(tx[j]), bspline::iw(tx[j]), bspline::w(ty[j]));
        }
        // a plain loop: `array::from_fn` is not inlined into the AVX2 copies of
        // the callers
        let mut out = [([0.0; 4], [0.0; 4]); K];
        for (field, (h, phi)) in fields.iter().zip(out.iter_mut()) {
            for j in 0..4 {
                let ax = Axis { i0: ix0[j] as isize, t: tx[j], excess: ex[j] };
                let ay = Axis { i0: iy0[j] as isize, t: ty[j], excess: 0.0 };
                (h[j], phi[j]) = field.sum_2d::<VALUE>(&ax, &ay, &wx[j], &iwx[j], &wy[j]);
            }
        }
        out
    }

    /// `Φ` alone of each of `fields` (one grid, as [`Self::lanes_2d`]) at the four
    /// points `p` (coordinates by axis; the third unused in 2D): the region
    /// integrals' quadrature, which needs no value.
    #[inline(always)]
    pub(crate) fn antiderivatives<const K: usize>(fields: [&EdgeField; K], p: [[f64; 4]; 3]) -> [[f64; 4]; K] {
        let lanes = if fields[0].dimension == 2 {
            Self::lanes_2d::<K, false>(fields, p[0], p[1])
        } else {
            Self::lanes_3d::<K, false>(fields, p)
        };
        // a plain loop, as in `lanes_2d`
        let mut out = [[0.0; 4]; K];
        for (phi, (_, lane)) in out.iter_mut().zip(lanes) {
            *phi = lane;
        }
        out
    }

    /// `H(p)` only.
    pub fn value<const D: usize>(&self, p: &SVector<f64, D>) -> f64 {
        self.value_and_antiderivative(p).0
    }

    /// `Φ(p)` only (see [`Self::value_and_antiderivative`]).
    pub fn antiderivative<const D: usize>(&self, p: &SVector<f64, D>) -> f64 {
        self.value_and_antiderivative(p).1
    }
}

/// The taps of one axis of an evaluation.
struct Taps {
    index: [usize; 4],
    w: [[f64; 4]; 3],
    count: usize,
}
