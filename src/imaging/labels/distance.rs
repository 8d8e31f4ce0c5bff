//! The Euclidean distance transform of a mask (Felzenszwalb–Huttenlocher, one
//! axis at a time), with anisotropic sample spacings.

use super::Dims;

/// The 1D squared distance transform of sampled function `f` with sample spacing
/// `h` (Felzenszwalb–Huttenlocher): `d(q) = min_p (h²(q − p)² + f(p))`.
fn squared_distance_1d(f: &[f64], h: f64, d: &mut [f64], v: &mut Vec<usize>, z: &mut Vec<f64>) {
    let n = f.len();
    v.clear();
    z.clear();
    let h2 = h * h;
    let inter = |p: usize, q: usize| {
        ((f[q] / h2 + (q * q) as f64) - (f[p] / h2 + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 0..n {
        if f[q] == f64::INFINITY {
            continue;
        }
        loop {
            match v.last() {
                Some(&p) if inter(p, q) <= *z.last().unwrap() => {
                    v.pop();
                    z.pop();
                }
                Some(&p) => {
                    z.push(inter(p, q));
                    break;
                }
                None => {
                    z.push(f64::NEG_INFINITY);
                    break;
                }
            }
        }
        v.push(q);
    }
    if v.is_empty() {
        d.iter_mut().for_each(|x| *x = f64::INFINITY);
        return;
    }
    z.push(f64::INFINITY);
    let mut k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *dq = h2 * (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// [`squared_distance_1d`] of a line of zeros and infinities, in place (the
/// same values): two sweeps, the number of steps to the nearest zero on the
/// left, then on either side.
fn squared_distance_to_zeros(line: &mut [f64], h: f64) {
    let mut steps = f64::INFINITY;
    for x in line.iter_mut() {
        steps = if *x == 0.0 { 0.0 } else { steps + 1.0 };
        *x = steps;
    }
    let (h2, mut steps) = (h * h, f64::INFINITY);
    for x in line.iter_mut().rev() {
        steps = if *x == 0.0 { 0.0 } else { steps + 1.0 };
        let k = x.min(steps);
        *x = h2 * (k * k);
    }
}

/// Euclidean distance from each sample of `mask` to the nearest sample outside it
/// (0 outside), with sample spacings `spacing` per axis; samples beyond the grid
/// count as outside.
pub fn distance_transform(mask: &[bool], dims: Dims, spacing: [f64; 3]) -> Vec<f64> {
    // pad by one background sample on every side of the used axes
    let used: Vec<usize> = (0..3).filter(|&a| dims[a] > 1 || a < 2).collect();
    let pd: Dims = std::array::from_fn(|a| if used.contains(&a) { dims[a] + 2 } else { dims[a] });
    let off = |a: usize| used.contains(&a) as usize;
    let total = pd[0] * pd[1] * pd[2];
    let mut g = vec![0.0; total];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                if mask[i + dims[0] * (j + dims[1] * k)] {
                    g[(i + off(0)) + pd[0] * ((j + off(1)) + pd[1] * (k + off(2)))] = f64::INFINITY;
                }
            }
        }
    }
    let (mut v, mut z) = (Vec::new(), Vec::new());
    // lines along `a` start at `low + n·stride·high` (`low < stride`); they are
    // taken `BLOCK` neighbouring lines at a time, so that every read and write
    // uses whole cache lines
    const BLOCK: usize = 8;
    for &a in &used {
        let n = pd[a];
        let stride: usize = pd[..a].iter().product();
        let (mut lines, mut out) = (vec![0.0; BLOCK * n], vec![0.0; n]);
        for high in 0..total / (n * stride) {
            for low in (0..stride).step_by(BLOCK) {
                let width = BLOCK.min(stride - low);
                let base = low + n * stride * high;
                for t in 0..n {
                    let row = &g[base + t * stride..base + t * stride + width];
                    for (b, &x) in row.iter().enumerate() {
                        lines[b * n + t] = x;
                    }
                }
                for b in 0..width {
                    let line = &mut lines[b * n..(b + 1) * n];
                    if a == used[0] {
                        // the first pass sees only 0 and ∞: the distance to the nearest 0
                        squared_distance_to_zeros(line, spacing[a]);
                    } else if line.iter().any(|&x| x > 0.0) {
                        squared_distance_1d(line, spacing[a], &mut out, &mut v, &mut z);
                        line.copy_from_slice(&out);
                    }
                }
                for t in 0..n {
                    let row = &mut g[base + t * stride..base + t * stride + width];
                    for (b, x) in row.iter_mut().enumerate() {
                        *x = lines[b * n + t];
                    }
                }
            }
        }
    }
    let mut d = vec![0.0; mask.len()];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                d[i + dims[0] * (j + dims[1] * k)] =
                    g[(i + off(0)) + pd[0] * ((j + off(1)) + pd[1] * (k + off(2)))].sqrt();
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::super::disc_mask;
    use super::*;

    /// In 3D with anisotropic spacing, on a grid whose lines do not fill whole
    /// blocks: the exact distance to the nearest sample outside.
    #[test]
    fn distance_transform_in_3d_matches_the_brute_force() {
        let dims = [11, 10, 9];
        let spacing = [1.0, 1.5, 2.0];
        let at = |p: usize| [(p % 11) as isize, ((p / 11) % 10) as isize, (p / 110) as isize];
        let mask: Vec<bool> = (0..990)
            .map(|p| {
                let [i, j, k] = at(p).map(|c| c as f64);
                (i - 5.0).powi(2) / 16.0 + (j - 4.5).powi(2) / 12.0 + (k - 4.0).powi(2) / 9.0 < 1.0
                    || (i, j) == (2.0, 7.0)
            })
            .collect();
        let d = distance_transform(&mask, dims, spacing);
        for p in 0..990 {
            let mut want: f64 = 0.0;
            if mask[p] {
                want = f64::INFINITY;
                let c = at(p);
                for x in -1..=11isize {
                    for y in -1..=10isize {
                        for z in -1..=9isize {
                            let inside = (0..11).contains(&x) && (0..10).contains(&y) && (0..9).contains(&z);
                            if !inside || !mask[x as usize + 11 * (y as usize + 10 * z as usize)] {
                                let r = [x - c[0], y - c[1], z - c[2]];
                                let d2: f64 = (0..3).map(|a| (r[a] as f64 * spacing[a]).powi(2)).sum();
                                want = want.min(d2.sqrt());
                            }
                        }
                    }
                }
            }
            assert!((d[p] - want).abs() < 1e-12, "sample {p}: {} against {want}", d[p]);
        }
    }

    #[test]
    fn distance_transform_matches_the_brute_force() {
        let (w, h) = (40, 30);
        let m = disc_mask(w, h, &[(15.0, 14.0, 9.0), (28.0, 16.0, 7.0)]);
        let d = distance_transform(&m, [w, h, 1], [1.0, 1.0, 1.0]);
        for p in 0..w * h {
            let want = if !m[p] {
                0.0
            } else {
                let (i, j) = ((p % w) as isize, (p / w) as isize);
                let mut best = f64::INFINITY;
                for y in -1..=h as isize {
                    for x in -1..=w as isize {
                        let outside =
                            x < 0 || y < 0 || x >= w as isize || y >= h as isize || !m[x as usize + w * y as usize];
                        if outside {
                            best = best.min(((x - i) as f64).hypot((y - j) as f64));
                        }
                    }
                }
                best
            };
            assert!((d[p] - want).abs() < 1e-9, "{p}: {} {want}", d[p]);
        }
    }
}
