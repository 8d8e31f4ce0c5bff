//! Intersections of triangulated surfaces: whether any two triangles that share
//! no vertex meet (touch or cross), across all components of a mesh and within
//! each. The broad phase lays the triangles' bounding boxes on a uniform grid
//! (cells of about two mean edge lengths) and tests each pair once, in the cell
//! that holds the lowest corner of the intersection of their boxes; the narrow
//! phase decides with Shewchuk's exact `orient3d` (the `robust` crate): two
//! triangles that do not lie in one plane meet exactly when an edge of one meets
//! the other, and an edge meets a triangle when its ends are not strictly on one
//! side of the triangle's plane and it passes on the same side of (or on) the
//! three edges of the triangle. Coplanar pairs are decided in the plane of the
//! largest projection by `orient2d`.
//!
//! Triangles that share a vertex are not tested: their contact is a fold of the
//! surface, which the flow's tangling rule rejects.

use super::Point;
use robust::{orient2d, orient3d, Coord, Coord3D};

/// Cells of the broad phase, in mean edge lengths.
pub(super) const CELL_EDGES: f64 = 2.0;

/// Cells a triangle may cover at most before it is kept aside and tested against
/// every other (a triangle far larger than the mean: a coarse cap).
pub(super) const MAX_CELLS: usize = 512;

/// The first pair of triangles `(a, b)`, `a < b`, that share no vertex and meet;
/// `None` if no two such triangles meet.
pub fn first_surface_intersection(positions: &[Point<3>], triangles: &[[usize; 3]]) -> Option<(usize, usize)> {
    let mut hits = surface_intersections(positions, triangles, 1);
    hits.pop()
}

/// Up to `most` pairs of triangles that share no vertex and meet, each once.
pub fn surface_intersections(positions: &[Point<3>], triangles: &[[usize; 3]], most: usize) -> Vec<(usize, usize)> {
    let mut hits = Vec::new();
    if triangles.len() < 2 || most == 0 {
        return hits;
    }
    let boxes: Vec<Aabb> = triangles.iter().map(|t| bounds(positions, t)).collect();
    let cell = CELL_EDGES * mean_edge(positions, triangles);
    box_pairs(&boxes, cell, |a, b| {
        let (ta, tb) = (&triangles[a], &triangles[b]);
        if !ta.iter().any(|v| tb.contains(v)) && triangles_meet(positions, ta, tb) {
            hits.push((a.min(b), a.max(b)));
        }
        hits.len() >= most
    });
    hits
}

/// An axis-aligned box: its lowest and highest corners.
pub(super) type Aabb = ([f64; 3], [f64; 3]);

/// The mean edge length of `triangles` (each interior edge counted twice).
pub(super) fn mean_edge(positions: &[Point<3>], triangles: &[[usize; 3]]) -> f64 {
    let mut edge_sum = 0.0;
    for t in triangles {
        for k in 0..3 {
            edge_sum += (positions[t[(k + 1) % 3]] - positions[t[k]]).norm();
        }
    }
    edge_sum / (3 * triangles.len()).max(1) as f64
}

/// The broad phase: `visit(a, b)` once for every pair of `boxes` that overlap,
/// until it returns `true`. The boxes are laid on a uniform grid of side `cell`; a
/// pair is visited in the cell that holds the lowest corner of the intersection of
/// its boxes. A box that covers more than [`MAX_CELLS`] cells is kept aside and
/// paired with every other.
pub(super) fn box_pairs(boxes: &[Aabb], cell: f64, mut visit: impl FnMut(usize, usize) -> bool) {
    if !(cell.is_finite() && cell > 0.0) {
        return;
    }
    let index = |x: f64| (x / cell).floor() as i64;
    // (cell, triangle) for every cell a triangle's box covers, sorted by cell: a
    // cell's triangles are a run of the list (no hashing, no list per cell)
    let mut entries: Vec<(u64, u32)> = Vec::with_capacity(8 * boxes.len());
    let mut large = Vec::new();
    for (t, (lo, hi)) in boxes.iter().enumerate() {
        let (l, h) = (lo.map(index), hi.map(index));
        let count = (0..3).map(|k| (h[k] - l[k] + 1) as usize).product::<usize>();
        if count > MAX_CELLS {
            large.push(t);
            continue;
        }
        for i in l[0]..=h[0] {
            for j in l[1]..=h[1] {
                for k in l[2]..=h[2] {
                    entries.push((pack([i, j, k]), t as u32));
                }
            }
        }
    }
    entries.sort_unstable();
    let mut start = 0;
    while start < entries.len() {
        let key = entries[start].0;
        let end = start + entries[start..].iter().take_while(|e| e.0 == key).count();
        let members = &entries[start..end];
        for (m, &(_, a)) in members.iter().enumerate() {
            for &(_, b) in &members[m + 1..] {
                let (a, b) = (a as usize, b as usize);
                if !overlap(&boxes[a], &boxes[b]) {
                    continue;
                }
                if overlap_cell(&boxes[a], &boxes[b], cell) == key && visit(a, b) {
                    return;
                }
            }
        }
        start = end;
    }
    for (m, &a) in large.iter().enumerate() {
        for b in 0..boxes.len() {
            // a pair of two large ones once
            if b == a || large[..m].contains(&b) || !overlap(&boxes[a], &boxes[b]) {
                continue;
            }
            if visit(a, b) {
                return;
            }
        }
    }
}

/// The key of the cell (side `cell`) that holds the lowest corner of the overlap
/// of two boxes: the one cell in which a broad phase visits the pair.
pub(super) fn overlap_cell(a: &Aabb, b: &Aabb, cell: f64) -> u64 {
    pack([0, 1, 2].map(|k| (a.0[k].max(b.0[k]) / cell).floor() as i64))
}

/// A grid cell's key: its three indices, 21 bits each (wrapped).
pub(super) fn pack(c: [i64; 3]) -> u64 {
    let b = |v: i64| (v.rem_euclid(1 << 21)) as u64;
    b(c[0]) | b(c[1]) << 21 | b(c[2]) << 42
}

/// The box of triangle `t`'s corners.
pub(super) fn bounds(x: &[Point<3>], t: &[usize; 3]) -> Aabb {
    around(t.iter().map(|&v| &x[v]))
}

/// The box around `points` (a NaN coordinate widens nothing; the narrow phase
/// sees it).
pub(super) fn around<'a>(points: impl Iterator<Item = &'a Point<3>>) -> Aabb {
    let mut b = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            if p[k] < b.0[k] {
                b.0[k] = p[k];
            }
            if p[k] > b.1[k] {
                b.1[k] = p[k];
            }
        }
    }
    b
}

pub(super) fn overlap(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
}

fn c3(p: &Point<3>) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

/// Whether triangles `a` and `b` (sharing no vertex) touch or cross.
pub(super) fn triangles_meet(x: &[Point<3>], a: &[usize; 3], b: &[usize; 3]) -> bool {
    points_meet(&a.map(|v| x[v]), &b.map(|v| x[v]))
}

/// Whether the triangles of corners `pa` and `pb` (sharing no corner) touch or
/// cross, decided exactly.
pub(super) fn points_meet(pa: &[Point<3>; 3], pb: &[Point<3>; 3]) -> bool {
    let (pa, pb) = (*pa, *pb);
    let side = |t: &[Point<3>; 3], p: &Point<3>| orient3d(c3(&t[0]), c3(&t[1]), c3(&t[2]), c3(p));
    let sa = pa.map(|p| side(&pb, &p));
    let sb = pb.map(|p| side(&pa, &p));
    // all of one strictly on one side of the other's plane
    let apart = |s: &[f64; 3]| s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0);
    if apart(&sa) || apart(&sb) {
        return false;
    }
    if sa.iter().all(|&v| v == 0.0) {
        return coplanar_meet(&pa, &pb);
    }
    (0..3).any(|k| edge_meets(&pa[k], &pa[(k + 1) % 3], &pb))
        || (0..3).any(|k| edge_meets(&pb[k], &pb[(k + 1) % 3], &pa))
}

/// Whether the segment `p q` meets the triangle `t` (not in its plane as a whole).
fn edge_meets(p: &Point<3>, q: &Point<3>, t: &[Point<3>; 3]) -> bool {
    let (sp, sq) = (orient3d(c3(&t[0]), c3(&t[1]), c3(&t[2]), c3(p)), orient3d(c3(&t[0]), c3(&t[1]), c3(&t[2]), c3(q)));
    if (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) || (sp == 0.0 && sq == 0.0) {
        return false;
    }
    // the line p q passes each edge of t on the same side, or on it
    let around: [f64; 3] = [0, 1, 2].map(|k| orient3d(c3(p), c3(q), c3(&t[k]), c3(&t[(k + 1) % 3])));
    around.iter().all(|&v| v >= 0.0) || around.iter().all(|&v| v <= 0.0)
}

/// Two triangles in one plane: an edge of one crosses an edge of the other, or a
/// vertex of one lies in the other (in the projection that drops the axis of the
/// plane's largest normal component).
fn coplanar_meet(a: &[Point<3>; 3], b: &[Point<3>; 3]) -> bool {
    let n = (a[1] - a[0]).cross(&(a[2] - a[0]));
    let drop = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    let (u, v) = match drop {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let c = |p: &Point<3>| Coord { x: p[u], y: p[v] };
    let o = |p: &Point<3>, q: &Point<3>, r: &Point<3>| orient2d(c(p), c(q), c(r));
    let inside = |t: &[Point<3>; 3], p: &Point<3>| {
        let s = [o(&t[0], &t[1], p), o(&t[1], &t[2], p), o(&t[2], &t[0], p)];
        s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
    };
    let cross = |p: &Point<3>, q: &Point<3>, r: &Point<3>, s: &Point<3>| {
        let (d1, d2) = (o(p, q, r), o(p, q, s));
        let (d3, d4) = (o(r, s, p), o(r, s, q));
        (d1 * d2 <= 0.0) && (d3 * d4 <= 0.0) && !(d1 == 0.0 && d2 == 0.0 && d3 == 0.0 && d4 == 0.0)
    };
    (0..3).any(|i| (0..3).any(|j| cross(&a[i], &a[(i + 1) % 3], &b[j], &b[(j + 1) % 3])))
        || a.iter().any(|p| inside(b, p))
        || b.iter().any(|p| inside(a, p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::icosphere;

    fn shifted(mesh: &crate::geometry::SurfaceMesh, dx: f64) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
        let x = mesh.positions().iter().map(|p| p + Point::<3>::new(dx, 0.0, 0.0)).collect();
        (x, mesh.elements().to_vec())
    }

    /// Two unit spheres: apart, touching in a thin lens, overlapping; every hit is a
    /// pair of triangles of different spheres, and a brute-force search over all
    /// pairs finds the same pairs.
    #[test]
    fn two_spheres_meet_exactly_when_they_overlap() {
        let s = icosphere([0.0; 3], 1.0, 3).unwrap();
        let n = s.elements().len();
        for (gap, meet) in [(2.05, false), (1.9, true), (1.0, true)] {
            let (mut x, mut t) = shifted(&s, 0.0);
            let (x2, t2) = shifted(&s, gap);
            let offset = x.len();
            x.extend(x2);
            t.extend(t2.iter().map(|e| e.map(|v| v + offset)));
            let mut hits = surface_intersections(&x, &t, usize::MAX);
            hits.sort();
            assert_eq!(!hits.is_empty(), meet, "gap {gap}");
            assert!(hits.iter().all(|&(a, b)| a < n && b >= n), "only pairs across the spheres");
            let mut brute = Vec::new();
            for a in 0..t.len() {
                for b in a + 1..t.len() {
                    if !t[a].iter().any(|v| t[b].contains(v)) && triangles_meet(&x, &t[a], &t[b]) {
                        brute.push((a, b));
                    }
                }
            }
            assert_eq!(hits, brute, "gap {gap}");
        }
    }

    #[test]
    fn crossing_touching_and_coplanar_triangles() {
        let p = |x: f64, y: f64, z: f64| Point::<3>::new(x, y, z);
        let x = vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            // pierces the first through its middle
            p(0.2, 0.2, -1.0),
            p(0.2, 0.2, 1.0),
            p(0.3, 0.4, 1.0),
            // coplanar, overlapping
            p(0.1, 0.1, 0.0),
            p(2.0, 0.1, 0.0),
            p(0.1, 2.0, 0.0),
            // above, apart
            p(0.0, 0.0, 0.5),
            p(1.0, 0.0, 0.5),
            p(0.0, 1.0, 0.5),
        ];
        let meet = |a: [usize; 3], b: [usize; 3]| triangles_meet(&x, &a, &b);
        assert!(meet([0, 1, 2], [3, 4, 5]));
        assert!(meet([0, 1, 2], [6, 7, 8]));
        assert!(!meet([0, 1, 2], [9, 10, 11]));
        assert!(meet([3, 4, 5], [9, 10, 11]), "the piercing one crosses the plane z = 0.5 inside");
    }
}
