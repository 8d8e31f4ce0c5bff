//! Uneven illumination: a quadratic background `B(x) = Σ c_k x^α_k` (all monomials
//! of degree ≤ 2 in the 2 or 3 coordinates, scaled to `[−1, 1]`) fitted by least
//! squares to the samples marked as background. Subtracting it (and adding back
//! its mean) flattens a vignette or an illumination gradient while keeping objects
//! and their contrast.

use super::grid::Grid;
use nalgebra::{DMatrix, DVector};

/// The monomials of degree ≤ 2 at `x` (`x` in `[−1, 1]^d`).
fn monomials(x: [f64; 3], d: usize) -> Vec<f64> {
    let mut m = vec![1.0];
    m.extend(&x[..d]);
    for a in 0..d {
        for b in a..d {
            m.push(x[a] * x[b]);
        }
    }
    m
}

/// The quadratic background of `grid` fitted to the samples where `background` is
/// true, evaluated at every sample; `None` if they are too few (fewer than 10 per
/// coefficient) or the fit is singular.
pub fn quadratic_background(grid: &Grid, background: &[bool]) -> Option<Vec<f64>> {
    let d = grid.dimension;
    let coords = |p: usize| -> [f64; 3] {
        let idx = [p % grid.dims[0], (p / grid.dims[0]) % grid.dims[1], p / (grid.dims[0] * grid.dims[1])];
        std::array::from_fn(|a| {
            let n = grid.dims[a] as f64;
            if n > 1.0 {
                2.0 * idx[a] as f64 / (n - 1.0) - 1.0
            } else {
                0.0
            }
        })
    };
    let k = monomials([0.0; 3], d).len();
    if background.iter().filter(|&&b| b).count() < 10 * k {
        return None;
    }
    // normal equations, accumulated sample by sample
    let mut ata = DMatrix::<f64>::zeros(k, k);
    let mut atb = DVector::<f64>::zeros(k);
    for (p, _) in background.iter().enumerate().filter(|(_, &b)| b) {
        let m = monomials(coords(p), d);
        for i in 0..k {
            atb[i] += m[i] * grid.values[p];
            for j in 0..k {
                ata[(i, j)] += m[i] * m[j];
            }
        }
    }
    let c = ata.cholesky()?.solve(&atb);
    Some((0..grid.len()).map(|p| monomials(coords(p), d).iter().zip(c.iter()).map(|(m, c)| m * c).sum()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::SampleKind;

    /// A quadratic ramp under a square object is recovered from the background.
    #[test]
    fn a_ramp_under_an_object() {
        let (w, h) = (60, 40);
        let ramp = |i: usize, j: usize| 0.2 + 0.003 * i as f64 + 0.0001 * (j * j) as f64;
        let object = |i: usize, j: usize| (20..35).contains(&i) && (10..25).contains(&j);
        let values: Vec<f64> =
            (0..w * h).map(|p| ramp(p % w, p / w) + if object(p % w, p / w) { 0.5 } else { 0.0 }).collect();
        let g = Grid::new(2, [w, h, 1], values, SampleKind::F32);
        let bg: Vec<bool> = (0..w * h).map(|p| !object(p % w, p / w)).collect();
        let b = quadratic_background(&g, &bg).unwrap();
        for p in 0..w * h {
            assert!((b[p] - ramp(p % w, p / w)).abs() < 1e-9);
        }
        assert!(quadratic_background(&g, &vec![false; w * h]).is_none());
    }
}
