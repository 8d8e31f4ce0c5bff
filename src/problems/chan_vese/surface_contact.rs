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
use std::collections::HashMap;

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
        // closer than the clearance, and closer than the vertex was
        let mut around: Option<Clearance> = None;
        for _ in 0..ROUNDS {
            let close = Clearance::new(&x, triangles, &component, gap);
            let near: Vec<usize> = (0..x.len()).filter(|&v| moved(&x, v) && close.within(&x, v)).collect();
            if near.is_empty() {
                break;
            }
            let around = around.get_or_insert_with(|| Clearance::new(here, triangles, &component, gap));
            let hold: Vec<usize> =
                near.into_iter().filter(|&v| close.distance(&x, v) < around.distance(here, v)).collect();
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
/// distance from a vertex to the nearest triangle of another component.
struct Clearance<'a> {
    triangles: &'a [[usize; 3]],
    component: &'a [usize],
    gap: f64,
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> Clearance<'a> {
    fn new(x: &[Point<3>], triangles: &'a [[usize; 3]], component: &'a [usize], gap: f64) -> Clearance<'a> {
        let mean = triangles.iter().map(|t| (x[t[1]] - x[t[0]]).norm()).sum::<f64>() / triangles.len().max(1) as f64;
        let cell = (2.0 * mean).max(gap).max(f64::MIN_POSITIVE);
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (t, tri) in triangles.iter().enumerate() {
            let lo = [0, 1, 2].map(|a| tri.iter().map(|&v| x[v][a]).fold(f64::INFINITY, f64::min) - gap);
            let hi = [0, 1, 2].map(|a| tri.iter().map(|&v| x[v][a]).fold(f64::NEG_INFINITY, f64::max) + gap);
            let (l, h) = (lo.map(|c| (c / cell).floor() as i64), hi.map(|c| (c / cell).floor() as i64));
            if (0..3).map(|a| (h[a] - l[a] + 1) as usize).product::<usize>() > 512 {
                continue;
            }
            for i in l[0]..=h[0] {
                for j in l[1]..=h[1] {
                    for k in l[2]..=h[2] {
                        cells.entry([i, j, k]).or_default().push(t as u32);
                    }
                }
            }
        }
        Clearance { triangles, component, gap, cell, cells }
    }

    /// The distance from vertex `v` (at `x[v]`) to the nearest triangle of
    /// another component among those within `gap` of its cell; `gap` if none.
    fn distance(&self, x: &[Point<3>], v: usize) -> f64 {
        let p = x[v];
        let key = [0, 1, 2].map(|a| (p[a] / self.cell).floor() as i64);
        let Some(list) = self.cells.get(&key) else { return self.gap };
        let at = [p[0], p[1], p[2]];
        list.iter()
            .map(|&t| self.triangles[t as usize])
            .filter(|t| self.component[t[0]] != self.component[v])
            .map(|t| point_triangle_distance(at, &t.map(|q| [x[q][0], x[q][1], x[q][2]])))
            .fold(self.gap, f64::min)
    }

    fn within(&self, x: &[Point<3>], v: usize) -> bool {
        self.distance(x, v) < self.gap
    }
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
        let clearance = Clearance::new(apart.positions(), two.elements(), &component, 0.2);
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
