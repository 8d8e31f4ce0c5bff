//! Crossing checks of an evolving curve, skipped while a certificate from the last
//! full check proves that no two segments can have crossed since.
//!
//! At a full check without crossings ([`super::find_segment_intersections`]) the
//! segments are laid on the cells of [`RunGrid`] (side `c`). If, for every cell,
//! all runs in the 3×3 block around it lie on one closed chain within `w` segments
//! of each other (counted along the chain, the short way round), then any two
//! segments closer than `c` are within `w` of each other along the chain: a
//! point `P` of one and `Q` of the other with `|P − Q| < c` lie in cells at most one
//! apart. Later, with the same connectivity:
//!
//! - *near pairs* (within `w` along the chain) cannot cross while every turning
//!   angle is below `π/w`: the directions of a chain of at most `w + 1` segments
//!   then lie in an open half-plane, the chain is monotone along some direction,
//!   and two of its segments can meet only at a shared vertex;
//! - *far pairs* were at least `c` apart and cannot meet while no vertex has moved
//!   by `c/2` or more since (every point of a segment moves at most as far as its
//!   farther end).
//!
//! Checking both costs a comparison of the connectivity and one pass along the
//! chains (displacement and turning at every vertex), against one pass of the
//! finder with its table; the finder runs again (and a new certificate is drawn)
//! as soon as either condition fails. Any grid will do for the certificate: a
//! coarse one (cells of 32 mean segment lengths, 8× the finder's) has a larger `w`
//! and so a tighter turning bound, but lets vertices move 8× farther, and it is
//! tried first. Curves of fewer than [`SMALL`] segments get no certificate: the full
//! check costs them less.

use super::intersect::{cross, find_with_grid, pack, RunGrid};
use super::{CurveMesh, Point, SegmentHit};
use std::sync::Arc;

/// Cells of the coarse certificate, in mean segment lengths (the finder's are 4):
/// a certificate then holds while no vertex has moved by 16 of them, as long as no
/// vertex turns by more than about π/(100–150) on a smooth curve.
const COARSE_CELLS: f64 = 32.0;

/// Curves of fewer segments are checked in full at every step: the finder costs
/// them a few microseconds, less than drawing certificates that a fast-moving small
/// curve (a segmentation contour) soon outruns.
const SMALL: usize = 256;

/// What the last full check proved, if anything.
#[derive(Debug, Clone)]
struct Certificate {
    elements: Arc<[[usize; 2]]>,
    /// The closed chains, as ranges of `elements`.
    chains: Vec<std::ops::Range<usize>>,
    /// Whether segment `e` of every chain is `[e, e + 1]` (the last one closing it):
    /// chains are then also ranges of vertices.
    contiguous: bool,
    anchor: Vec<Point<2>>,
    /// Largest displacement from `anchor` the certificate allows (exclusive): `c/2`.
    reach: f64,
    /// `tan²(π/w)`: every turning angle must stay below `π/w`.
    tan2: f64,
    /// `tan²(π/2w)`.
    tan2_half: f64,
}

/// Crossing checks between the steps of one flow (see the module documentation).
#[derive(Debug, Clone, Default)]
pub struct CrossingWatch {
    certificate: Option<Certificate>,
    /// Full checks run (for tests and benchmarks).
    pub full_checks: usize,
    /// Checks answered by the certificate.
    pub skipped: usize,
}

impl CrossingWatch {
    /// All crossings among `segments` (as
    /// [`find_segment_intersections`](super::find_segment_intersections)): none if the
    /// certificate of the last full check still holds, else a full check.
    pub fn crossings(&mut self, points: &[Point<2>], segments: &[[usize; 2]]) -> Vec<SegmentHit> {
        self.check(points, segments, None)
    }

    /// [`CrossingWatch::crossings`] of a closed curve mesh. The certificate keeps
    /// the mesh's shared element list, so that the meshes of one connectivity are
    /// recognized by address instead of by comparing their elements.
    pub fn crossings_of(&mut self, mesh: &CurveMesh) -> Vec<SegmentHit> {
        self.check(mesh.positions(), mesh.elements(), Some(mesh.shared_elements()))
    }

    fn check(
        &mut self,
        points: &[Point<2>],
        segments: &[[usize; 2]],
        shared: Option<&Arc<[[usize; 2]]>>,
    ) -> Vec<SegmentHit> {
        if let Some(cert) = &self.certificate {
            if holds(cert, points, segments) {
                self.skipped += 1;
                return Vec::new();
            }
        }
        self.full_checks += 1;
        let (hits, grid) = find_with_grid(points, segments);
        self.certificate = if hits.is_empty() && segments.len() >= SMALL {
            // a coarse certificate reaches farther (a full check less often) where
            // the curve turns slowly enough; else the finder's own cells
            // (kept only if the curve turns by at most half its bound now, or it
            // would fail at once)
            let coarse = RunGrid::build_scaled(points, segments, None, COARSE_CELLS);
            let elements = || shared.cloned().unwrap_or_else(|| segments.into());
            certify(points, segments, &coarse, elements())
                .filter(|c| holds_with(c, points, segments, c.tan2_half))
                .or_else(|| certify(points, segments, &grid, elements()))
        } else {
            None
        };
        hits
    }
}

/// Whether the certificate still covers the curve `(points, segments)`: one pass
/// along the chains checks the displacement of every segment's first vertex (each
/// vertex of a closed chain is one) and the turning angle there.
fn holds(cert: &Certificate, points: &[Point<2>], segments: &[[usize; 2]]) -> bool {
    holds_with(cert, points, segments, cert.tan2)
}

/// [`holds`] with the turning bound `tan2` in place of the certificate's.
fn holds_with(cert: &Certificate, points: &[Point<2>], segments: &[[usize; 2]], tan2: f64) -> bool {
    // the certificate keeps its element list alive: at its address there can be no
    // other list
    let same = std::ptr::eq(cert.elements.as_ptr(), segments.as_ptr()) && cert.elements.len() == segments.len();
    if !(same || *cert.elements == *segments) || cert.anchor.len() != points.len() {
        return false;
    }
    let reach2 = cert.reach * cert.reach;
    // every vertex turns by less than π/w: with u, v the segments before and after,
    // u·v > 0 and (u × v)² < tan²(π/w) (u·v)² (w ≥ 2, so π/w ≤ π/2)
    let fine = |u: Point<2>, v: Point<2>, moved: Point<2>| {
        let (dot, cross) = (u.dot(&v), cross(u, v));
        (moved.norm_squared() < reach2) & (dot > 0.0) & (cross * cross < tan2 * dot * dot)
    };
    if cert.contiguous {
        // chains stored as runs of vertices: slices, no gathers, and a count
        // instead of an early exit, so that the pass runs two lanes at a time
        return cert.chains.iter().all(|r| {
            let (p, a) = (&points[r.clone()], &cert.anchor[r.clone()]);
            let m = p.len();
            let ends = [(p[m - 1], p[0], p[1], a[0]), (p[m - 2], p[m - 1], p[0], a[m - 1])];
            let bad: usize = p
                .windows(3)
                .zip(&a[1..m - 1])
                .map(|(w, &a)| usize::from(!fine(w[1] - w[0], w[2] - w[1], w[1] - a)))
                .sum();
            bad == 0 && ends.iter().all(|&(x0, x1, x2, a)| fine(x1 - x0, x2 - x1, x1 - a))
        });
    }
    cert.chains.iter().all(|r| {
        let last = segments[r.end - 1];
        let mut u = points[last[1]] - points[last[0]];
        segments[r.clone()].iter().all(|&[a, b]| {
            let v = points[b] - points[a];
            let ok = fine(u, v, points[a] - cert.anchor[a]);
            u = v;
            ok
        })
    })
}

/// The certificate of a curve without crossings, if its segments are closed
/// chains stored in order (each segment starting where the one before ended,
/// every chain closing on itself) and every 3×3 block of cells holds one stretch
/// of one chain.
fn certify(
    points: &[Point<2>],
    segments: &[[usize; 2]],
    grid: &RunGrid,
    elements: Arc<[[usize; 2]]>,
) -> Option<Certificate> {
    let n = segments.len();
    if n < 8 {
        return None;
    }
    // chains: chain[e] = (start, length) of the chain of segment e
    let mut chain = vec![(0usize, 0usize); n];
    let mut chains = Vec::new();
    let mut start = 0;
    for e in 1..=n {
        if e == n || segments[e][0] != segments[e - 1][1] {
            let len = e - start;
            if segments[e - 1][1] != segments[start][0] {
                return None; // not closed, or not in order
            }
            chain[start..e].fill((start, len));
            chains.push(start..e);
            start = e;
        }
    }
    if !grid.long.is_empty() {
        return None;
    }
    // the largest distance along a chain between segments of runs in one block
    let mut w = 1usize;
    for r in &grid.runs {
        let (cx, cy) = ((r.cell >> 32) as u32, r.cell as u32);
        let (a1, a2) = (r.first as usize, r.last as usize);
        let (base, len) = chain[a1];
        for dx in [-1i64, 0, 1] {
            for dy in [-1i64, 0, 1] {
                let (x, y) = (i64::from(cx) + dx, i64::from(cy) + dy);
                if x < 0 || y < 0 || x > i64::from(u32::MAX) || y > i64::from(u32::MAX) {
                    continue;
                }
                for o in grid.cell_runs(pack(x as u32, y as u32)) {
                    let o = grid.runs[o];
                    let (b1, b2) = (o.first as usize, o.last as usize);
                    if chain[b1].0 != base {
                        return None; // two chains in one block
                    }
                    w = w.max(span(a1 - base, a2 - base, b1 - base, b2 - base, len));
                }
            }
        }
    }
    // with w + 1 segments in a window the turning angles must stay below π/w,
    // which even a smooth curve cannot promise for windows of a quarter turn
    if 4 * w > n {
        return None;
    }
    let angle = std::f64::consts::PI / w.max(2) as f64;
    Some(Certificate {
        elements,
        contiguous: segments.iter().enumerate().all(|(e, s)| s[0] == e),
        chains,
        anchor: points.to_vec(),
        reach: 0.5 * grid.side,
        tan2: angle.tan().powi(2),
        tan2_half: (0.5 * angle).tan().powi(2),
    })
}

/// Vertices strictly inside the shortest stretch of a closed chain of `len`
/// segments that holds the segments `a1..=a2` and `b1..=b2` (positions along the
/// chain).
fn span(a1: usize, a2: usize, b1: usize, b2: usize, len: usize) -> usize {
    let straight = a2.max(b2) - a1.min(b1);
    // the other way round, when the two ranges are disjoint
    let around = if a2 < b1 {
        len - b1 + a2
    } else if b2 < a1 {
        len - a1 + b2
    } else {
        usize::MAX
    };
    straight.min(around)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::find_segment_intersections;
    use crate::geometry::intersect::tests::rng;

    fn closed(n: usize, f: impl Fn(f64) -> Point<2>) -> (Vec<Point<2>>, Vec<[usize; 2]>) {
        let pts = (0..n).map(|k| f(std::f64::consts::TAU * k as f64 / n as f64)).collect();
        (pts, (0..n).map(|k| [k, (k + 1) % n]).collect())
    }

    #[test]
    fn spans_go_the_short_way_round() {
        assert_eq!(span(0, 2, 3, 5, 100), 5);
        assert_eq!(span(0, 2, 95, 98, 100), 100 - 95 + 2);
        assert_eq!(span(10, 20, 15, 30, 100), 20);
    }

    /// The neck of a dumbbell squeezed step by step: the watch reports exactly what
    /// the finder reports at every step, including the step at which the neck's
    /// sides first cross, and skips most checks while the neck is wide.
    #[test]
    fn the_watch_agrees_with_the_finder_at_every_step() {
        let (mut pts, segs) = closed(2000, |t| Point::<2>::new(2.0 * t.cos(), t.sin() * (0.3 + t.cos().powi(2))));
        let mut watch = CrossingWatch::default();
        let mut state = 7u64;
        let mut crossed_at = None;
        for step in 0..400 {
            if step == 150 {
                // the neck still wider than a few cells: mostly skipped
                assert!(watch.skipped > 3 * watch.full_checks, "{} skipped, {} full", watch.skipped, watch.full_checks);
            }
            let hits = watch.crossings(&pts, &segs);
            let truth = find_segment_intersections(&pts, &segs);
            assert_eq!(hits.len(), truth.len(), "step {step}");
            if !truth.is_empty() {
                crossed_at.get_or_insert(step);
            }
            // squeeze the neck (|x| < 1), with a little noise on every vertex
            for p in &mut pts {
                let squeeze = 1e-3 * (1.0 - p.x * p.x).max(0.0);
                p.y -= squeeze * p.y.signum();
                p.x += 2e-6 * (rng(&mut state) - 0.5);
                p.y += 2e-6 * (rng(&mut state) - 0.5);
            }
        }
        assert!(crossed_at.is_some_and(|s| s > 200), "{crossed_at:?}");
    }

    /// A large smooth circle shrinking slowly, with noise: the coarse certificate
    /// (vertices may move 16 mean segment lengths) answers most checks, and the
    /// watch still agrees with the finder when the circle is pinched at the end.
    #[test]
    fn a_slowly_moving_smooth_curve_is_watched_from_coarse_cells() {
        let (mut pts, segs) = closed(4000, |t| Point::<2>::new(t.cos(), t.sin()));
        let mut watch = CrossingWatch::default();
        let mut state = 11u64;
        for step in 0..100 {
            let truth = find_segment_intersections(&pts, &segs);
            assert_eq!(watch.crossings(&pts, &segs).len(), truth.len(), "step {step}");
            for p in &mut pts {
                *p *= 1.0 - 1e-3;
                p.x += 1e-6 * (rng(&mut state) - 0.5);
            }
        }
        // the fine cells (2 mean lengths of reach) would need a full check every
        // third step
        assert!(watch.full_checks <= 8, "{} full, {} skipped", watch.full_checks, watch.skipped);
        // fold two vertices over: caught by the turning angles
        fold_is_caught(&mut watch, &mut pts, &segs, 1e-5);
    }

    /// Vertices 10 and 11 trade places along their segment (each moving less than
    /// the segment, off the line by `off`): the watch reports the crossings.
    fn fold_is_caught(watch: &mut CrossingWatch, pts: &mut [Point<2>], segs: &[[usize; 2]], off: f64) {
        let (a, b) = (pts[10], pts[11]);
        pts[10] = a + (b - a) * 1.4;
        pts[11] = b + (a - b) * 1.4 + Point::<2>::new(off, off);
        let truth = find_segment_intersections(pts, segs);
        assert!(!truth.is_empty());
        assert_eq!(watch.crossings(pts, segs).len(), truth.len());
    }

    /// Two circles approaching each other rigidly (no angle changes): the far
    /// pairs' clearance, spent by the displacement, forces the full check in time.
    #[test]
    fn rigid_approach_is_caught_by_the_displacement() {
        let n = 200;
        let ring = |cx: f64, k: usize| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            Point::<2>::new(cx + t.cos(), t.sin())
        };
        let mut pts: Vec<Point<2>> = (0..n).map(|k| ring(0.0, k)).chain((0..n).map(|k| ring(3.0, k))).collect();
        let segs: Vec<[usize; 2]> = (0..2 * n).map(|k| [k, if k % n == n - 1 { k + 1 - n } else { k + 1 }]).collect();
        let mut watch = CrossingWatch::default();
        for step in 0..200 {
            let truth = find_segment_intersections(&pts, &segs);
            assert_eq!(watch.crossings(&pts, &segs).len(), truth.len(), "step {step}");
            for p in &mut pts[n..] {
                p.x -= 0.01; // the second circle moves left: overlap from step 100 on
            }
        }
        assert!(watch.skipped > 50, "{}", watch.skipped);
    }

    /// Two neighbouring vertices of a circle trade places along the tangent (a
    /// local tangle, each moving less than a segment): the turning angles force the
    /// full check.
    #[test]
    fn a_local_tangle_is_caught_by_the_turning_angles() {
        let (mut pts, segs) = closed(400, |t| Point::<2>::new(t.cos(), t.sin()));
        let mut watch = CrossingWatch::default();
        assert!(watch.crossings(&pts, &segs).is_empty());
        assert!(watch.crossings(&pts, &segs).is_empty());
        assert_eq!(watch.skipped, 1);
        fold_is_caught(&mut watch, &mut pts, &segs, 1e-4);
    }

    /// A certificate is not drawn for a curve that comes back close to itself
    /// (two passes through one block of cells), nor kept when the connectivity
    /// changes.
    #[test]
    fn close_passes_and_new_connectivity_force_full_checks() {
        // a thin hairpin: the two sides are closer than a cell
        let (pts, segs) = closed(400, |t| Point::<2>::new(t.cos(), 0.01 * t.sin()));
        let mut watch = CrossingWatch::default();
        watch.crossings(&pts, &segs);
        watch.crossings(&pts, &segs);
        assert_eq!((watch.full_checks, watch.skipped), (2, 0));
        let (pts, segs) = closed(400, |t| Point::<2>::new(t.cos(), t.sin()));
        let mut watch = CrossingWatch::default();
        watch.crossings(&pts, &segs);
        watch.crossings(&pts, &segs);
        assert_eq!((watch.full_checks, watch.skipped), (1, 1));
        let mut reversed = segs.clone();
        reversed.rotate_left(1);
        watch.crossings(&pts, &reversed);
        assert_eq!(watch.full_checks, 2);
    }
}
