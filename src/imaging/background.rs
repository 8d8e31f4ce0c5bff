//! Uneven illumination: a quadratic background `B(x) = Σ c_k x^α_k` (all monomials
//! of degree ≤ 2 in the 2 or 3 coordinates, scaled to `[−1, 1]`) fitted by least
//! squares to the samples marked as background. Subtracting it (and adding back
//! its mean) flattens a vignette or an illumination gradient while keeping objects
//! and their contrast.

use super::grid::Grid;
use nalgebra::{DMatrix, DVector};

/// Most monomials of degree ≤ 2 in 3 variables.
const MAX_TERMS: usize = 10;

/// The monomials of degree ≤ 2 at `x` (`x` in `[−1, 1]^d`): `1`, the `x_a`, the
/// `x_a x_b` (`a ≤ b`), in that order; the number of them.
fn monomials(x: [f64; 3], d: usize) -> ([f64; MAX_TERMS], usize) {
    let mut m = [0.0; MAX_TERMS];
    m[0] = 1.0;
    let mut n = 1;
    for a in 0..d {
        m[n] = x[a];
        n += 1;
    }
    for a in 0..d {
        for b in a..d {
            m[n] = x[a] * x[b];
            n += 1;
        }
    }
    (m, n)
}

/// The coordinate of index `i` of `n` samples, scaled to `[−1, 1]`.
fn scaled(i: usize, n: usize) -> f64 {
    if n > 1 {
        2.0 * i as f64 / (n - 1) as f64 - 1.0
    } else {
        0.0
    }
}

/// The monomials of a row (fixed `y`, `z`) as `x^p · r`: the power `p` of `x` and
/// the factor `r` of `y` and `z` of each, in the order of [`monomials`].
fn row_factors(y: f64, z: f64, d: usize) -> ([usize; MAX_TERMS], [f64; MAX_TERMS]) {
    let (mut px, mut r) = ([0usize; MAX_TERMS], [0.0; MAX_TERMS]);
    let vars = [(1usize, 1.0), (0, y), (0, z)];
    let mut n = 0;
    let mut push = |p: usize, f: f64| {
        px[n] = p;
        r[n] = f;
        n += 1;
    };
    push(0, 1.0);
    for &(p, f) in &vars[..d] {
        push(p, f);
    }
    for a in 0..d {
        for b in a..d {
            push(vars[a].0 + vars[b].0, vars[a].1 * vars[b].1);
        }
    }
    (px, r)
}

/// The quadratic background of `grid` fitted to the samples where `background` is
/// true, evaluated at every sample; `None` if they are too few (fewer than 10 per
/// coefficient) or the fit is singular. Row by row: within a row only `x` varies,
/// so the normal equations take the row's sums of `x^p` and `x^p v`, and the
/// background is a quadratic in `x` there.
pub fn quadratic_background(grid: &Grid, background: &[bool]) -> Option<Vec<f64>> {
    let d = grid.dimension;
    let [nx, ny, nz] = grid.dims;
    let k = monomials([0.0; 3], d).1;
    if background.iter().filter(|&&b| b).count() < 10 * k {
        return None;
    }
    let xs: Vec<f64> = (0..nx).map(|i| scaled(i, nx)).collect();
    let mut ata = [[0.0; MAX_TERMS]; MAX_TERMS];
    let mut atb = [0.0; MAX_TERMS];
    for kz in 0..nz {
        for j in 0..ny {
            let row = grid.index(0, j, kz);
            // Σ x^p (p ≤ 4) and Σ x^p v (p ≤ 2) over the row's background samples
            let (mut sx, mut sv) = ([0.0; 5], [0.0; 3]);
            for (i, &x) in xs.iter().enumerate() {
                if background[row + i] {
                    let (x2, v) = (x * x, grid.values[row + i]);
                    sx[0] += 1.0;
                    sx[1] += x;
                    sx[2] += x2;
                    sx[3] += x2 * x;
                    sx[4] += x2 * x2;
                    sv[0] += v;
                    sv[1] += x * v;
                    sv[2] += x2 * v;
                }
            }
            if sx[0] == 0.0 {
                continue;
            }
            let (px, r) = row_factors(scaled(j, ny), scaled(kz, nz), d);
            for a in 0..k {
                atb[a] += r[a] * sv[px[a]];
                for b in a..k {
                    ata[a][b] += r[a] * r[b] * sx[px[a] + px[b]];
                }
            }
        }
    }
    let ata = DMatrix::<f64>::from_fn(k, k, |a, b| if a <= b { ata[a][b] } else { ata[b][a] });
    let c = ata.cholesky()?.solve(&DVector::from_column_slice(&atb[..k]));
    let mut out = vec![0.0; grid.len()];
    for kz in 0..nz {
        for j in 0..ny {
            let row = grid.index(0, j, kz);
            let (px, r) = row_factors(scaled(j, ny), scaled(kz, nz), d);
            let mut q = [0.0; 3];
            for a in 0..k {
                q[px[a]] += c[a] * r[a];
            }
            for (i, &x) in xs.iter().enumerate() {
                out[row + i] = q[0] + x * (q[1] + x * q[2]);
            }
        }
    }
    Some(out)
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

    /// In 3D every one of the ten monomials is recovered (the row-wise sums give the
    /// same fit as the monomials sample by sample).
    #[test]
    fn every_monomial_in_3d() {
        let n = [9, 7, 5];
        let c = [0.3, 0.1, -0.2, 0.05, 0.4, -0.3, 0.2, 0.15, -0.1, 0.25];
        let len = n[0] * n[1] * n[2];
        let at = |p: usize| {
            let x = [scaled(p % n[0], n[0]), scaled((p / n[0]) % n[1], n[1]), scaled(p / (n[0] * n[1]), n[2])];
            let (m, k) = monomials(x, 3);
            (0..k).map(|a| m[a] * c[a]).sum::<f64>()
        };
        let g = Grid::new(3, n, (0..len).map(at).collect(), SampleKind::F32);
        let mask: Vec<bool> = (0..len).map(|p| p % 3 != 0).collect();
        let b = quadratic_background(&g, &mask).unwrap();
        for (p, v) in b.iter().enumerate() {
            assert!((v - at(p)).abs() < 1e-10, "{p}: {v} {}", at(p));
        }
    }
}
