//! One component of a curve as a lifted polyline, and the per-vertex kernels of its
//! management (paper §4.1): segment lengths and turning angles, the sizes the
//! regularization aims at, and the area-preserving regularization sweep.
//!
//! Every pass here costs a few square roots or divisions per vertex, the units of a
//! CPU that do not pipeline. The lengths, angles, sizes and the sweep are written
//! as loops over plain slices without branches (the sweep over the vertices of one
//! colour at a time), so that they run as vector loops: two lanes on any x86-64,
//! four where the CPU has AVX2, for which these functions are compiled a second time
//! and picked at run time (`multiversion`; no fused multiply–adds are formed, so
//! both versions give the same numbers).

use super::intersect::cross;
use super::Point;

mod collapse;
mod regularize;

pub(super) use regularize::regularize_loop;

/// One component as a polyline: its points and the shift of the closing segment
/// (from the last point to `first + shift`; nonzero for a component winding around
/// a periodic mesh).
#[derive(Debug, Clone)]
pub(super) struct Loop {
    pub(super) p: Vec<Point<2>>,
    pub(super) shift: Point<2>,
}

impl Loop {
    pub(super) fn len(&self) -> usize {
        self.p.len()
    }

    /// Point `k` for `−n ≤ k < 2n`, continued across the closing segment.
    #[inline]
    pub(super) fn at(&self, k: isize) -> Point<2> {
        let n = self.p.len() as isize;
        if k < 0 {
            self.p[(k + n) as usize] - self.shift
        } else if k >= n {
            self.p[(k - n) as usize] + self.shift
        } else {
            self.p[k as usize]
        }
    }
}

/// Signed area enclosed by the closed polygon `l` (positive counterclockwise).
pub fn loop_area(l: &[Point<2>]) -> f64 {
    (0..l.len()).map(|k| 0.5 * cross(l[k], l[(k + 1) % l.len()])).sum()
}

/// Segment lengths and turning angles of a loop: `len[i] = |d_i|`, `d_i = X_{i+1} − X_i`
/// (the last one the closing segment), and at every vertex the turning angle as the
/// chord `|t_i − t_{i−1}|` of the adjacent unit tangents (`2 sin(β/2)`: the angle
/// itself for small angles, monotone in it, free of trigonometric calls), computed as
/// `|l_{i−1} d_i − l_i d_{i−1}| / (l_{i−1} l_i)`. A zero-length segment has no
/// tangent (taken as zero): its neighbours turn by 1.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn metrics(l: &Loop) -> (Vec<f64>, Vec<f64>) {
    let n = l.len();
    if n == 0 {
        return (Vec::new(), Vec::new());
    }
    let closing = l.p[0] + l.shift - l.p[n - 1];
    let (mut dx, mut dy) = (Vec::with_capacity(n), Vec::with_capacity(n));
    dx.extend(l.p.windows(2).map(|w| w[1].x - w[0].x));
    dy.extend(l.p.windows(2).map(|w| w[1].y - w[0].y));
    dx.push(closing.x);
    dy.push(closing.y);
    let len: Vec<f64> = dx.iter().zip(&dy).map(|(x, y)| (x * x + y * y).sqrt()).collect();
    let turn = |(x0, y0, l0): (f64, f64, f64), (x1, y1, l1): (f64, f64, f64)| {
        let (u, v) = (l0 * x1 - l1 * x0, l0 * y1 - l1 * y0);
        let q = l0 * l1;
        let chord = (u * u + v * v).sqrt() / q;
        if q > 0.0 {
            chord
        } else if l0 > 0.0 || l1 > 0.0 {
            1.0
        } else {
            0.0
        }
    };
    let mut beta = Vec::with_capacity(n);
    beta.push(turn((dx[n - 1], dy[n - 1], len[n - 1]), (dx[0], dy[0], len[0])));
    let before = dx[..n - 1].iter().zip(&dy[..n - 1]).zip(&len[..n - 1]);
    let after = dx[1..].iter().zip(&dy[1..]).zip(&len[1..]);
    beta.extend(before.zip(after).map(|(((&x0, &y0), &l0), ((&x1, &y1), &l1))| turn((x0, y0, l0), (x1, y1, l1))));
    (len, beta)
}

/// The lengths the regularization aims at stay in `[1.25 h_min, 0.8 h_max]`: a
/// margin inside the limits of adaptivity, so that motion does not trip it.
pub(super) fn size_bounds(s: &super::CurveRemeshSettings) -> (f64, f64) {
    (1.25 * s.h_min, 0.8 * s.h_max)
}

/// Sizes for the regularization, from the lengths and turning angles of a loop.
///
/// With `a_S = ε h_S / β_S = ε/κ_S` (`h_S` the mean of the two segments at `S`),
/// the shape `clamp(a_S, h_min, h_max)` is small in curved parts and large where the
/// curve is nearly straight. The sizes are `clamp(c·shape, 1.25 h_min, cap_S)` with
/// the scale `c` for which they add up to the loop's length, and
/// `cap_S = clamp(0.8 √a_S, 1.25 h_min, 0.8 h_max)`: a segment of length `h` at
/// curvature `κ` turns by `β ≈ κh`, so `√(ε/κ)` is where adaptivity would split it
/// (`hβ > ε`), as `h_max` is for straight parts. Aimed at lengths the loop can have
/// and inside both limits, the regularization does not push segments to be split
/// (merged) again at the next step — a 10k-vertex curve was re-meshed at 30 of 40
/// steps, and then at a single segment every few steps, before.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn desired_sizes(len: &[f64], beta: &[f64], s: &super::CurveRemeshSettings) -> Vec<f64> {
    let n = len.len();
    if n == 0 {
        return Vec::new();
    }
    let total = sum(len);
    let (lo, hi) = size_bounds(s);
    let (h_min, h_max, eps) = (s.h_min, s.h_max, s.epsilon);
    // plain comparisons instead of min/max (which handle NaN, and do not vectorize);
    // `b = 0` gives `a = ∞`, or NaN if both segments are empty: both clamp to the
    // upper limits below
    let inverse_curvature = |l0: f64, l1: f64, b: f64| eps * 0.5 * (l0 + l1) / b;
    let cap_of = |a: f64| {
        let cap = 0.8 * a.sqrt();
        let cap = if cap < hi { cap } else { hi };
        if cap > lo {
            cap
        } else {
            lo
        }
    };
    let shape_of = |a: f64| {
        let shape = if a < h_max { a } else { h_max };
        if shape > h_min {
            shape
        } else {
            h_min
        }
    };
    let (mut cap, mut shape) = (vec![0.0; n], vec![0.0; n]);
    let a = inverse_curvature(len[n - 1], len[0], beta[0]);
    (cap[0], shape[0]) = (cap_of(a), shape_of(a));
    let neighbours = len[..n - 1].iter().zip(&len[1..]).zip(&beta[1..]);
    for ((c, r), ((&l0, &l1), &b)) in cap[1..].iter_mut().zip(&mut shape[1..]).zip(neighbours) {
        let a = inverse_curvature(l0, l1, b);
        (*c, *r) = (cap_of(a), shape_of(a));
    }
    if sum(&cap) <= total {
        return cap;
    }
    if n as f64 * lo >= total {
        return vec![lo; n];
    }
    // Newton on the piecewise linear, nondecreasing Σ clamp(c shape, lo, cap) − total,
    // to 1e-3 of the length (only ratios and the clamping matter), four lanes at a time
    let clamp = |h: f64, cap: f64| {
        if h <= lo {
            lo
        } else if h < cap {
            h
        } else {
            cap
        }
    };
    let mut c = total / sum(&shape);
    for _ in 0..30 {
        let (mut acc, mut slope) = ([0.0; 4], [0.0; 4]);
        let (r4, c4) = (shape.chunks_exact(4), cap.chunks_exact(4));
        let (r_tail, c_tail) = (r4.remainder(), c4.remainder());
        for (r, k) in r4.zip(c4) {
            for j in 0..4 {
                let h = c * r[j];
                acc[j] += clamp(h, k[j]);
                slope[j] += if h > lo && h < k[j] { r[j] } else { 0.0 };
            }
        }
        for (&r, &k) in r_tail.iter().zip(c_tail) {
            let h = c * r;
            acc[0] += clamp(h, k);
            slope[0] += if h > lo && h < k { r } else { 0.0 };
        }
        let (f, slope) = (acc.iter().sum::<f64>() - total, slope.iter().sum::<f64>());
        if slope == 0.0 {
            break;
        }
        let next = (c - f / slope).max(0.5 * c);
        c = next;
        if f.abs() <= 1e-3 * total {
            break;
        }
    }
    for (r, &k) in shape.iter_mut().zip(&cap) {
        *r = clamp(c * *r, k);
    }
    shape
}

/// `Σ x`, four lanes at a time.
fn sum(x: &[f64]) -> f64 {
    let chunks = x.chunks_exact(4);
    let tail: f64 = chunks.remainder().iter().sum();
    let lanes = chunks.fold([0.0; 4], |mut a, c| {
        for j in 0..4 {
            a[j] += c[j];
        }
        a
    });
    lanes.iter().sum::<f64>() + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_a_regular_polygon_and_of_repeated_points() {
        let n = 12;
        let pts: Vec<Point<2>> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                Point::<2>::new(2.0 * t.cos(), 2.0 * t.sin())
            })
            .collect();
        let (len, beta) = metrics(&Loop { p: pts.clone(), shift: Point::<2>::zeros() });
        let side = 4.0 * (std::f64::consts::PI / n as f64).sin();
        let chord = 2.0 * (std::f64::consts::PI / n as f64).sin(); // 2 sin(β/2), β = 2π/n
        assert!(len.iter().all(|l| (l - side).abs() < 1e-14), "{len:?}");
        assert!(beta.iter().all(|b| (b - chord).abs() < 1e-14), "{beta:?}");
        // a repeated point: the zero segment has no tangent
        let mut rep = pts;
        rep.insert(3, rep[3]);
        let (len, beta) = metrics(&Loop { p: rep, shift: Point::<2>::zeros() });
        assert_eq!(len[3], 0.0);
        assert_eq!((beta[3], beta[4]), (1.0, 1.0));
        assert!((beta[2] - chord).abs() < 1e-14 && (beta[5] - chord).abs() < 1e-14);
    }

    #[test]
    fn desired_sizes_fill_the_loop_within_both_limits() {
        // lengths and angles of an ellipse-like loop: curved ends, straight sides
        let n = 400;
        let len = vec![0.01; n];
        let beta: Vec<f64> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                0.002 + 0.05 * t.cos().powi(8)
            })
            .collect();
        let s = crate::geometry::CurveRemeshSettings {
            epsilon: 2e-4,
            h_min: 0.002,
            h_max: 0.04,
            min_area: 0.0,
            keep_area: false,
            fill_pockets: false,
            keep_apart: false,
        };
        let hd = desired_sizes(&len, &beta, &s);
        let total: f64 = hd.iter().sum();
        assert!((total - 4.0).abs() < 1e-8, "{total}");
        for (k, (&h, &b)) in hd.iter().zip(&beta).enumerate() {
            let kappa = b / 0.01;
            assert!(h >= 1.25 * s.h_min - 1e-15 && h <= 0.8 * s.h_max + 1e-15, "{k}: {h}");
            assert!(
                h <= (0.8 * (s.epsilon / kappa).sqrt()).max(1.25 * s.h_min) + 1e-15,
                "{k}: {h} above the split size"
            );
        }
        // curved parts get smaller sizes than straight ones
        assert!(hd[0] < 0.6 * hd[n / 4], "{} {}", hd[0], hd[n / 4]);
    }

    /// The sweep vertex by vertex in red–black order, written plainly: vertex `k`
    /// to the foot of `X_{k−1} + λ' c` on its chord, `λ'` clamped so that both
    /// segments lie in `[lo, hi]` where the chord allows (½ where it does not).
    fn reference_sweep(l: &mut Loop, hd: &[f64], (lo, hi): (f64, f64)) {
        let n = l.len();
        let order = (0..n - n % 2).step_by(2).chain((1..n).step_by(2)).chain((n % 2 == 1).then_some(n - 1));
        for k in order {
            let (prev, next) = (l.at(k as isize - 1), l.at(k as isize + 1));
            let (hp, h, hn) = (hd[(k + n - 1) % n], hd[k], hd[(k + 1) % n]);
            let c = next - prev;
            let cl = c.norm();
            let (a, b) = (lo.max(cl - hi) / cl, hi.min(cl - lo) / cl);
            let lam = if a <= b { ((hp + h) / (hp + 2.0 * h + hn)).clamp(a, b) } else { 0.5 };
            let x = l.p[k];
            l.p[k] = x + c * ((prev + c * lam - x).dot(&c) / c.dot(&c));
        }
    }

    #[test]
    fn the_coloured_sweep_is_the_plain_red_black_sweep() {
        for n in [3, 4, 5, 8, 13, 64, 101] {
            // an uneven loop winding once around a period of (2, 0)
            let p: Vec<Point<2>> = (0..n)
                .map(|k| {
                    let u = (k as f64 + 0.4 * (k as f64 * 1.7).sin()) / n as f64;
                    Point::<2>::new(2.0 * u, 0.3 * (std::f64::consts::TAU * u).sin() + 0.05 * (k % 3) as f64)
                })
                .collect();
            let l = Loop { p, shift: Point::<2>::new(2.0, 0.0) };
            let hd: Vec<f64> = (0..n).map(|k| 1.0 + 0.5 * ((k * 7) % 5) as f64).collect();
            let bounds = (0.6 / n as f64, 3.0 / n as f64);
            let (mut fast, mut plain) = (l.clone(), l.clone());
            regularize_loop(&mut fast, &hd, 3, Some(bounds));
            for _ in 0..3 {
                reference_sweep(&mut plain, &hd, bounds);
            }
            for (k, (a, b)) in fast.p.iter().zip(&plain.p).enumerate() {
                assert!((a - b).norm() < 1e-13, "n = {n}, vertex {k}: {a} vs {b}");
            }
            // and the moves kept the area between the curve and the axis
            let area = |q: &[Point<2>]| {
                let closed: Vec<Point<2>> = q.iter().copied().chain([q[0] + l.shift]).collect();
                closed.windows(2).map(|w| 0.5 * (w[0].y + w[1].y) * (w[1].x - w[0].x)).sum::<f64>()
            };
            assert!((area(&fast.p) - area(&l.p)).abs() < 1e-14, "n = {n}");
        }
    }
}
