//! Gaussian smoothing `I_σ = G_σ * I` (σ in samples), separable, with the grid
//! extended by replication at its borders.

use super::grid::Grid;

/// The normalized 1D kernel `exp(-x²/2σ²)` on `|x| ≤ ⌈4σ⌉`.
fn kernel(sigma: f64) -> Vec<f64> {
    let r = (4.0 * sigma).ceil() as isize;
    let k: Vec<f64> = (-r..=r).map(|x| (-(x * x) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let s: f64 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

/// Smooth `grid` with a Gaussian of standard deviation `sigma` samples along every
/// axis of its dimension; `sigma = 0` returns a copy.
pub fn gaussian_smooth(grid: &Grid, sigma: f64) -> Grid {
    if sigma <= 0.0 {
        return grid.clone();
    }
    let k = kernel(sigma);
    let r = (k.len() / 2) as isize;
    let mut cur = grid.values.clone();
    let mut next = vec![0.0; cur.len()];
    let dims = grid.dims;
    for axis in 0..grid.dimension {
        let n = dims[axis] as isize;
        let stride: usize = dims[..axis].iter().product();
        if axis == 0 {
            // one row at a time, padded by `r` replicated samples on each side, so
            // that each output is a plain dot product with the kernel
            let mut line = vec![0.0; (n + 2 * r) as usize];
            for (src, dst) in cur.chunks_exact(n as usize).zip(next.chunks_exact_mut(n as usize)) {
                for (u, l) in line.iter_mut().enumerate() {
                    *l = src[(u as isize - r).clamp(0, n - 1) as usize];
                }
                for (out, window) in dst.iter_mut().zip(line.windows(k.len())) {
                    let mut s = 0.0;
                    for (w, v) in k.iter().zip(window) {
                        s += w * v;
                    }
                    *out = s;
                }
            }
        } else {
            // along a strided axis whole rows at once (the same sums in the same
            // order, on contiguous memory): output row t is Σ_j k_j · row(t + j − r)
            for (src, dst) in cur.chunks_exact(stride * n as usize).zip(next.chunks_exact_mut(stride * n as usize)) {
                for (t, out) in dst.chunks_exact_mut(stride).enumerate() {
                    out.iter_mut().for_each(|v| *v = 0.0);
                    for (j, w) in k.iter().enumerate() {
                        let at = (t as isize + j as isize - r).clamp(0, n - 1) as usize;
                        for (o, v) in out.iter_mut().zip(&src[at * stride..(at + 1) * stride]) {
                            *o += w * v;
                        }
                    }
                }
            }
        }
        std::mem::swap(&mut cur, &mut next);
    }
    Grid { values: cur, ..grid.clone() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::SampleKind;

    #[test]
    fn preserves_constants_and_spreads_an_impulse_like_a_gaussian() {
        let n = 41;
        let mut v = vec![0.0; n * n];
        v[20 + n * 20] = 1.0;
        let g = Grid::new(2, [n, n, 1], v, SampleKind::F32);
        let s = gaussian_smooth(&g, 2.0);
        let total: f64 = s.values.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        // second moment along x: σ²
        let m2: f64 = (0..n * n).map(|i| s.values[i] * ((i % n) as f64 - 20.0).powi(2)).sum();
        assert!((m2 - 4.0).abs() < 4e-3, "{m2}");
        let c = gaussian_smooth(&Grid::new(3, [5, 6, 7], vec![3.0; 210], SampleKind::U8), 1.5);
        assert!(c.values.iter().all(|v| (v - 3.0).abs() < 1e-12));
    }
}
