//! Intersections among the segments of curves, found in expected `O(N)` time by
//! spatial hashing: every segment is entered in the cells of a uniform grid (cell
//! size the mean segment length) that its bounding box covers, and only segments
//! sharing a cell are tested.

use super::Point;

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
    hits.sort_by(|x, y| (x.a, x.b).cmp(&(y.a, y.b)));
    hits.dedup_by(|x, y| (x.a, x.b) == (y.a, y.b));
    hits
}

/// The finder; `ids` (if given) maps point indices to vertex identities for the
/// test whether two segments are neighbours.
fn find_with_ids(points: &[Point<2>], segments: &[[usize; 2]], ids: Option<&[usize]>) -> Vec<SegmentHit> {
    if segments.len() < 2 {
        return Vec::new();
    }
    let total: f64 = segments.iter().map(|s| (points[s[1]] - points[s[0]]).norm()).sum();
    let cell = (total / segments.len() as f64).max(1e-300);
    let inv = 1.0 / cell;
    let (mut x_lo, mut y_lo) = (f64::INFINITY, f64::INFINITY);
    for s in segments {
        for &v in s {
            x_lo = x_lo.min(points[v].x);
            y_lo = y_lo.min(points[v].y);
        }
    }
    // coordinates shifted to be nonnegative, so truncation is floor
    let key = |x: f64, lo: f64| ((x - lo) * inv) as u64;
    // (bucket, segment) pairs, bucket = hash of the cell; counting sort, O(n).
    // Segments of different cells sharing a bucket are merely tested needlessly.
    let hash =
        |cx: u64, cy: u64| (cx.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ cy.wrapping_mul(0xC2B2_AE3D_27D4_EB4F)) >> 32;
    let mut entries: Vec<(u32, u32)> = Vec::with_capacity(4 * segments.len());
    let mut long = Vec::new();
    for (i, s) in segments.iter().enumerate() {
        let (p, q) = (points[s[0]], points[s[1]]);
        let (x0, x1) = (key(p.x.min(q.x), x_lo), key(p.x.max(q.x), x_lo));
        let (y0, y1) = (key(p.y.min(q.y), y_lo), key(p.y.max(q.y), y_lo));
        if (x1 - x0 + 1) * (y1 - y0 + 1) > 64 {
            long.push(i); // far longer than the mean: tested against every segment
            continue;
        }
        for cx in x0..=x1 {
            for cy in y0..=y1 {
                entries.push((hash(cx, cy) as u32, i as u32));
            }
        }
    }
    let buckets = entries.len().next_power_of_two().max(2);
    let mask = buckets as u32 - 1;
    let mut start = vec![0u32; buckets + 1];
    for e in &entries {
        start[(e.0 & mask) as usize + 1] += 1;
    }
    for k in 0..buckets {
        start[k + 1] += start[k];
    }
    let mut sorted = vec![0u32; entries.len()];
    for e in entries.iter().rev() {
        let b = (e.0 & mask) as usize + 1;
        start[b] -= 1;
        sorted[start[b] as usize] = e.1;
    }
    // now start[b + 1] is the beginning of bucket b; shift back
    start.remove(0);
    start.push(entries.len() as u32);
    let mut hits = Vec::new();
    for k in 0..buckets {
        let (lo, hi) = (start[k] as usize, start[k + 1] as usize);
        debug_assert!(lo <= hi);
        if hi - lo < 2 {
            continue;
        }
        let bucket = &sorted[lo..hi];
        for (j, &sa) in bucket.iter().enumerate() {
            for &sb in &bucket[j + 1..] {
                let (a, b) = if sa < sb { (sa as usize, sb as usize) } else { (sb as usize, sa as usize) };
                if a != b {
                    if let Some(h) = intersect_pair(points, segments, ids, a, b) {
                        hits.push(h);
                    }
                }
            }
        }
    }
    for &l in &long {
        for other in 0..segments.len() {
            if other != l && !(long.contains(&other) && other < l) {
                let (a, b) = if l < other { (l, other) } else { (other, l) };
                if let Some(h) = intersect_pair(points, segments, ids, a, b) {
                    hits.push(h);
                }
            }
        }
    }
    // a pair sharing several cells is found once per cell
    hits.sort_by(|x, y| (x.a, x.b).cmp(&(y.a, y.b)));
    hits.dedup_by(|x, y| (x.a, x.b) == (y.a, y.b));
    hits
}

/// The scalar cross product `u × v`.
pub(super) fn cross(u: Point<2>, v: Point<2>) -> f64 {
    u.x * v.y - u.y * v.x
}

fn intersect_pair(
    points: &[Point<2>],
    segments: &[[usize; 2]],
    ids: Option<&[usize]>,
    a: usize,
    b: usize,
) -> Option<SegmentHit> {
    let (sa, sb) = (segments[a], segments[b]);
    let (p, p2) = (points[sa[0]], points[sa[1]]);
    let (q, q2) = (points[sb[0]], points[sb[1]]);
    let id = |v: usize| ids.map_or(v, |ids| ids[v]);
    let (ia, ib) = (sa.map(id), sb.map(id));
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
    let denom = cross(r, w);
    let (rr, ww) = (r.dot(&r), w.dot(&w));
    let qp = q - p;
    if denom * denom <= 1e-28 * rr * ww {
        // parallel: report only collinear overlaps of positive length
        let c = cross(qp, r);
        if c * c > 1e-24 * rr * (qp.dot(&qp) + rr) {
            return None;
        }
        if shares && r.dot(&w) > 0.0 {
            return None; // consecutive and pointing the same way: no overlap
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
