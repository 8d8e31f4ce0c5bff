//! Contact of a curve with itself (or another component) across its interior.
//!
//! Topological changes are triggered by crossings ([`super::resolve_crossings`]).
//! A flow can instead bring two parts of a curve to a gap that it then holds or
//! closes only asymptotically: the stressed film's mushroom caps, which come to
//! within a fraction of a segment over a gas channel and stay there, or the walls of
//! a crack. [`close_contact`] gives such a gap a physical length: two parts that
//! face each other across the interior (the left side of the curve: the gas of the
//! film) closer than a contact distance `δ` touch. The closest such pair, a vertex
//! `x_i` and a point `q` of a segment `[a, b]` with
//!
//! `|q − x_i| < δ`,   `ν_i · (q − x_i) > 0`,   `ν_ab · (x_i − q) > 0`,   `ν_i · ν_ab < 0`
//!
//! (`ν` the left normals) and `q` at least `4δ` and four vertices from `x_i` along
//! the curve (so that neither a convex arc nor a round tip narrower than `δ`
//! touches itself), is pushed past each other so that their segments cross, ready for the
//! crossing resolution: `x_i` and the segment each move half-way to the other
//! and then a quarter of the shorter segment on. With `δ` fixed the rule does not
//! depend on the mesh (it needs segments no longer than about `δ` to see the gap
//! well); it models adhesion over a short range, which the continuum flow lacks.

use std::collections::HashMap;

use super::{CurveMesh, Point};

/// Vertices this close along the same component never count as a contact.
const MIN_SEPARATION: usize = 4;
/// Points closer than this many contact distances along the same component never
/// count as a contact.
const MIN_ARC: f64 = 4.0;

/// A found contact: the distance, the vertex, and the segment (element index) with
/// the parameter `t ∈ [0, 1]` of its nearest point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub distance: f64,
    pub vertex: usize,
    pub element: usize,
    pub t: f64,
}

fn rot90(v: Point<2>) -> Point<2> {
    Point::<2>::new(-v.y, v.x)
}

/// The closest contact closer than `delta` (see the module documentation), if any.
pub fn find_contact(mesh: &CurveMesh, delta: f64) -> Option<Contact> {
    let x = mesh.positions();
    let elements = mesh.elements();
    if elements.is_empty() || !(delta > 0.0) {
        return None;
    }
    let n = x.len();
    // per vertex: component, position and arc length along it, left normal
    let (mut comp, mut pos, mut arc, mut left) =
        (vec![usize::MAX; n], vec![0; n], vec![0.0; n], vec![Point::<2>::zeros(); n]);
    let cycles = mesh.cycles();
    let mut perimeter = vec![0.0; cycles.len()];
    for (c, cycle) in cycles.iter().enumerate() {
        let m = cycle.len();
        for (k, &v) in cycle.iter().enumerate() {
            let (prev, next) = (cycle[(k + m - 1) % m], cycle[(k + 1) % m]);
            let (a, b) = (x[v] - mesh.lift(x[prev], &x[v]), mesh.lift(x[next], &x[v]) - x[v]);
            (comp[v], pos[v], arc[v]) = (c, k, perimeter[c]);
            left[v] = rot90(a + b);
            perimeter[c] += b.norm();
        }
    }
    let longest = elements.iter().map(|&[a, b]| (mesh.lift(x[b], &x[a]) - x[a]).norm()).fold(0.0, f64::max);
    // segments bucketed by midpoint on a grid of cells at least δ + longest/2 wide,
    // so that every segment within δ of a vertex lies in its cell or a neighbour
    let cell = delta + 0.5 * longest;
    let grid = Grid::new(cell, mesh.period());
    let mut buckets: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (e, &[a, b]) in elements.iter().enumerate() {
        let mid = x[a] + 0.5 * (mesh.lift(x[b], &x[a]) - x[a]);
        buckets.entry(grid.key(mid)).or_default().push(e);
    }
    // far enough apart along the curve: `q` at arc length `s` on the segment from `v`
    let apart = |i: usize, v: usize, s: f64| {
        if comp[i] != comp[v] {
            return true;
        }
        let m = cycles[comp[i]].len();
        let k = pos[i].abs_diff(pos[v]);
        let p = perimeter[comp[i]];
        let along = (arc[v] + s - arc[i]).rem_euclid(p);
        k.min(m - k) >= MIN_SEPARATION && along.min(p - along) >= MIN_ARC * delta
    };
    let mut best: Option<Contact> = None;
    for i in 0..n {
        if comp[i] == usize::MAX {
            continue;
        }
        for key in grid.neighbours(grid.key(x[i])) {
            for &e in buckets.get(&key).map_or(&[][..], |v| &v[..]) {
                let [a, b] = elements[e];
                let pa = mesh.lift(x[a], &x[i]);
                let ab = mesh.lift(x[b], &pa) - pa;
                let t = ((x[i] - pa).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
                let d = pa + t * ab - x[i];
                let dist = d.norm();
                if dist >= delta || best.is_some_and(|c| c.distance <= dist) {
                    continue;
                }
                if !(apart(i, a, t * ab.norm()) && apart(i, b, 0.0)) {
                    continue;
                }
                let nab = rot90(ab);
                if left[i].dot(&d) > 0.0 && nab.dot(&d) < 0.0 && left[i].dot(&nab) < 0.0 {
                    best = Some(Contact { distance: dist, vertex: i, element: e, t });
                }
            }
        }
    }
    best
}

/// The curve with its closest contact closer than `delta` made into a crossing, or
/// `None` when there is none (or when pushing the pair together does not make the
/// segments cross, which the crossing resolution needs).
pub fn close_contact(mesh: &CurveMesh, delta: f64) -> Option<CurveMesh> {
    let c = find_contact(mesh, delta)?;
    let x = mesh.positions();
    let [a, b] = mesh.elements()[c.element];
    let p = x[c.vertex];
    let pa = mesh.lift(x[a], &p);
    let ab = mesh.lift(x[b], &pa) - pa;
    let d = pa + c.t * ab - p;
    let shorter = ab.norm().min(neighbour_segment(mesh, c.vertex));
    let push = 0.25 * shorter * d / d.norm().max(1e-300);
    let half = 0.5 * (d + push);
    let mut moved = x.to_vec();
    moved[c.vertex] = p + half;
    moved[a] -= half;
    moved[b] -= half;
    let touched = mesh.with_positions(moved);
    (!touched.crossings().is_empty()).then_some(touched)
}

/// The shorter of the two segments at vertex `v`.
fn neighbour_segment(mesh: &CurveMesh, v: usize) -> f64 {
    let x = mesh.positions();
    mesh.elements()
        .iter()
        .filter(|e| e[0] == v || e[1] == v)
        .map(|&[a, b]| (mesh.lift(x[b], &x[a]) - x[a]).norm())
        .fold(f64::INFINITY, f64::min)
}

/// Square cells of side at least `cell`; on the cylinder the columns wrap around.
struct Grid {
    cell: f64,
    /// Number of columns and the period, for periodic meshes.
    columns: Option<(i64, f64)>,
}

impl Grid {
    fn new(cell: f64, period: Option<f64>) -> Self {
        match period {
            Some(l) => {
                let cols = ((l / cell).floor() as i64).max(1);
                Grid { cell, columns: Some((cols, l / cols as f64)) }
            }
            None => Grid { cell, columns: None },
        }
    }

    fn key(&self, p: Point<2>) -> (i64, i64) {
        let row = (p.y / self.cell).floor() as i64;
        match self.columns {
            Some((cols, width)) => {
                let l = width * cols as f64;
                (((p.x.rem_euclid(l) / width).floor() as i64).min(cols - 1), row)
            }
            None => ((p.x / self.cell).floor() as i64, row),
        }
    }

    /// The cell and its eight neighbours, each once.
    fn neighbours(&self, (i, j): (i64, i64)) -> Vec<(i64, i64)> {
        let mut out = Vec::with_capacity(9);
        for di in -1..=1 {
            let col = match self.columns {
                Some((cols, _)) => (i + di).rem_euclid(cols),
                None => i + di,
            };
            for dj in -1..=1 {
                if !out.contains(&(col, j + dj)) {
                    out.push((col, j + dj));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{polygon, resolve_intersections};

    /// Counter-clockwise outline of two 1×1 squares joined by a neck of width `gap`.
    fn dumbbell(gap: f64) -> CurveMesh {
        let g = 0.5 * gap;
        let pts: Vec<Point<2>> = [
            [-1.0, -0.5],
            [-0.1, -0.5],
            [0.0, -g],
            [0.1, -0.5],
            [1.0, -0.5],
            [1.0, 0.5],
            [0.1, 0.5],
            [0.0, g],
            [-0.1, 0.5],
            [-1.0, 0.5],
        ]
        .iter()
        .map(|p| Point::<2>::new(p[0], p[1]))
        .collect();
        polygon(&pts, Some(80)).unwrap()
    }

    /// A neck narrower than `δ` pinches into two lobes of the right areas; a wider
    /// one does not, nor does any part of a convex curve.
    #[test]
    fn a_neck_narrower_than_the_contact_distance_pinches() {
        assert!(close_contact(&dumbbell(0.3), 0.1).is_none());
        let narrow = dumbbell(0.05);
        let c = find_contact(&narrow, 0.1).expect("a contact");
        assert!((c.distance - 0.05).abs() < 0.02, "{c:?}");
        let touched = close_contact(&narrow, 0.1).expect("a contact");
        let split = resolve_intersections(&touched, 1e-6, false).unwrap().expect("a crossing");
        assert_eq!(split.num_components(), 2);
        let areas = split.component_measures();
        assert!(areas.iter().all(|a| (a - 0.95).abs() < 0.05), "{areas:?}");
        let circle = crate::geometry::circle([0.0, 0.0], 1.0, 64).unwrap();
        assert!(find_contact(&circle, 0.5).is_none());
    }

    /// Across the solid (the exterior) nothing touches: a thin strip of exterior
    /// between two lobes of a U-shaped curve is not a contact.
    #[test]
    fn parts_facing_across_the_exterior_do_not_touch() {
        // a U: its two arms 0.05 apart across the exterior notch between them
        let pts: Vec<Point<2>> =
            [[0.0, 0.0], [2.05, 0.0], [2.05, 2.0], [1.05, 2.0], [1.05, 0.5], [1.0, 0.5], [1.0, 2.0], [0.0, 2.0]]
                .iter()
                .map(|p| Point::<2>::new(p[0], p[1]))
                .collect();
        let u = polygon(&pts, Some(120)).unwrap();
        assert!(find_contact(&u, 0.1).is_none());
    }
}
