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
pub(super) mod tests {
    use super::*;

    /// Every pair, tested directly.
    fn brute_force(points: &[Point<2>], segments: &[[usize; 2]]) -> Vec<(usize, usize)> {
        let segs: Vec<Seg> = segments.iter().map(|s| Seg { p: points[s[0]], q: points[s[1]], id: *s }).collect();
        let mut out = Vec::new();
        for a in 0..segs.len() {
            for b in a + 1..segs.len() {
                if intersect_pair(&segs[a], &segs[b], a, b).is_some() {
                    out.push((a, b));
                }
            }
        }
        out
    }

    /// A tiny deterministic generator (xorshift), uniform in [0, 1).
    pub(in crate::geometry) fn rng(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Closed polylines: wiggly circles with random radii, centres and sampling, some
    /// crossing themselves (large wiggles) and each other, some with spikes that fold
    /// back onto themselves, some with repeated points.
    #[test]
    fn runs_find_exactly_the_pairs_of_the_brute_force() {
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut total_hits = 0;
        for case in 0..60 {
            let mut points = Vec::new();
            let mut segments = Vec::new();
            let components = 1 + (rng(&mut state) * 3.0) as usize;
            for _ in 0..components {
                let n = 8 + (rng(&mut state) * 300.0) as usize;
                let (cx, cy) = (rng(&mut state) * 2.0, rng(&mut state) * 2.0);
                let r = 0.3 + rng(&mut state);
                let wiggle = if case % 3 == 0 { 0.0 } else { rng(&mut state) * 0.6 };
                let k = 2.0 + (rng(&mut state) * 9.0).floor();
                let base = points.len();
                for j in 0..n {
                    let t = 2.0 * std::f64::consts::PI * (j as f64 + 0.8 * rng(&mut state)) / n as f64;
                    let rr = r * (1.0 + wiggle * (k * t).sin());
                    let mut p = Point::<2>::new(cx + rr * t.cos(), cy + rr * t.sin());
                    if case % 5 == 1 && j % 37 == 5 {
                        p = points[base + j - 2]; // a spike folding back
                    }
                    if case % 7 == 2 && j % 41 == 3 {
                        p = points[base + j - 1]; // a repeated point
                    }
                    points.push(p);
                }
                segments.extend((0..n).map(|j| [base + j, base + (j + 1) % n]));
            }
            let fast: Vec<(usize, usize)> =
                find_segment_intersections(&points, &segments).iter().map(|h| (h.a, h.b)).collect();
            let slow = brute_force(&points, &segments);
            assert_eq!(fast, slow, "case {case}");
            total_hits += slow.len();
        }
        assert!(total_hits > 100, "the cases cross: {total_hits}");
    }

    /// Many short segments in the cells of a few long ones (their mean sets the
    /// cells): a comb of tiny teeth along a long edge and a tiny random walk that
    /// crosses itself, on the refined grids of dense cells.
    #[test]
    fn dense_cells_find_exactly_the_pairs_of_the_brute_force() {
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        for case in 0..4 {
            let mut points = vec![Point::<2>::new(0.0, 0.0), Point::<2>::new(100.0, 0.0), Point::<2>::new(100.0, 50.0)];
            // the comb, from (100, 50) back to (99, 50): 1,200 segments, teeth of height 0.01
            let teeth = 600;
            for j in 0..teeth {
                let x = 100.0 - (j as f64 + 0.5) / teeth as f64;
                let h = if case % 2 == 1 && j % 97 == 13 { -0.02 } else { 0.01 }; // some teeth cross
                points.push(Point::<2>::new(x + 0.0008, 50.0));
                points.push(Point::<2>::new(x, 50.0 + h));
            }
            // a random walk of tiny steps near (0, 25)
            let mut p = Point::<2>::new(0.5, 25.0);
            for _ in 0..(300 + 200 * case) {
                p += Point::<2>::new(rng(&mut state) - 0.5, rng(&mut state) - 0.5) * 0.004;
                points.push(p);
            }
            let n = points.len();
            let segments: Vec<[usize; 2]> = (0..n).map(|j| [j, (j + 1) % n]).collect();
            let grid = RunGrid::build(&points, &segments, None);
            let mut per_cell = std::collections::HashMap::new();
            for r in &grid.runs {
                *per_cell.entry(r.cell).or_insert(0) += (r.last - r.first + 1) as usize;
            }
            assert!(per_cell.values().filter(|&&m| m > DENSE).count() >= 2, "case {case}: dense cells");
            let fast: Vec<(usize, usize)> =
                find_segment_intersections(&points, &segments).iter().map(|h| (h.a, h.b)).collect();
            let slow = brute_force(&points, &segments);
            assert_eq!(fast, slow, "case {case}");
            assert!(!slow.is_empty() || case == 0, "case {case} crosses");
        }
    }

    #[test]
    fn crossing_and_touching_pairs() {
        let pts = vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(0.0, 1.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(5.0, 5.0),
            Point::<2>::new(6.0, 5.0),
        ];
        let segs = vec![[0, 1], [2, 3], [4, 5], [1, 4]];
        let hits = find_segment_intersections(&pts, &segs);
        assert_eq!(hits.len(), 1);
        assert_eq!((hits[0].a, hits[0].b), (0, 1));
        assert!((hits[0].point - Point::<2>::new(0.5, 0.5)).norm() < 1e-14);
    }
}
