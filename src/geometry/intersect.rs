//! Intersections among the segments of curves, found in expected `O(N)` time by
//! spatial hashing: every segment is entered in the cells of a uniform grid (cell
//! size the mean segment length) that its bounding box covers, and only segments
//! sharing a cell are tested.

use super::Point;
use std::collections::{HashMap, HashSet};

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
    if segments.len() < 2 {
        return Vec::new();
    }
    let total: f64 = segments.iter().map(|s| (points[s[1]] - points[s[0]]).norm()).sum();
    let cell = (total / segments.len() as f64).max(1e-300);
    let key = |x: f64| (x / cell).floor() as i64;
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::with_capacity(2 * segments.len());
    for (i, s) in segments.iter().enumerate() {
        let (p, q) = (points[s[0]], points[s[1]]);
        let (x0, x1) = (key(p.x.min(q.x)), key(p.x.max(q.x)));
        let (y0, y1) = (key(p.y.min(q.y)), key(p.y.max(q.y)));
        for cx in x0..=x1 {
            for cy in y0..=y1 {
                grid.entry((cx, cy)).or_default().push(i);
            }
        }
    }
    let mut tested: HashSet<(usize, usize)> = HashSet::new();
    let mut hits = Vec::new();
    for list in grid.values() {
        for (k, &i) in list.iter().enumerate() {
            for &j in &list[k + 1..] {
                let (a, b) = if i < j { (i, j) } else { (j, i) };
                if !tested.insert((a, b)) {
                    continue;
                }
                if let Some(h) = intersect_pair(points, segments, a, b) {
                    hits.push(h);
                }
            }
        }
    }
    hits.sort_by(|x, y| (x.a, x.b).cmp(&(y.a, y.b)));
    hits
}

fn cross(u: Point<2>, v: Point<2>) -> f64 {
    u.x * v.y - u.y * v.x
}

fn intersect_pair(points: &[Point<2>], segments: &[[usize; 2]], a: usize, b: usize) -> Option<SegmentHit> {
    let (sa, sb) = (segments[a], segments[b]);
    let shares = sa[0] == sb[0] || sa[0] == sb[1] || sa[1] == sb[0] || sa[1] == sb[1];
    let (p, r) = (points[sa[0]], points[sa[1]] - points[sa[0]]);
    let (q, w) = (points[sb[0]], points[sb[1]] - points[sb[0]]);
    let denom = cross(r, w);
    let qp = q - p;
    let scale = r.norm() * w.norm();
    if denom.abs() <= 1e-14 * scale {
        // Parallel: report only collinear overlaps of positive length.
        if cross(qp, r).abs() > 1e-12 * r.norm() * (qp.norm() + r.norm()) {
            return None;
        }
        let rr = r.dot(&r);
        let t0 = qp.dot(&r) / rr;
        let t1 = t0 + w.dot(&r) / rr;
        let (lo, hi) = (t0.min(t1).max(0.0), t0.max(t1).min(1.0));
        let overlap = (hi - lo) * rr.sqrt();
        if overlap > 1e-12 * r.norm() {
            let s = 0.5 * (lo + hi);
            let point = p + r * s;
            let t = ((point - q).dot(&w) / w.dot(&w)).clamp(0.0, 1.0);
            return Some(SegmentHit { a, b, s, t, point });
        }
        return None;
    }
    if shares {
        return None;
    }
    let s = cross(qp, w) / denom;
    let t = cross(qp, r) / denom;
    if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
        Some(SegmentHit { a, b, s, t, point: p + r * s })
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
