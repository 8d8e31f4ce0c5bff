//! The exact certificates of the patch search: a patch, a group or a seam
//! projects one to one onto a coordinate plane (module documentation of
//! [`super`]).

use super::super::Point;
use robust::{orient2d, Coord};

/// The plane (the axis dropped, and whether the triangles project
/// counterclockwise) over which the disk patch of triangles `slots` and
/// boundary loop `lp` (vertices of `x`) is proved to project one to one:
/// `preferred` (the patch's class: then the patches of a group share it), or
/// else the coordinate plane most nearly parallel to it (module documentation).
pub(super) fn embedded(
    x: &[Point<3>],
    slots: &[[usize; 3]],
    lp: &[usize],
    preferred: (usize, bool),
) -> Option<(usize, bool)> {
    let over = |(k, ccw): (usize, bool)| {
        let at = |p: &Point<3>| flat(k, p);
        let sign = if ccw { 1.0 } else { -1.0 };
        slots.iter().all(|&[a, b, c]| orient2d(at(&x[a]), at(&x[b]), at(&x[c])) * sign > 0.0)
            && loop_projects_simple(x, lp, k, ccw)
    };
    if over(preferred) {
        return Some(preferred);
    }
    // the area vector, a sum over the boundary loop
    let o = x[lp[0]];
    let n = (0..lp.len())
        .fold(nalgebra::Vector3::zeros(), |n, i| n + (x[lp[i]] - o).cross(&(x[lp[(i + 1) % lp.len()]] - o)));
    let k = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    let plane = (k, n[k] > 0.0);
    (n[k] != 0.0 && plane != preferred && over(plane)).then_some(plane)
}

/// An edge of a loop: its index, its ends and its extent along x.
type Edge = (usize, Coord<f64>, Coord<f64>, f64, f64);

/// Whether the loop `lp` (vertices of `x`) projects along axis `k` to a simple
/// loop; `ccw`: the orientation it should have, tried first by a cheaper test.
pub(super) fn loop_projects_simple(x: &[Point<3>], lp: &[usize], k: usize, ccw: bool) -> bool {
    let pts: Vec<Coord<f64>> = lp.iter().map(|&v| flat(k, &x[v])).collect();
    star_simple(&pts, ccw) || simple_loop(&pts)
}

/// Whether the closed polygon through `pts` turns once around the mean of its
/// corners `c` with every edge seen from `c` turning the same way (`ccw`:
/// counterclockwise), decided exactly for that `c`: then every ray from `c`
/// meets it once, and it is simple. `false` says nothing.
pub(super) fn star_simple(pts: &[Coord<f64>], ccw: bool) -> bool {
    let b = pts.len();
    if b < 3 {
        return false;
    }
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(sx, sy), p| (sx + p.x, sy + p.y));
    let c = Coord { x: sx / b as f64, y: sy / b as f64 };
    let sign = if ccw { 1.0 } else { -1.0 };
    let mut turns = 0;
    for i in 0..b {
        let (p, q) = (pts[i], pts[if i + 1 == b { 0 } else { i + 1 }]);
        if orient2d(c, p, q) * sign <= 0.0 {
            return false;
        }
        // crossings of the line through c along x, going round the way of sign
        // (each on the ray from c to one side, the edges turning one way)
        turns += usize::from(if ccw { p.y < c.y && c.y <= q.y } else { p.y >= c.y && c.y > q.y });
    }
    turns == 1
}

/// A point projected along axis `k`: the coordinates in cyclic order after `k`
/// (so that `orient2d` is the `k`-th component of the area vector).
pub(super) fn flat(k: usize, p: &Point<3>) -> Coord<f64> {
    Coord { x: p[(k + 1) % 3], y: p[(k + 2) % 3] }
}

/// Whether the closed polygon through `pts` is simple: no two of its edges meet
/// but consecutive ones, at their common corner only (decided exactly).
pub(super) fn simple_loop(pts: &[Coord<f64>]) -> bool {
    let b = pts.len();
    if b < 3 {
        return false;
    }
    let next = |i: usize| if i + 1 == b { 0 } else { i + 1 };
    // the edges (index, ends, extent along x), by their left end
    let mut edges: Vec<Edge> = (0..b)
        .map(|i| {
            let (p, q) = (pts[i], pts[next(i)]);
            (i, p, q, p.x.min(q.x), p.x.max(q.x))
        })
        .collect();
    edges.sort_unstable_by(|e, f| e.3.total_cmp(&f.3));
    for (m, &(i, p, q, _, right)) in edges.iter().enumerate() {
        for &(j, r, s, left, _) in &edges[m + 1..] {
            if left > right {
                break;
            }
            let meet = if j == next(i) {
                folds_back(p, q, s)
            } else if i == next(j) {
                folds_back(r, s, q)
            } else {
                p.y.max(q.y) >= r.y.min(s.y) && r.y.max(s.y) >= p.y.min(q.y) && segments_meet(p, q, r, s)
            };
            if meet {
                return false;
            }
        }
    }
    true
}

/// Whether the edges `p q` and `q r` overlap beyond `q`: collinear, `r` on the
/// side of `q` where `p` lies.
pub(super) fn folds_back(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>) -> bool {
    if orient2d(p, q, r) != 0.0 {
        return false;
    }
    let side = |a: f64, b: f64| sign(a - b);
    let (sp, sr) = match p.x != q.x {
        true => (side(p.x, q.x), side(r.x, q.x)),
        false => (side(p.y, q.y), side(r.y, q.y)),
    };
    sp * sr >= 0
}

/// Whether the closed segments `p q` and `r s` meet.
pub(super) fn segments_meet(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>, s: Coord<f64>) -> bool {
    let (d1, d2) = (sign(orient2d(p, q, r)), sign(orient2d(p, q, s)));
    if d1 == 0 && d2 == 0 {
        // on one line: their extents overlap
        let over = |a: f64, b: f64, c: f64, d: f64| a.min(b) <= c.max(d) && c.min(d) <= a.max(b);
        return over(p.x, q.x, r.x, s.x) && over(p.y, q.y, r.y, s.y);
    }
    let (d3, d4) = (sign(orient2d(r, s, p)), sign(orient2d(r, s, q)));
    d1 * d2 <= 0 && d3 * d4 <= 0
}

/// The sign of `v`: -1, 0 (either zero) or 1.
fn sign(v: f64) -> i8 {
    (v > 0.0) as i8 - (v < 0.0) as i8
}
