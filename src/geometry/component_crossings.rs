//! Crossings between different components of a curve mesh, searched only where
//! two components' bounding boxes overlap: a segment crossing another
//! component's segment lies in the overlap of the two boxes, so the segments
//! elsewhere (most of them, for objects that touch only here and there) need no
//! test. The hits are those of [`Mesh::crossings`] that join two components.
//! While a few vertices move back along their steps, only the segments whose
//! swept boxes meet theirs need a test ([`SweptSegments`]).

use super::boxes::{bounding_box, boxes_meet, grown, overlap, EMPTY};
use super::{find_segment_intersections, segment_pair_hit, BoxGrid, Mesh, Point, Rect, SegmentHit};

impl Mesh<2> {
    /// The crossings of segments of two different components (`a < b`, in the
    /// order of [`Mesh::crossings`]); a non-periodic mesh.
    pub fn component_crossings(&self) -> Vec<SegmentHit> {
        debug_assert!(self.period().is_none(), "component crossings of a periodic curve");
        let (label, count) = self.component_labels();
        if count < 2 {
            return Vec::new();
        }
        let x = self.positions();
        let mut boxes = vec![EMPTY; count];
        for (p, &c) in x.iter().zip(&label) {
            boxes[c] = grown(boxes[c], [p.x, p.y]);
        }
        // the overlaps of every component's box with the others', by component,
        // the pairs found on a grid of the boxes (a seeds start has thousands)
        let grid = BoxGrid::new(&boxes);
        let mut overlaps: Vec<Vec<Rect>> = vec![Vec::new(); count];
        let mut seen = vec![usize::MAX; count];
        for i in 0..count {
            let a = boxes[i];
            for j in grid.near(&a) {
                if j <= i || seen[j] == i || !boxes_meet(&a, &boxes[j]) {
                    continue;
                }
                seen[j] = i;
                let o = overlap(&a, &boxes[j]);
                overlaps[i].push(o);
                overlaps[j].push(o);
            }
        }
        let candidates: Vec<usize> = (0..self.num_elements())
            .filter(|&e| {
                let [a, b] = self.elements()[e];
                let s = bounding_box([[x[a].x, x[a].y], [x[b].x, x[b].y]].into_iter());
                overlaps[label[a]].iter().any(|o| boxes_meet(&s, o))
            })
            .collect();
        if candidates.is_empty() {
            return Vec::new();
        }
        let segments: Vec<[usize; 2]> = candidates.iter().map(|&e| self.elements()[e]).collect();
        find_segment_intersections(x, &segments)
            .into_iter()
            .map(|h| SegmentHit { a: candidates[h.a], b: candidates[h.b], ..h })
            .filter(|h| label[self.elements()[h.a][0]] != label[self.elements()[h.b][0]])
            .collect()
    }
}

/// The segments of a curve whose vertices may be anywhere on the straight paths
/// between two positions, each with the box it can sweep, binned on a grid: the
/// segments that a segment may meet, wherever along their paths both lie.
pub struct SweptSegments {
    boxes: Vec<Rect>,
    grid: BoxGrid,
}

impl SweptSegments {
    /// The segments `elements` between the positions `from` and `to`.
    pub fn new(elements: &[[usize; 2]], from: &[Point<2>], to: &[Point<2>]) -> SweptSegments {
        let boxes: Vec<Rect> = elements
            .iter()
            .map(|e| bounding_box(e.iter().flat_map(|&v| [[from[v].x, from[v].y], [to[v].x, to[v].y]])))
            .collect();
        let grid = BoxGrid::new(&boxes);
        SweptSegments { boxes, grid }
    }

    /// The crossings of two different components of `mesh` (whose vertices lie on
    /// their paths) in which one of `segments` (element indices) takes part: each
    /// of them is tested against the segments whose swept boxes meet its own.
    /// Sorted by `(a, b)`, as [`Mesh::component_crossings`].
    pub fn crossings_of(&self, mesh: &Mesh<2>, segments: impl Iterator<Item = usize>) -> Vec<SegmentHit> {
        self.crossings_within(mesh, segments, usize::MAX).expect("no bound on the search")
    }

    /// [`Self::crossings_of`], or `None` once the search has looked at more than
    /// `budget` swept boxes: after a long step, whose boxes cover much of the
    /// curve, a search of the curve as it lies ([`Mesh::component_crossings`])
    /// costs less.
    pub fn crossings_within(
        &self,
        mesh: &Mesh<2>,
        segments: impl Iterator<Item = usize>,
        budget: usize,
    ) -> Option<Vec<SegmentHit>> {
        let (label, _) = mesh.component_labels();
        let (x, els) = (mesh.positions(), mesh.elements());
        let mut hits = Vec::new();
        let mut looked = 0usize;
        for s in segments {
            let b = &self.boxes[s];
            for j in self.grid.near(b) {
                looked += 1;
                if looked > budget {
                    return None;
                }
                if label[els[s][0]] == label[els[j][0]] || !boxes_meet(b, &self.boxes[j]) {
                    continue;
                }
                let (a, c) = (s.min(j), s.max(j));
                hits.extend(segment_pair_hit(x, els[a], els[c], (a, c)));
            }
        }
        hits.sort_by_key(|h| (h.a, h.b));
        hits.dedup_by_key(|h| (h.a, h.b));
        Some(hits)
    }
}

#[cfg(test)]
mod tests {
    use super::SweptSegments;
    use crate::geometry::{circle, CurveMesh, Mesh, Point};

    /// The circles side by side in one mesh, crossings allowed.
    fn together(parts: &[CurveMesh]) -> CurveMesh {
        let (mut x, mut elements) = (Vec::new(), Vec::new());
        for part in parts {
            let k = x.len();
            x.extend_from_slice(part.positions());
            elements.extend(part.elements().iter().map(|&[a, b]| [a + k, b + k]));
        }
        Mesh::from_trusted_parts(x, elements)
    }

    /// Every crossing of two components that the full search finds, and only
    /// those: two overlapping circles, a third apart, a fourth crossing both.
    #[test]
    fn the_same_crossings_as_the_full_search() {
        let mesh = together(&[
            circle([0.0, 0.0], 1.0, 64).unwrap(),
            circle([1.5, 0.0], 1.0, 48).unwrap(),
            circle([6.0, 0.0], 1.0, 32).unwrap(),
            circle([0.75, 0.9], 0.5, 40).unwrap(),
        ]);
        let all = mesh.crossings();
        let between: Vec<(usize, usize)> = mesh.crossings_between_components(&all).iter().map(|h| (h.a, h.b)).collect();
        let found: Vec<(usize, usize)> = mesh.component_crossings().iter().map(|h| (h.a, h.b)).collect();
        assert!(between.len() >= 6, "{between:?}");
        assert_eq!(found, between);
        // apart, and a single component: nothing to search
        let apart = together(&[circle([0.0, 0.0], 1.0, 32).unwrap(), circle([3.0, 0.0], 1.0, 32).unwrap()]);
        assert!(apart.component_crossings().is_empty());
        assert!(circle([0.0, 0.0], 1.0, 32).unwrap().component_crossings().is_empty());
        // a component that crosses itself is not reported
        let x = vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
        ];
        let bow = Mesh::from_trusted_parts(x, vec![[0, 1], [1, 2], [2, 3], [3, 0]]);
        assert!(!bow.crossings().is_empty());
        assert!(bow.component_crossings().is_empty());
    }

    /// Vertices anywhere on their paths between two states: the swept search
    /// finds exactly the crossings of the full search (every segment asked), and
    /// those of one segment among them.
    #[test]
    fn the_swept_search_finds_the_crossings_on_the_way() {
        let from = together(&[circle([0.0, 0.0], 1.0, 48).unwrap(), circle([2.1, 0.0], 1.0, 40).unwrap()]);
        // the first circle moves right by 0.3, the second left by 0.1: they meet
        let to: Vec<Point<2>> = from
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| if i < 48 { *p + Point::<2>::new(0.3, 0.0) } else { *p - Point::<2>::new(0.1, 0.0) })
            .collect();
        let swept = SweptSegments::new(from.elements(), from.positions(), &to);
        let mut mesh = from.clone();
        let (mut next, mut crossed) = (crate::geometry::test_numbers::numbers(7), 0);
        for _ in 0..20 {
            let x: Vec<Point<2>> = from.positions().iter().zip(&to).map(|(a, b)| *a + (*b - *a) * next()).collect();
            mesh.set_positions(x);
            let full: Vec<(usize, usize)> = mesh.component_crossings().iter().map(|h| (h.a, h.b)).collect();
            let found: Vec<(usize, usize)> =
                swept.crossings_of(&mesh, 0..mesh.num_elements()).iter().map(|h| (h.a, h.b)).collect();
            assert_eq!(found, full);
            let within = swept.crossings_within(&mesh, 0..mesh.num_elements(), 1 << 20);
            assert_eq!(within.map(|h| h.iter().map(|h| (h.a, h.b)).collect::<Vec<_>>()), Some(full.clone()));
            assert!(swept.crossings_within(&mesh, 0..mesh.num_elements(), 10).is_none());
            if let Some(&(a, b)) = full.first() {
                crossed += 1;
                let one = swept.crossings_of(&mesh, [a].into_iter());
                assert!(one.iter().any(|h| (h.a, h.b) == (a, b)));
                assert!(one.iter().all(|h| h.a == a || h.b == a));
            }
        }
        assert!(crossed >= 5, "{crossed} of 20 states crossed");
    }
}
