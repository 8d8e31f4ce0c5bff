//! Putting back the vertices of triangles that would pass through each other.
//!
//! A trial state is searched in full once ([`PatchSearch`]); each round after
//! that puts back a few vertices, so that only the triangles around them have
//! moved: the pairs of two triangles that did not move are those of the round
//! before, and the pairs with a moved triangle are found by a broad phase over
//! the moved triangles and the triangles in their grid cells alone
//! ([`intersections_with`]). The answer is the full search's at every round.

use super::surface_intersections::{bounds, box_pairs, mean_edge, pack, triangles_meet, Aabb, MAX_CELLS};
use super::{PatchSearch, Point};

/// `after` (positions of the vertices of `triangles`, which meet nowhere new at
/// `before`) with the vertices of every pair of triangles that meet in it but
/// not at `before` put back at `before`, repeated until no new pair meets (a
/// vertex put back can bring a neighbouring triangle into contact) or `rounds`
/// are done; `None` if some new pair still meets then. At worst every vertex is
/// put back: `before`, which meets nowhere new. The first round's pairs are found
/// by `search` (the exhaustive search's pairs; its patches kept for the next
/// call), the later rounds' around the vertices put back (the same pairs); the
/// result's pairs are kept by `search` for its next search of that state.
pub fn revert_new_intersections(
    before: &[Point<3>],
    after: &[Point<3>],
    triangles: &[[usize; 3]],
    rounds: usize,
    search: &mut PatchSearch,
) -> Option<Vec<Point<3>>> {
    let mut x = after.to_vec();
    let mut pairs = search.intersections(&x, triangles, usize::MAX);
    if pairs.is_empty() {
        return Some(x);
    }
    pairs.sort_unstable();
    let old = search.intersections_of_state(before, triangles);
    let mut back = vec![false; x.len()];
    let mut changed = vec![false; triangles.len()];
    for _ in 0..rounds {
        let new: Vec<(usize, usize)> = pairs.iter().filter(|p| old.binary_search(p).is_err()).copied().collect();
        if new.is_empty() {
            search.remember(&x, triangles, pairs);
            return Some(x);
        }
        back.fill(false);
        for &(a, b) in &new {
            for &v in triangles[a].iter().chain(&triangles[b]) {
                back[v] |= x[v] != before[v];
                x[v] = before[v];
            }
        }
        for (c, t) in changed.iter_mut().zip(triangles) {
            *c = t.iter().any(|&v| back[v]);
        }
        pairs.retain(|&(a, b)| !changed[a] && !changed[b]);
        pairs.extend(intersections_with(&x, triangles, &changed));
        pairs.sort_unstable();
    }
    pairs.iter().all(|p| old.binary_search(p).is_ok()).then_some(x)
}

/// The pairs `(a, b)`, `a < b`, of `triangles` that share no vertex, meet at `x`
/// and of which at least one is `changed`: those of the exhaustive search with a
/// changed triangle. The broad phase lays the changed triangles' boxes on a grid
/// of the exhaustive search's cells and pairs them with the triangles whose
/// boxes cover one of those cells.
pub(super) fn intersections_with(x: &[Point<3>], triangles: &[[usize; 3]], changed: &[bool]) -> Vec<(usize, usize)> {
    let mut hits = Vec::new();
    if !changed.iter().any(|&c| c) {
        return hits;
    }
    let cell = super::surface_intersections::CELL_EDGES * mean_edge(x, triangles);
    if !(cell.is_finite() && cell > 0.0) {
        return super::surface_intersections(x, triangles, usize::MAX)
            .into_iter()
            .filter(|&(a, b)| changed[a] || changed[b])
            .collect();
    }
    let cells_of = |b: &Aabb| {
        let (l, h) = (b.0.map(|c| (c / cell).floor() as i64), b.1.map(|c| (c / cell).floor() as i64));
        let count = (0..3).map(|k| (h[k] - l[k] + 1) as usize).product::<usize>();
        (count <= MAX_CELLS).then(|| {
            (l[0]..=h[0])
                .flat_map(move |i| (l[1]..=h[1]).flat_map(move |j| (l[2]..=h[2]).map(move |k| pack([i, j, k]))))
        })
    };
    // the cells of the changed triangles (all cells if one of them is too large)
    let mut cells: Vec<u64> = Vec::new();
    let mut everywhere = false;
    for tri in triangles.iter().zip(changed).filter(|&(_, &c)| c).map(|(t, _)| t) {
        match cells_of(&bounds(x, tri)) {
            Some(keys) => cells.extend(keys),
            None => everywhere = true,
        }
    }
    cells.sort_unstable();
    cells.dedup();
    // the changed triangles and those that share a cell with one
    let mut near: Vec<usize> = Vec::new();
    let mut boxes: Vec<Aabb> = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        let b = bounds(x, tri);
        let close = changed[t]
            || everywhere
            || cells_of(&b).is_none_or(|mut keys| keys.any(|k| cells.binary_search(&k).is_ok()));
        if close {
            near.push(t);
            boxes.push(b);
        }
    }
    box_pairs(&boxes, cell, |i, j| {
        let (a, b) = (near[i], near[j]);
        let (ta, tb) = (&triangles[a], &triangles[b]);
        if (changed[a] || changed[b]) && !ta.iter().any(|v| tb.contains(v)) && triangles_meet(x, ta, tb) {
            hits.push((a.min(b), a.max(b)));
        }
        false
    });
    hits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{icosphere, surface_intersections, surface_union};

    /// Two spheres pushed into each other, a few of their triangles marked as
    /// changed: the pairs with a changed triangle are the exhaustive search's.
    #[test]
    fn the_pairs_with_a_changed_triangle_are_the_exhaustive_searchs() {
        let a = icosphere([-0.45, 0.0, 0.0], 0.5, 3).unwrap();
        let b = icosphere([0.45, 0.03, 0.0], 0.5, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let (x, t) = (two.positions(), two.elements());
        let mut all = surface_intersections(x, t, usize::MAX);
        all.sort_unstable();
        assert!(all.len() > 20, "{}", all.len());
        for every in [3, 7, 50] {
            let changed: Vec<bool> = (0..t.len()).map(|i| i % every == 0).collect();
            let mut with = intersections_with(x, t, &changed);
            with.sort_unstable();
            let expected: Vec<(usize, usize)> =
                all.iter().filter(|&&(a, b)| changed[a] || changed[b]).copied().collect();
            assert!(!expected.is_empty());
            assert_eq!(with, expected, "every {every}th triangle changed");
        }
        assert!(intersections_with(x, t, &vec![false; t.len()]).is_empty());
    }

    /// The rounds find what rounds of exhaustive searches find: the spheres grown
    /// into each other keep their contact where it was and meet nowhere new.
    #[test]
    fn reverting_meets_nowhere_new() {
        let a = icosphere([-0.52, 0.0, 0.0], 0.5, 3).unwrap();
        let b = icosphere([0.52, 0.02, 0.01], 0.5, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let centre = |p: &Point<3>| Point::<3>::new(if p[0] < 0.0 { -0.52 } else { 0.52 }, 0.0, 0.0);
        let before = two.positions();
        let after: Vec<Point<3>> = before.iter().map(|p| centre(p) + (p - centre(p)) * 1.15).collect();
        assert!(!surface_intersections(&after, two.elements(), 1).is_empty());
        let x = revert_new_intersections(before, &after, two.elements(), 20, &mut PatchSearch::default()).unwrap();
        assert!(surface_intersections(&x, two.elements(), 1).is_empty());
        let grown = (0..x.len()).filter(|&v| x[v] == after[v]).count();
        assert!(grown > x.len() / 2, "{grown} of {}", x.len());
    }
}
