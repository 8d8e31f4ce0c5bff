//! The antiderivative `Φ(p) = ∫^{p₁} H(s, p₂, p₃) ds` of an edge field (with its
//! value `H`) from the B-spline coefficients and the row prefix sums: at one
//! point, and four points at a time of several fields on one grid, the region
//! integrals' quadrature.

use super::evaluate::Axis;
use super::{EdgeField, PAD};
use crate::imaging::bspline;
use nalgebra::SVector;

impl EdgeField {
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
