//! Intersections among the segments of curves, found in expected `O(N)` time by
//! spatial hashing: every segment is entered in the cells of a uniform grid (cell
//! size the mean segment length) that its bounding box covers, and only segments
//! sharing a cell are tested.

use super::Point;

mod run_grid;

pub(super) use run_grid::{pack, RunGrid};

/// Two segments that intersect: their indices (`a < b`), the parameters `s, t ∈ [0, 1]`
/// of the intersection point along each, and the point itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentHit {
    pub a: usize,
    pub b: usize,
    pub s: f64,
    pub t: f64,
    pub point: Point<2>,
}

/// All intersecting pairs among `segments` (index pairs into `points`). Segments that
/// share an endpoint index are neighbours and are not reported unless they overlap
/// collinearly. The result is sorted by `(a, b)`.
pub fn find_segment_intersections(points: &[Point<2>], segments: &[[usize; 2]]) -> Vec<SegmentHit> {
    find_with_ids(points, segments, None)
}

/// Intersections of a curve on the cylinder `R/LZ × R` (see
/// [`super::Mesh::new_periodic`]), including those with periodic images: every
/// segment is lifted to start in `0 ≤ x < L`, segments reaching past `x = L` (or
/// below 0) get a copy shifted by `∓L`, and the pairs are found among those. Hits
/// name the original segments (`a < b`), `s` and `t` are the parameters along them
/// and `point` is one representative of the crossing point modulo `L`.
pub fn find_periodic_intersections(points: &[Point<2>], segments: &[[usize; 2]], period: f64) -> Vec<SegmentHit> {
    let mut pts = Vec::with_capacity(4 * segments.len());
    let mut ids = Vec::with_capacity(4 * segments.len());
    let mut segs = Vec::with_capacity(2 * segments.len());
    let mut origin = Vec::with_capacity(2 * segments.len());
    for (e, &[a, b]) in segments.iter().enumerate() {
        let mut p = points[a];
        p.x = p.x.rem_euclid(period);
        let mut q = points[b];
        q.x += period * ((p.x - q.x) / period).round();
        let mut push = |dx: f64| {
            let k = pts.len();
            pts.push(Point::<2>::new(p.x + dx, p.y));
            pts.push(Point::<2>::new(q.x + dx, q.y));
            ids.extend([a, b]);
            segs.push([k, k + 1]);
            origin.push(e);
        };
        push(0.0);
        if q.x > period {
            push(-period);
        } else if q.x < 0.0 {
            push(period);
        }
    }
    let mut hits: Vec<SegmentHit> = find_with_ids(&pts, &segs, Some(&ids))
        .into_iter()
        .filter_map(|h| {
            let (ea, eb) = (origin[h.a], origin[h.b]);
            if ea == eb {
                return None;
            }
            let (a, b, s, t) = if ea < eb { (ea, eb, h.s, h.t) } else { (eb, ea, h.t, h.s) };
            Some(SegmentHit { a, b, s, t, point: h.point })
        })
        .collect();
    hits.sort_by_key(|h| (h.a, h.b));
    hits.dedup_by(|x, y| (x.a, x.b) == (y.a, y.b));
    hits
}

/// A segment gathered for the pair tests: its endpoints and their vertex identities.
#[derive(Debug, Clone, Copy)]
struct Seg {
    p: Point<2>,
    q: Point<2>,
    id: [usize; 2],
}

/// Whether all segments of `first..=last` point forward along the chord from the
/// first point to the last: then their projections on it increase strictly, and
/// no two of them cross (non-neighbours project to disjoint intervals, neighbours
/// cannot fold back).
pub(super) fn monotone(points: &[Point<2>], segments: &[[usize; 2]], first: usize, last: usize) -> bool {
    let u = points[segments[last][1]] - points[segments[first][0]];
    segments[first..=last].iter().all(|s| (points[s[1]] - points[s[0]]).dot(&u) > 0.0)
}

/// The finder; `ids` (if given) maps point indices to vertex identities for the
/// test whether two segments are neighbours.
///
/// Cells of side `4 h̄` (`h̄` the mean segment length); every segment belongs to the
/// cells its bounding box meets, and a crossing point lies in a cell that both
/// crossing segments meet. Walking the segments in order, the segments meeting a
/// cell form runs of consecutive segments ([`RunGrid`]). A [`monotone`] run cannot
/// cross itself; other runs are tested pair by pair. Pairs from different runs of
/// one cell (the curve passing twice, or two components) are always tested. On a
/// smooth curve a cell holds one monotone run, and the work is one pass over the
/// segments with a table lookup per run rather than per segment.
fn find_with_ids(points: &[Point<2>], segments: &[[usize; 2]], ids: Option<&[usize]>) -> Vec<SegmentHit> {
    if segments.len() < 2 {
        return Vec::new();
    }
    find_on_grid(points, segments, ids, &RunGrid::build(points, segments, ids))
}

/// [`find_segment_intersections`] that also returns the grid it used.
pub(super) fn find_with_grid(points: &[Point<2>], segments: &[[usize; 2]]) -> (Vec<SegmentHit>, RunGrid) {
    let grid = RunGrid::build(points, segments, None);
    let hits = if segments.len() < 2 { Vec::new() } else { find_on_grid(points, segments, None, &grid) };
    (hits, grid)
}

/// A cell holding more segments than this is searched on a finer grid of its own
/// (cells scaled to those segments' mean length), so that many short segments in
/// one cell (a strongly graded curve, or a zigzag of tiny segments beside long
/// ones) cost about linear time, not quadratic.
const DENSE: usize = 128;
/// Levels of such refinement; below them a dense cell is tested pair by pair
/// (segments that stay together at every scale mostly meet anyway).
const MAX_DEPTH: u32 = 4;

fn find_on_grid(
    points: &[Point<2>],
    segments: &[[usize; 2]],
    ids: Option<&[usize]>,
    grid: &RunGrid,
) -> Vec<SegmentHit> {
    find_at_depth(points, segments, ids, grid, 0)
}

/// The pairs among the segments of a dense cell, on a grid of their own.
fn find_in_cell(
    points: &[Point<2>],
    segments: &[[usize; 2]],
    ids: Option<&[usize]>,
    mut subset: Vec<usize>,
    depth: u32,
) -> Vec<SegmentHit> {
    subset.sort_unstable();
    subset.dedup();
    let local: Vec<[usize; 2]> = subset.iter().map(|&e| segments[e]).collect();
    let grid = RunGrid::build(points, &local, ids);
    let mut hits = find_at_depth(points, &local, ids, &grid, depth + 1);
    for h in &mut hits {
        // `subset` is increasing, so local a < b stays global a < b
        (h.a, h.b) = (subset[h.a], subset[h.b]);
    }
    hits
}

fn find_at_depth(
    points: &[Point<2>],
    segments: &[[usize; 2]],
    ids: Option<&[usize]>,
    grid: &RunGrid,
    depth: u32,
) -> Vec<SegmentHit> {
    let id = |v: usize| ids.map_or(v, |ids| ids[v]);
    let seg = |e: usize| {
        let s = segments[e];
        Seg { p: points[s[0]], q: points[s[1]], id: [id(s[0]), id(s[1])] }
    };
    let mut hits = Vec::new();
    let test = |a: usize, b: usize, hits: &mut Vec<SegmentHit>| {
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        if let Some(h) = intersect_pair(&seg(a), &seg(b), a, b) {
            hits.push(h);
        }
    };
    let len = |o: usize| (grid.runs[o].last - grid.runs[o].first + 1) as usize;
    // cells that turned out dense and went to a grid of their own (few, usually none)
    let mut dense: std::collections::HashSet<u64> = std::collections::HashSet::new();
    let mut earlier: Vec<usize> = Vec::new();
    for (k, r) in grid.runs.iter().enumerate() {
        if !dense.is_empty() && dense.contains(&r.cell) {
            continue;
        }
        earlier.clear();
        earlier.extend(grid.cell_runs(r.cell).filter(|&o| o < k));
        if depth < MAX_DEPTH && len(k) + earlier.iter().map(|&o| len(o)).sum::<usize>() > DENSE {
            // the whole cell, its later runs included (pairs found twice are deduplicated)
            dense.insert(r.cell);
            let mut subset = Vec::new();
            for o in grid.cell_runs(r.cell) {
                subset.extend(grid.runs[o].first as usize..=grid.runs[o].last as usize);
            }
            hits.extend(find_in_cell(points, segments, ids, subset, depth));
            continue;
        }
        let (first, last) = (r.first as usize, r.last as usize);
        // within the run
        if last > first && !monotone(points, segments, first, last) {
            for a in first..last {
                for b in a + 1..=last {
                    test(a, b, &mut hits);
                }
            }
        }
        // against the runs of its cell entered before it
        for &o in &earlier {
            let o = grid.runs[o];
            for a in o.first..=o.last {
                for b in first..=last {
                    if a as usize != b {
                        test(a as usize, b, &mut hits);
                    }
                }
            }
        }
    }
    let mut is_long = if grid.long.is_empty() { Vec::new() } else { vec![false; segments.len()] };
    for &l in &grid.long {
        is_long[l] = true;
    }
    for &l in &grid.long {
        for (other, &long) in is_long.iter().enumerate() {
            if other != l && !(long && other < l) {
                test(l, other, &mut hits);
            }
        }
    }
    hits.sort_by_key(|h| (h.a, h.b));
    hits.dedup_by(|x, y| (x.a, x.b) == (y.a, y.b));
    hits
}

/// The intersection of the segments `a` and `b` (index pairs into `points`), if
/// any, as [`find_segment_intersections`] reports it (`a` and `b` as given).
pub fn segment_pair_hit(points: &[Point<2>], a: [usize; 2], b: [usize; 2], ids: (usize, usize)) -> Option<SegmentHit> {
    let seg = |s: [usize; 2]| Seg { p: points[s[0]], q: points[s[1]], id: s };
    intersect_pair(&seg(a), &seg(b), ids.0, ids.1)
}

/// The scalar cross product `u × v`.
pub(super) fn cross(u: Point<2>, v: Point<2>) -> f64 {
    u.x * v.y - u.y * v.x
}

/// The intersection of segments `a < b`, if any. Neighbours (sharing a vertex)
/// intersect only where they overlap collinearly (a fold).
#[inline]
fn intersect_pair(sa: &Seg, sb: &Seg, a: usize, b: usize) -> Option<SegmentHit> {
    let (p, p2, q, q2) = (sa.p, sa.q, sb.p, sb.q);
    let (ia, ib) = (sa.id, sb.id);
    let shares = ia[0] == ib[0] || ia[0] == ib[1] || ia[1] == ib[0] || ia[1] == ib[1];
    if !shares
        && (p.x.max(p2.x) < q.x.min(q2.x)
            || q.x.max(q2.x) < p.x.min(p2.x)
            || p.y.max(p2.y) < q.y.min(q2.y)
            || q.y.max(q2.y) < p.y.min(p2.y))
    {
        return None;
    }
    let (r, w) = (p2 - p, q2 - q);
    if shares && r.dot(&w) > 0.0 {
        return None; // neighbours pointing the same way: no overlap
    }
    let denom = cross(r, w);
    let (rr, ww) = (r.dot(&r), w.dot(&w));
    let qp = q - p;
    if denom * denom <= 1e-28 * rr * ww {
        // parallel: report only collinear overlaps of positive length
        let c = cross(qp, r);
        if c * c > 1e-24 * rr * (qp.dot(&qp) + rr) {
            return None;
        }
        let t0 = qp.dot(&r) / rr;
        let t1 = t0 + w.dot(&r) / rr;
        let (lo, hi) = (t0.min(t1).max(0.0), t0.max(t1).min(1.0));
        if (hi - lo) > 1e-12 {
            let s = 0.5 * (lo + hi);
            let point = p + r * s;
            let t = ((point - q).dot(&w) / ww).clamp(0.0, 1.0);
            return Some(SegmentHit { a, b, s, t, point });
        }
        return None;
    }
    if shares {
        return None;
    }
    let (cs, ct) = (cross(qp, w), cross(qp, r));
    // s = cs / denom and t = ct / denom must lie in [0, 1]: signs first, no division
    let inside = |c: f64| if denom > 0.0 { c >= 0.0 && c <= denom } else { c <= 0.0 && c >= denom };
    if !(inside(cs) && inside(ct)) {
        return None;
    }
    let (s, t) = (cs / denom, ct / denom);
    if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
        Some(SegmentHit { a, b, s, t, point: p + r * s })
    } else {
        None
    }
}

#[cfg(test)]
pub(super) mod tests;
