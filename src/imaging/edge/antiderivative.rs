//! The antiderivative `Φ` alone, at four points at a time of several fields on
//! one grid: what the region integrals of the Chan–Vese model need (`∫_Ω f =
//! ∫_Γ Φ_f ν₁`). The same sums as [`EdgeField::value_and_antiderivative`] makes
//! for `Φ`; the value's own sums only for points beyond the grid along `x`, the
//! one place where the value enters `Φ` (times the clamp's excess).

use super::evaluate::Axis;
use super::{EdgeField, PAD};
use crate::imaging::bspline;

impl EdgeField {
    /// `Φ` of each of `fields` (the same dimensions and scale) at the four points
    /// `p` (coordinates by axis; the third unused in 2D): grid coordinates and
    /// weights computed once, as vectors, for every field.
    #[inline(always)]
    pub(crate) fn antiderivatives<const K: usize>(fields: [&EdgeField; K], p: [[f64; 4]; 3]) -> [[f64; 4]; K] {
        let grid = fields[0];
        debug_assert!(fields.iter().all(|f| f.dims == grid.dims && f.scale == grid.scale));
        let d = grid.dimension;
        let mut axes = [[(0.0, 0.0, 0.0); 4]; 3];
        for a in 0..d {
            for j in 0..4 {
                axes[a][j] = grid.grid_coordinate(p[a][j], a);
            }
        }
        let (mut wx, mut iwx, mut wy, mut wz) = ([[0.0; 4]; 4], [[0.0; 4]; 4], [[0.0; 4]; 4], [[0.0; 4]; 4]);
        for j in 0..4 {
            (wx[j], iwx[j], wy[j]) = (bspline::w(axes[0][j].1), bspline::iw(axes[0][j].1), bspline::w(axes[1][j].1));
            if d == 3 {
                wz[j] = bspline::w(axes[2][j].1);
            }
        }
        let mut out = [[0.0; 4]; K];
        for (field, phi) in fields.iter().zip(out.iter_mut()) {
            for j in 0..4 {
                let axis = |a: usize| Axis { i0: axes[a][j].0 as isize, t: axes[a][j].1, excess: axes[a][j].2 };
                phi[j] = if d == 2 {
                    field.integral_2d(&axis(0), &axis(1), &wx[j], &iwx[j], &wy[j])
                } else {
                    field.integral_3d(&axis(0), &axis(1), &axis(2), &wx[j], &iwx[j], &wy[j], &wz[j])
                };
            }
        }
        out
    }

    /// `Φ` of a 2D field: `Σ_b w_b (R_b + Σ_a c_ab iw_a + excess Σ_a c_ab w_a)`.
    #[inline(always)]
    fn integral_2d(&self, ax: &Axis, ay: &Axis, wx: &[f64; 4], iwx: &[f64; 4], wy: &[f64; 4]) -> f64 {
        let (ix, iy) = (self.tap_indices(ax, 0), self.tap_indices(ay, 1));
        let (width, m, inside) = self.row_layout(ax);
        let mut phi = 0.0;
        for b in 0..4 {
            let row = iy[b];
            phi += wy[b] * self.row_integral(self.dims[0] * row, row * width + m, &ix, inside, ax.excess, wx, iwx);
        }
        phi / self.scale
    }

    /// `Φ` of a 3D field, the rows `(b, c)` weighted by `w_b w_c`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn integral_3d(
        &self,
        ax: &Axis,
        ay: &Axis,
        az: &Axis,
        wx: &[f64; 4],
        iwx: &[f64; 4],
        wy: &[f64; 4],
        wz: &[f64; 4],
    ) -> f64 {
        let (ix, iy, iz) = (self.tap_indices(ax, 0), self.tap_indices(ay, 1), self.tap_indices(az, 2));
        let (sy, sz) = self.strides();
        let (width, m, inside) = self.row_layout(ax);
        let mut phi = 0.0;
        for c in 0..4 {
            for b in 0..4 {
                let row = iy[b] + self.dims[1] * iz[c];
                let base = sy * iy[b] + sz * iz[c];
                phi += wy[b] * wz[c] * self.row_integral(base, row * width + m, &ix, inside, ax.excess, wx, iwx);
            }
        }
        phi / self.scale
    }

    /// Width of a row of prefix sums, the offset of the taps' prefix in it, and
    /// whether the four x taps lie inside the grid (one slice).
    #[inline(always)]
    fn row_layout(&self, ax: &Axis) -> (usize, usize, bool) {
        let nx = self.dims[0] as isize;
        (self.dims[0] + 2 * PAD as usize, (ax.i0 - 2 + PAD) as usize, ax.i0 >= 1 && ax.i0 + 2 < nx)
    }

    /// One row's `R + Σ_a c_a iw_a`, plus `excess · Σ_a c_a w_a` where the point
    /// lies beyond the grid along x (`excess ≠ 0`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn row_integral(
        &self,
        base: usize,
        prefix_at: usize,
        ix: &[usize; 4],
        inside: bool,
        excess: f64,
        wx: &[f64; 4],
        iwx: &[f64; 4],
    ) -> f64 {
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
        if excess != 0.0 {
            let mut s0 = 0.0;
            for a in 0..4 {
                s0 += v[a] * wx[a];
            }
            si += excess * s0;
        }
        si
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    /// `Φ` alone equals the `Φ` of [`EdgeField::value_and_antiderivative`] (to
    /// rounding), inside the grid, on its border and beyond it, in 2D and 3D.
    #[test]
    fn equals_the_antiderivative_with_the_value() {
        let (nx, ny, nz) = (7usize, 5usize, 4usize);
        let f = |x: usize, y: usize, z: usize| ((x * 7 + y * 3 + z * 5) % 11) as f64 - 2.5;
        let c2: Vec<f64> = (0..nx * ny).map(|i| f(i % nx, i / nx, 0)).collect();
        let c3: Vec<f64> = (0..nx * ny * nz).map(|i| f(i % nx, (i / nx) % ny, i / (nx * ny))).collect();
        let a2 = EdgeField::from_coefficients(2, [nx, ny, 1], c2.clone());
        let b2 = EdgeField::from_coefficients(2, [nx, ny, 1], c2.iter().map(|v| v * v).collect());
        let a3 = EdgeField::from_coefficients(3, [nx, ny, nz], c3);
        let xs = [-0.4, -0.01, 0.0, 0.03, 0.31, 0.5, 0.77, 0.99, 1.0, 1.2, 1.7, 0.13];
        for chunk in xs.chunks(4) {
            let px: [f64; 4] = [chunk[0], chunk[1], chunk[2], chunk[3]];
            let py = [px[1], px[3], px[0], px[2]].map(|v| 0.8 * v - 0.05);
            let pz = [px[2], px[0], px[3], px[1]].map(|v| 1.1 * v + 0.02);
            let [p2a, p2b] = EdgeField::antiderivatives([&a2, &b2], [px, py, [0.0; 4]]);
            let [p3] = EdgeField::antiderivatives([&a3], [px, py, pz]);
            for j in 0..4 {
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (1.0 + b.abs());
                assert!(close(p2a[j], a2.antiderivative(&Vector2::new(px[j], py[j]))));
                assert!(close(p2b[j], b2.antiderivative(&Vector2::new(px[j], py[j]))));
                assert!(close(p3[j], a3.antiderivative(&Vector3::new(px[j], py[j], pz[j]))));
            }
        }
    }
}
