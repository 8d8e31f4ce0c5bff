//! The contact rule of curves: objects that start separate stay separate. Where a
//! step would make two objects' contours cross, the vertices of the crossing
//! segments (and their neighbours) go only a quarter of their step, then a quarter
//! of that, up to [`SHORTENINGS`] times, and then keep their positions; the rest
//! of the step goes on. The contours thus close in on each other where they meet,
//! rather than stopping at the gap that the step which first crossed left between
//! them.

use crate::geometry::{Mesh, SegmentHit, SweptSegments};

/// Rounds in which the crossing vertices' steps are shortened, each time by
/// [`SHORTENING`] (down to 1/64). Halving six times instead ended at the same Dice
/// on touching discs and took 1.15 times as long on the nuclei image.
const SHORTENINGS: usize = 3;

/// What a round leaves of a crossing vertex's step.
const SHORTENING: f64 = 0.25;

/// Further rounds in which the vertices still crossing keep their positions;
/// whatever crosses after them is inadmissible.
const HOLDS: usize = 8;

/// Whether two different components of a curve mesh cross (never, for a mesh
/// that is not a curve in the plane).
pub(super) fn objects_cross<const D: usize>(mesh: &Mesh<D>) -> bool {
    (mesh as &dyn std::any::Any).downcast_ref::<Mesh<2>>().is_some_and(|c| !c.component_crossings().is_empty())
}

/// Swept boxes that a round's search of the moved segments may look at, per
/// segment of the curve, before it searches the whole curve instead
/// ([`SweptSegments::crossings_within`]): the same crossings either way, but
/// after long steps (thousands of seeds pushed hard) the boxes cover much of the
/// image, and the swept search grew with the square of the segments (minutes
/// for one step on a 400 × 328 picture).
const SWEPT_BUDGET: usize = 4;

/// `candidate`, a step from `current` with the same vertices, with the crossing
/// vertices' steps shortened until no two objects cross, or the rounds are over.
pub(super) fn keep_apart(current: &Mesh<2>, candidate: &mut Mesh<2>) {
    let budget = SWEPT_BUDGET * candidate.num_elements() + 1024;
    keep_apart_within(current, candidate, budget);
}

/// [`keep_apart`] with the swept search of a round bounded by `budget`.
fn keep_apart_within(current: &Mesh<2>, candidate: &mut Mesh<2>, budget: usize) {
    let mut hits = candidate.component_crossings();
    if hits.is_empty() {
        return;
    }
    let (from, to) = (current.positions(), candidate.positions().to_vec());
    let els = candidate.elements().to_vec();
    let n = to.len();
    // the segments ending and starting at each vertex
    let mut segments_of = vec![[usize::MAX; 2]; n];
    for (k, e) in els.iter().enumerate() {
        segments_of[e[0]][1] = k;
        segments_of[e[1]][0] = k;
    }
    let swept = SweptSegments::new(&els, from, &to);
    let mut fraction = vec![1.0; n];
    for round in 0..SHORTENINGS + HOLDS {
        // the vertices of the crossing segments and their neighbours
        let held = held_vertices(&hits, &els, &segments_of);
        let mut x = candidate.positions().to_vec();
        for &v in &held {
            fraction[v] = if round < SHORTENINGS { SHORTENING * fraction[v] } else { 0.0 };
            x[v] = from[v] + (to[v] - from[v]) * fraction[v];
        }
        candidate.set_positions(x);
        // only the segments of the vertices just moved can cross anew, and only the
        // segments whose paths meet theirs
        let mut segments: Vec<usize> = held.iter().flat_map(|&v| segments_of[v]).filter(|&k| k != usize::MAX).collect();
        segments.sort_unstable();
        segments.dedup();
        hits = match swept.crossings_within(candidate, segments.into_iter(), budget) {
            Some(hits) => hits,
            None => candidate.component_crossings(),
        };
        if hits.is_empty() {
            return;
        }
    }
}

/// The vertices of the segments of `hits` and of their neighbouring segments, so
/// that the held stretch is not folded by the step around it.
fn held_vertices(hits: &[SegmentHit], els: &[[usize; 2]], segments_of: &[[usize; 2]]) -> Vec<usize> {
    let mut out = Vec::new();
    for h in hits {
        for v in [els[h.a], els[h.b]].into_iter().flatten() {
            out.extend(segments_of[v].iter().filter(|&&k| k != usize::MAX).flat_map(|&k| els[k]));
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, Point};

    /// Two circles 0.1 apart; a step moves the first 0.2 towards the second. The
    /// crossing vertices go a quarter of their step: no two objects cross, the gap
    /// halves (holding them where they were kept it at 0.1), and the vertices
    /// away from the contact go all the way.
    #[test]
    fn contours_close_in_where_they_meet() {
        let (a, b) = (circle([0.0, 0.0], 1.0, 64).unwrap(), circle([2.1, 0.0], 1.0, 64).unwrap());
        let x: Vec<Point<2>> = a.positions().iter().chain(b.positions()).copied().collect();
        let elements: Vec<[usize; 2]> =
            a.elements().iter().copied().chain(b.elements().iter().map(|&[p, q]| [p + 64, q + 64])).collect();
        let current = Mesh::<2>::from_trusted_parts(x.clone(), elements);
        let step = Point::<2>::new(0.2, 0.0);
        let moved: Vec<Point<2>> = x.iter().enumerate().map(|(i, p)| if i < 64 { *p + step } else { *p }).collect();
        let mut candidate = current.clone();
        candidate.set_positions(moved.clone());
        assert!(objects_cross(&candidate));
        keep_apart(&current, &mut candidate);
        assert!(!objects_cross(&candidate));
        let y = candidate.positions();
        let rightmost = (0..64).map(|i| y[i].x).fold(f64::NEG_INFINITY, f64::max);
        assert!((rightmost - 1.05).abs() < 1e-12, "the gap is {}", 1.1 - rightmost);
        // the left half of the first circle moved the whole step
        for i in 0..64 {
            if x[i].x < 0.0 {
                assert!((y[i] - moved[i]).norm() < 1e-15);
            }
        }
    }

    /// A long step of many small loops, each pushed out past its neighbours: the
    /// rounds end as they do with the swept search alone when every round's
    /// swept search runs out of its budget and the whole curve is searched.
    #[test]
    fn a_search_of_the_whole_curve_gives_the_same_step() {
        let (mut x, mut elements) = (Vec::new(), Vec::new());
        for k in 0..36 {
            let c = circle([(k % 6) as f64, (k / 6) as f64], 0.3, 12).unwrap();
            let base = x.len();
            x.extend_from_slice(c.positions());
            elements.extend(c.elements().iter().map(|&[p, q]| [p + base, q + base]));
        }
        let current = Mesh::<2>::from_trusted_parts(x.clone(), elements);
        // each vertex out to 0.6–1.0 from its loop's centre (the loops 1 apart), turned a little
        let moved: Vec<Point<2>> = x
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let k = i / 12;
                let c = Point::<2>::new((k % 6) as f64, (k / 6) as f64);
                let out = (p - c) * (1.0 + (i % 3) as f64 / 3.0);
                c + out * 2.0 + Point::<2>::new(-out.y, out.x) * 0.2
            })
            .collect();
        let mut swept = current.clone();
        swept.set_positions(moved.clone());
        assert!(objects_cross(&swept));
        let mut whole = swept.clone();
        keep_apart_within(&current, &mut swept, usize::MAX);
        keep_apart_within(&current, &mut whole, 0);
        assert_eq!(swept.positions(), whole.positions());
        assert!(!objects_cross(&whole));
        let held = (0..x.len()).filter(|&i| (whole.positions()[i] - moved[i]).norm() > 1e-12).count();
        assert!(held > 36 && held < x.len(), "{held} of {} vertices held back", x.len());
    }
}
