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

/// A segment gathered for the pair tests: its endpoints and their vertex identities.
#[derive(Debug, Clone, Copy)]
struct Seg {
    p: Point<2>,
    q: Point<2>,
    id: [usize; 2],
}

impl Seg {
    fn lower(&self) -> (f64, f64) {
        (self.p.x.min(self.q.x), self.p.y.min(self.q.y))
    }

    fn upper(&self) -> (f64, f64) {
        (self.p.x.max(self.q.x), self.p.y.max(self.q.y))
    }
}

/// The finder; `ids` (if given) maps point indices to vertex identities for the
/// test whether two segments are neighbours. Every segment is entered, in order, in
/// the cells its bounding box covers and tested against the segments entered there
/// before it. Cells live in a table tiled modulo its side, so that a curve walking
/// through neighbouring cells walks through neighbouring slots (cache-friendly);
/// slots shared by distant cells are told apart by the cell key. A pair is tested
/// in one cell only, the one holding the lower corner of the intersection of the
/// two bounding boxes.
fn find_with_ids(points: &[Point<2>], segments: &[[usize; 2]], ids: Option<&[usize]>) -> Vec<SegmentHit> {
    if segments.len() < 2 {
        return Vec::new();
    }
    let id = |v: usize| ids.map_or(v, |ids| ids[v]);
    let segs: Vec<Seg> =
        segments.iter().map(|s| Seg { p: points[s[0]], q: points[s[1]], id: [id(s[0]), id(s[1])] }).collect();
    let total: f64 = segs.iter().map(|s| (s.q - s.p).norm()).sum();
    let cell = (total / segs.len() as f64).max(1e-300);
    let inv = 1.0 / cell;
    let (mut x_lo, mut y_lo) = (f64::INFINITY, f64::INFINITY);
    for s in &segs {
        let (x, y) = s.lower();
        x_lo = x_lo.min(x);
        y_lo = y_lo.min(y);
    }
    // coordinates shifted to be nonnegative, so truncation is floor
    let key = |x: f64, lo: f64| ((x - lo) * inv) as u32;
    let pack = |cx: u32, cy: u32| (u64::from(cx) << 32) | u64::from(cy);
    // a square table of side 2^bits, about four slots per segment
    let bits = ((4 * segs.len()).next_power_of_two().trailing_zeros() + 1) / 2;
    let side_mask = (1u32 << bits) - 1;
    let slot_of = |cx: u32, cy: u32| (((cy & side_mask) << bits) | (cx & side_mask)) as usize;
    const NONE: u32 = u32::MAX;
    let mut head = vec![NONE; 1usize << (2 * bits)];
    // entries: cell key, segment, next entry in the same slot
    let mut entry_cell: Vec<u64> = Vec::with_capacity(3 * segs.len());
    let mut entry_seg: Vec<u32> = Vec::with_capacity(3 * segs.len());
    let mut entry_next: Vec<u32> = Vec::with_capacity(3 * segs.len());
    let mut long = Vec::new();
    let mut hits = Vec::new();
    for (i, sa) in segs.iter().enumerate() {
        let ((axl, ayl), (axu, ayu)) = (sa.lower(), sa.upper());
        let (x0, x1, y0, y1) = (key(axl, x_lo), key(axu, x_lo), key(ayl, y_lo), key(ayu, y_lo));
        if (u64::from(x1 - x0) + 1) * (u64::from(y1 - y0) + 1) > 64 {
            long.push(i); // far longer than the mean: tested against every segment
            continue;
        }
        for cx in x0..=x1 {
            for cy in y0..=y1 {
                let c = pack(cx, cy);
                let slot = slot_of(cx, cy);
                let mut e = head[slot];
                while e != NONE {
                    let k = e as usize;
                    e = entry_next[k];
                    if entry_cell[k] != c {
                        continue; // another cell sharing the slot
                    }
                    let j = entry_seg[k] as usize;
                    let sb = &segs[j];
                    let ((bxl, byl), (bxu, byu)) = (sb.lower(), sb.upper());
                    if axu < bxl || bxu < axl || ayu < byl || byu < ayl {
                        continue;
                    }
                    if pack(key(axl.max(bxl), x_lo), key(ayl.max(byl), y_lo)) != c {
                        continue; // tested in the cell of the overlap's lower corner
                    }
                    // j < i: entered earlier
                    if let Some(h) = intersect_pair(sb, sa, j, i) {
                        hits.push(h);
                    }
                }
                entry_next.push(head[slot]);
                head[slot] = entry_cell.len() as u32;
                entry_cell.push(c);
                entry_seg.push(i as u32);
            }
        }
    }
    for &l in &long {
        for other in 0..segs.len() {
            if other != l && !(long.contains(&other) && other < l) {
                let (a, b) = if l < other { (l, other) } else { (other, l) };
                if let Some(h) = intersect_pair(&segs[a], &segs[b], a, b) {
                    hits.push(h);
                }
            }
        }
    }
    hits.sort_by(|x, y| (x.a, x.b).cmp(&(y.a, y.b)));
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
