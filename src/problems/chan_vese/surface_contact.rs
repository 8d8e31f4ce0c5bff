//! The contact rule of surfaces: objects that meet stop where they meet.
//!
//! A trial step that would bring a vertex closer than a clearance `gap` to a
//! triangle of another component (another object, or another part of one split
//! at a neck), or carry triangles of the surface through each other, holds
//! those vertices where they are, and the rest of the step goes on. A held
//! vertex can bring a neighbouring triangle into contact, so this is repeated
//! until nothing is held anew; at worst every vertex is held, which is the state
//! the step starts from. The clearance keeps touching objects a little apart, so
//! that the mesh management's tangential moves do not carry a vertex through
//! the sheet beside it. A vertex already within the clearance may move away, not
//! closer; pairs of triangles that already met (the parts of an object split at
//! a neck may start so) are left as they are: the flow's intersection check does
//! not count them either.

use crate::geometry::{revert_new_intersections, Mesh, PatchSearch, Point};
use crate::imaging::signed_distance::point_triangle_distance;

/// Rounds of holding after which the step is left to the flow's intersection
/// check (which then halves it).
const ROUNDS: usize = 12;

/// `candidate` (the connectivity of `current`) with the vertices held at their
/// positions in `current` that come within `gap` of another component, or belong
/// to a pair of triangles that meet in it but not in `current` (see the module
/// documentation); unchanged where there are none. `search` finds the pairs
/// that meet (its patches kept for the next step).
pub(super) fn hold_contacts(current: &Mesh<3>, candidate: &mut Mesh<3>, gap: f64, search: &mut PatchSearch) {
    let triangles = current.elements();
    let (component, count) = current.component_labels();
    let here = current.positions();
    let moved = |x: &[Point<3>], v: usize| x[v] != here[v];
    let mut x = candidate.positions().to_vec();
    let mut held = 0;
    if count > 1 && gap > 0.0 {
        // closer than the clearance, and closer than the vertex was; every round's
        // positions lie between `here` and the candidate's, whose swept boxes
        // the grid holds
        let close = Clearance::new(here, &x, triangles, &component, gap);
        for _ in 0..ROUNDS {
            let hold: Vec<usize> = (0..x.len())
                .filter(|&v| moved(&x, v))
                .filter(|&v| {
                    let d = close.distance(&x, v);
                    d < gap && d < close.distance(here, v)
                })
                .collect();
            if hold.is_empty() {
                break;
            }
            held += hold.len();
            for v in hold {
                x[v] = here[v];
            }
        }
    }
    // then the triangles that would pass through each other
    if let Some(apart) = revert_new_intersections(here, &x, triangles, ROUNDS, search) {
        x = apart;
    }
    tracing::trace!(held, "vertices held at a contact of surfaces");
    candidate.set_positions(x);
}

/// The triangles of a surface on a grid of cells of at least `gap`, for the
/// distance from a vertex to the nearest triangle of another component, at any
/// positions between two states: each triangle is entered in the cells of its
/// box swept from one to the other and grown by `gap`, in a list sorted by cell;
/// only the triangles that come that close to another component's swept box.
struct Clearance<'a> {
    triangles: &'a [[usize; 3]],
    component: &'a [usize],
    gap: f64,
    cell: f64,
    /// Each component's box swept from one state to the other.
    boxes: Vec<([f64; 3], [f64; 3])>,
    /// (cell, triangle), sorted.
    cells: Vec<([i64; 3], u32)>,
    /// Triangles whose swept box covers more than `MAX_CELLS` cells: near every
    /// vertex.
    large: Vec<u32>,
}

/// Cells a triangle's swept box may cover at most before it is kept aside.
const MAX_CELLS: usize = 512;

impl<'a> Clearance<'a> {
    fn new(
        from: &[Point<3>],
        to: &[Point<3>],
        triangles: &'a [[usize; 3]],
        component: &'a [usize],
        gap: f64,
    ) -> Clearance<'a> {
        let mean =
            triangles.iter().map(|t| (from[t[1]] - from[t[0]]).norm()).sum::<f64>() / triangles.len().max(1) as f64;
        let cell = (2.0 * mean).max(gap).max(f64::MIN_POSITIVE);
        let count = component.iter().max().map_or(0, |&c| c + 1);
        let mut boxes = vec![([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]); count];
        for (v, &c) in component.iter().enumerate() {
            for p in [from[v], to[v]] {
                for a in 0..3 {
                    boxes[c].0[a] = boxes[c].0[a].min(p[a]);
                    boxes[c].1[a] = boxes[c].1[a].max(p[a]);
                }
            }
        }
        let mut cells = Vec::new();
        let mut large = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            let corners = || tri.iter().flat_map(|&v| [from[v], to[v]]);
            let lo = [0, 1, 2].map(|a| corners().map(|p| p[a]).fold(f64::INFINITY, f64::min) - gap);
            let hi = [0, 1, 2].map(|a| corners().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max) + gap);
            if !near_another(&boxes, component[tri[0]], (lo, hi)) {
                continue;
            }
            let (l, h) = (lo.map(|c| (c / cell).floor() as i64), hi.map(|c| (c / cell).floor() as i64));
            if (0..3).map(|a| (h[a] - l[a] + 1) as usize).product::<usize>() > MAX_CELLS {
                large.push(t as u32);
                continue;
            }
            for i in l[0]..=h[0] {
                for j in l[1]..=h[1] {
                    for k in l[2]..=h[2] {
                        cells.push(([i, j, k], t as u32));
                    }
                }
            }
        }
        cells.sort_unstable();
        Clearance { triangles, component, gap, cell, boxes, cells, large }
    }

    /// The distance from vertex `v` (at `x[v]`) to the nearest triangle of
    /// another component among those within `gap` of its cell; `gap` if none.
    fn distance(&self, x: &[Point<3>], v: usize) -> f64 {
        let p = x[v];
        let around = ([0, 1, 2].map(|a| p[a] - self.gap), [0, 1, 2].map(|a| p[a] + self.gap));
        if !near_another(&self.boxes, self.component[v], around) {
            return self.gap;
        }
        let key = [0, 1, 2].map(|a| (p[a] / self.cell).floor() as i64);
        let start = self.cells.partition_point(|e| e.0 < key);
        let end = start + self.cells[start..].partition_point(|e| e.0 == key);
        let at = [p[0], p[1], p[2]];
        (self.cells[start..end].iter().map(|e| e.1).chain(self.large.iter().copied()))
            .map(|t| self.triangles[t as usize])
            .filter(|t| self.component[t[0]] != self.component[v])
            .map(|t| point_triangle_distance(at, &t.map(|q| [x[q][0], x[q][1], x[q][2]])))
            .fold(self.gap, f64::min)
    }

    #[cfg(test)]
    fn within(&self, x: &[Point<3>], v: usize) -> bool {
        self.distance(x, v) < self.gap
    }
}

/// Whether the box `b` overlaps the box of a component other than `own`.
fn near_another(boxes: &[([f64; 3], [f64; 3])], own: usize, b: ([f64; 3], [f64; 3])) -> bool {
    (boxes.iter().enumerate()).any(|(c, o)| c != own && (0..3).all(|a| b.0[a] <= o.1[a] && o.0[a] <= b.1[a]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{icosphere, surface_union};

    /// Two spheres of radius 1 at x = ±1.05 grown by 10 % (radius 1.1, passing
    /// through each other by 0.1): the vertices that would pass are held, the
    /// result meets nowhere, and the vertices away from the contact have grown.
    #[test]
    fn growing_spheres_stop_where_they_meet() {
        let a = icosphere([-1.05, 0.0, 0.0], 1.0, 3).unwrap();
        let b = icosphere([1.05, 0.0, 0.0], 1.0, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let centre = |x: &Point<3>| Point::<3>::new(if x[0] < 0.0 { -1.05 } else { 1.05 }, 0.0, 0.0);
        let grown: Vec<Point<3>> = two.positions().iter().map(|x| centre(x) + (x - centre(x)) * 1.1).collect();
        let grown = two.with_positions(grown);
        assert!(!crate::geometry::surface_intersections(grown.positions(), grown.elements(), 1).is_empty());
        let mut held = grown.clone();
        hold_contacts(&two, &mut held, 0.0, &mut PatchSearch::default());
        assert!(crate::geometry::surface_intersections(held.positions(), held.elements(), 1).is_empty());
        let kept = (0..two.num_vertices()).filter(|&v| held.positions()[v] == two.positions()[v]).count();
        let moved = (0..two.num_vertices()).filter(|&v| held.positions()[v] == grown.positions()[v]).count();
        // the held vertices are those near the contact plane x = 0
        assert!(kept > 0 && moved + kept == two.num_vertices() && moved > 9 * kept, "{kept} held, {moved} moved");
        for v in 0..two.num_vertices() {
            if held.positions()[v] == two.positions()[v] {
                assert!(two.positions()[v][0].abs() < 0.35, "{:?}", two.positions()[v]);
            }
        }
        // with a clearance of 0.2 (twice the spheres' distance) no vertex that moved
        // comes that close to the other sphere

        let mut apart = grown.clone();
        hold_contacts(&two, &mut apart, 0.2, &mut PatchSearch::default());
        let (component, _) = two.component_labels();
        let clearance = Clearance::new(apart.positions(), apart.positions(), two.elements(), &component, 0.2);
        for v in 0..two.num_vertices() {
            if apart.positions()[v] != two.positions()[v] {
                assert!(!clearance.within(apart.positions(), v), "vertex {v}");
            }
        }
        let held_apart = (0..two.num_vertices()).filter(|&v| apart.positions()[v] == two.positions()[v]).count();
        assert!(held_apart > kept, "{held_apart} {kept}");
        // a step that meets nowhere is kept as it is
        let small: Vec<Point<3>> = two.positions().iter().map(|x| centre(x) + (x - centre(x)) * 1.01).collect();
        let small = two.with_positions(small);
        let mut kept = small.clone();
        hold_contacts(&two, &mut kept, 0.0, &mut PatchSearch::default());
        assert_eq!(kept.positions(), small.positions());
    }
}
