//! The edge indicator of geodesic active contours (paper §1.1):
//! `H = 1/(1 + |∇I_σ|²)`, where `I` is the image mapped onto `[0, 100]` (so that
//! 8-bit, 16-bit and float inputs behave alike; 100 levels per pixel of gradient is
//! the scale of the paper's 100×100 images) and `I_σ` its Gaussian smoothing; the
//! gradient is taken per sample by central differences.
//!
//! `H` is represented on the whole plane/space by the cubic B-spline with the grid
//! values as coefficients, `H(x) = Σ c_ijk B(u-i) B(v-j) B(w-k)`, `u = xL - ½` etc.
//! (C², so `∇H` and `D²H` are continuous), extended by replicating the border
//! samples. For the domain integral `∫_Ω H` the field also provides the exact
//! antiderivative in `x`, `Φ(x) = ∫^x H dx₁` (row-wise prefix sums of the
//! coefficients and the integrated spline), so that `∫_Ω H = ∫_Γ Φ ν₁` by the
//! divergence theorem.

use super::contrast::{contrast_scale, noise_gradient};
use super::grid::Grid;
use super::smooth::gaussian_smooth;
use super::threshold::noise_level;
use nalgebra::{SMatrix, SVector};

mod antiderivative;
mod evaluate;

/// Padding (in samples) of the row prefix sums on each side.
const PAD: isize = 4;

/// `H`, `∇H` and `D²H` at a point (unit-box coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeSample<const D: usize> {
    pub h: f64,
    pub grad: SVector<f64, D>,
    pub hess: SMatrix<f64, D, D>,
}

/// The interpolated edge indicator of an image (2D or 3D).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeField {
    dimension: usize,
    dims: [usize; 3],
    scale: f64,
    /// The Gaussian smoothing `σ` (samples) behind the field; 0 if built from coefficients.
    sigma: f64,
    coef: Vec<f64>,
    /// Per row `(j, k)`: `R(m) = Σ_{i=-PAD}^{m} c_(clamp i) j k`, `m = -PAD … n_x+PAD-1`.
    prefix: Vec<f64>,
}

impl EdgeField {
    /// The edge indicator `H = 1/(1 + |∇I_σ|²)` of `grid` mapped to [0, 100] and
    /// smoothed with `sigma` samples (the contrast scale `k = 1` of
    /// [`EdgeField::with_contrast`]). `None` when the image is constant.
    pub fn new(grid: &Grid, sigma: f64) -> Option<EdgeField> {
        Self::with_contrast(grid, sigma, Some(1.0)).map(|(f, _)| f)
    }

    /// The edge indicator `H = 1/(1 + |∇I_σ|²/k²)` of `grid` mapped to [0, 100]
    /// and smoothed with `sigma` samples, and the contrast scale `k` used: the one
    /// given, or by default [`contrast_scale`] of the image's own gradients. `None`
    /// when the image is constant (no edges at all).
    pub fn with_contrast(grid: &Grid, sigma: f64, k: Option<f64>) -> Option<(EdgeField, f64)> {
        let norm = grid.normalized(100.0)?;
        let s = gaussian_smooth(&norm, sigma);
        let d = grid.dims;
        let at = |i: isize, j: isize, k: isize| {
            let c = |x: isize, n: usize| x.clamp(0, n as isize - 1) as usize;
            s.values[grid.index(c(i, d[0]), c(j, d[1]), c(k, d[2]))]
        };
        // |∇I_σ|² by central differences
        let mut coef = vec![0.0; grid.len()];
        for k in 0..d[2] as isize {
            for j in 0..d[1] as isize {
                for i in 0..d[0] as isize {
                    let gx = 0.5 * (at(i + 1, j, k) - at(i - 1, j, k));
                    let gy = 0.5 * (at(i, j + 1, k) - at(i, j - 1, k));
                    let gz = if grid.dimension == 3 { 0.5 * (at(i, j, k + 1) - at(i, j, k - 1)) } else { 0.0 };
                    coef[grid.index(i as usize, j as usize, k as usize)] = gx * gx + gy * gy + gz * gz;
                }
            }
        }
        let k = k.unwrap_or_else(|| {
            let noise = noise_gradient(noise_level(&norm), sigma, grid.dimension);
            contrast_scale(&coef).max(2.0 * noise)
        });
        let inv = 1.0 / (k * k);
        for c in &mut coef {
            *c = 1.0 / (1.0 + *c * inv);
        }
        Some((EdgeField { sigma, ..Self::from_coefficients(grid.dimension, d, coef) }, k))
    }

    /// A field with the given spline coefficients (`H` at the samples).
    pub fn from_coefficients(dimension: usize, dims: [usize; 3], coef: Vec<f64>) -> EdgeField {
        let nx = dims[0];
        let width = nx + 2 * PAD as usize;
        let rows = dims[1] * dims[2];
        let mut prefix = vec![0.0; rows * width];
        for r in 0..rows {
            let mut acc = 0.0;
            for m in 0..width {
                let i = (m as isize - PAD).clamp(0, nx as isize - 1) as usize;
                acc += coef[i + nx * r];
                prefix[r * width + m] = acc;
            }
        }
        let scale = dims.iter().copied().max().unwrap_or(1) as f64;
        EdgeField { dimension, dims, scale, sigma: 0.0, coef, prefix }
    }

    /// The Gaussian smoothing `σ` of the image, in samples.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// `L`: samples per unit length.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    fn field(dimension: usize, dims: [usize; 3]) -> EdgeField {
        let n = dims[0] * dims[1] * dims[2];
        let coef = (0..n).map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0).collect();
        EdgeField::from_coefficients(dimension, dims, coef)
    }

    #[test]
    fn derivatives_match_finite_differences_2d_and_3d() {
        let f2 = field(2, [9, 7, 1]);
        let p = Vector2::new(0.43, 0.61);
        let s = f2.sample(&p);
        let h = 1e-6;
        for a in 0..2 {
            let e = Vector2::ith(a, h);
            let fd = (f2.value(&(p + e)) - f2.value(&(p - e))) / (2.0 * h);
            assert!((fd - s.grad[a]).abs() < 1e-5 * s.grad.norm().max(1.0), "{fd} {}", s.grad[a]);
            let fd2 = (f2.sample(&(p + e)).grad - f2.sample(&(p - e)).grad) / (2.0 * h);
            for b in 0..2 {
                assert!((fd2[b] - s.hess[(a, b)]).abs() < 1e-4 * s.hess.norm().max(1.0));
            }
            // dΦ/dx = H
        }
        let fd = (f2.antiderivative(&(p + Vector2::new(h, 0.0))) - f2.antiderivative(&(p - Vector2::new(h, 0.0))))
            / (2.0 * h);
        assert!((fd - s.h).abs() < 1e-6, "{fd} {}", s.h);
        // outside the grid: the extension is continuous and Φ' = H still holds
        let q = Vector2::new(-0.2, 1.3);
        let fd = (f2.antiderivative(&(q + Vector2::new(h, 0.0))) - f2.antiderivative(&(q - Vector2::new(h, 0.0))))
            / (2.0 * h);
        assert!((fd - f2.value(&q)).abs() < 1e-6);

        let f3 = field(3, [6, 5, 7]);
        let p = Vector3::new(0.31, 0.52, 0.77);
        let s = f3.sample(&p);
        for a in 0..3 {
            let e = Vector3::ith(a, h);
            let fd = (f3.value(&(p + e)) - f3.value(&(p - e))) / (2.0 * h);
            assert!((fd - s.grad[a]).abs() < 1e-5 * s.grad.norm().max(1.0));
            let fd2 = (f3.sample(&(p + e)).grad - f3.sample(&(p - e)).grad) / (2.0 * h);
            for b in 0..3 {
                assert!((fd2[b] - s.hess[(a, b)]).abs() < 1e-4 * s.hess.norm().max(1.0));
            }
        }
        let ex = Vector3::new(h, 0.0, 0.0);
        let fd = (f3.antiderivative(&(p + ex)) - f3.antiderivative(&(p - ex))) / (2.0 * h);
        assert!((fd - s.h).abs() < 1e-6);
    }

    #[test]
    fn constant_image_has_no_field_and_a_step_gives_a_valley() {
        use crate::imaging::SampleKind;
        let g = Grid::new(2, [16, 16, 1], vec![5.0; 256], SampleKind::U8);
        assert!(EdgeField::new(&g, 1.0).is_none());
        let v = (0..256).map(|i| if i % 16 < 8 { 0.0 } else { 255.0 }).collect();
        let f = EdgeField::new(&Grid::new(2, [16, 16, 1], v, SampleKind::U8), 1.0).unwrap();
        // the valley of H is at the edge x = 8/16
        let at = |x: f64| f.value(&Vector2::new(x, 0.5));
        assert!(at(0.5) < 0.01 && at(0.1) > 0.9 && at(0.9) > 0.9, "{} {} {}", at(0.5), at(0.1), at(0.9));
    }

    /// A step on the [0, 100] scale gets `H ≈ 1/400` at its steepest point with
    /// the automatic contrast scale (no noise: the strong edges set it).
    #[test]
    fn a_clean_step_gets_h_near_one_over_400() {
        use crate::imaging::SampleKind;
        let v = (0..256).map(|i| if i % 16 < 8 { 0.0 } else { 255.0 }).collect();
        let grid = Grid::new(2, [16, 16, 1], v, SampleKind::U8);
        let (f, k) = EdgeField::with_contrast(&grid, 1.0, None).unwrap();
        let lowest = (0..=160).map(|i| f.value(&Vector2::new(0.4 + i as f64 * 1e-3, 0.5))).fold(1.0, f64::min);
        // (the spline between the samples is not below its lowest sample by much)
        assert!(lowest > 0.8 / 401.0 && lowest < 1.25 / 401.0, "k {k}, lowest H {lowest}");
    }

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
