//! The exhaustive intersection search of a surface whose connectivity is reused
//! from one search to the next (a flow's trial steps), with most pairs of
//! neighbouring triangles proved apart a patch at a time instead of tested.
//!
//! The connectivity is cut once into patches ([`patches`]: the triangles of a
//! cell of a grid, about 500 triangles wide, whose normals point most nearly along
//! one of the six axis directions, connected across edges); each that is a
//! topological disk keeps its boundary loop. At each search a disk patch is
//! *embedded* (no two of its triangles meet outside the vertices and edges they
//! share) when, dropping the axis `k` of the largest component of its area
//! vector, every triangle projects with the same strict orientation and the
//! projected boundary loop is simple, both decided exactly (`orient2d` on the
//! coordinates as they are). The proof is the degree of the projection `π`:
//! orientation-preserving on every triangle, its number of preimages of a point
//! off `π(∂P)` is the winding number of `π(∂P)` around it, at most 1 for a simple
//! loop; so `π` is injective and the patch a graph over the plane.
//!
//! Pairs within an embedded patch are not tested. All other pairs of triangles
//! whose boxes overlap are, with the narrow phase of [`surface_intersections`]:
//! those within a patch not proved embedded (through the exhaustive search's
//! broad phase), and those of two patches whose boxes overlap (the triangles of
//! each inside the other's box, found by runs of [`CHUNK`] triangles and swept
//! along the longest side of the overlap). The result is the exhaustive search's:
//! the same pairs, in another order. When fewer than half of the disk patches
//! are embedded (the surface has left the shape they were cut for far behind),
//! they are cut again at the next search.
//!
//! [`surface_intersections`]: super::surface_intersections

mod patches;
#[cfg(test)]
mod tests;

use super::surface_intersections::{box_pairs, overlap, points_meet, surface_intersections, Aabb};
use super::Point;
use patches::Patches;
use robust::{orient2d, Coord};

/// Triangles of a run along a patch's rings, boxed together.
const CHUNK: usize = 16;

/// The search (see the module documentation); it keeps the patches of the last
/// connectivity searched.
#[derive(Debug, Clone, Default)]
pub struct PatchSearch {
    patches: Patches,
    /// Scratch: the corners and boxes of the triangles by slot.
    corners: Vec<[Point<3>; 3]>,
    boxes: Vec<Aabb>,
    /// Whether the patches are cut again at the next search.
    stale: bool,
    /// Of the last search: patches, patches proved embedded, pairs of patches
    /// whose boxes overlap, and pairs of triangles tested (for tests and
    /// benchmarks).
    pub patches_searched: usize,
    pub embedded: usize,
    pub neighbours: usize,
    pub tested: usize,
}

impl PatchSearch {
    /// Whether the patches kept are those of `triangles` (a search of them
    /// cuts none).
    pub fn knows(&self, triangles: &[[usize; 3]]) -> bool {
        self.patches.triangles == triangles
    }

    /// Up to `most` pairs `(a, b)`, `a < b`, of `triangles` that share no vertex
    /// and meet at `x`, each once ([`surface_intersections`] of the same input:
    /// the same pairs when all are asked for).
    ///
    /// [`surface_intersections`]: super::surface_intersections
    pub fn intersections(&mut self, x: &[Point<3>], triangles: &[[usize; 3]], most: usize) -> Vec<(usize, usize)> {
        let mut hits = Vec::new();
        (self.patches_searched, self.embedded, self.neighbours, self.tested) = (0, 0, 0, 0);
        if triangles.len() < 2 || most == 0 {
            return hits;
        }
        if self.stale || self.patches.triangles != triangles {
            self.patches = Patches::new(x, triangles);
        }
        let (p, tested, neighbours) = (&self.patches, &mut self.tested, &mut self.neighbours);
        // everything by slot (a triangle's place in the patches' order): a
        // patch's triangles lie side by side in memory
        let (corners, boxes) = (&mut self.corners, &mut self.boxes);
        corners.clear();
        corners.extend(p.slots.iter().map(|t| t.map(|v| x[v])));
        boxes.clear();
        boxes.extend(corners.iter().map(box_of));
        let (corners, boxes) = (&*corners, &*boxes);
        // runs of CHUNK triangles of a patch (along its rings) and their boxes:
        // a patch's triangles near another patch are found run by run
        let (mut chunks, mut first_chunk) = (Vec::new(), Vec::with_capacity(p.patches.len() + 1));
        for patch in &p.patches {
            first_chunk.push(chunks.len());
            for s in (patch.start..patch.end).step_by(CHUNK) {
                let e = (s + CHUNK).min(patch.end);
                chunks.push((s, e, union(boxes[s..e].iter())));
            }
        }
        first_chunk.push(chunks.len());
        let patch_boxes: Vec<Aabb> = (0..p.patches.len())
            .map(|q| union(chunks[first_chunk[q]..first_chunk[q + 1]].iter().map(|c| &c.2)))
            .collect();
        // pairs of patches are visited on a grid of the patches' typical size
        let mut sides: Vec<f64> =
            patch_boxes.iter().map(|b| (0..3).map(|k| b.1[k] - b.0[k]).fold(0.0, f64::max)).collect();
        sides.sort_unstable_by(f64::total_cmp);
        let cell = sides[sides.len() / 2];
        if !(cell.is_finite() && cell > 0.0) {
            return surface_intersections(x, triangles, most);
        }
        let mut test = |i: usize, j: usize, hits: &mut Vec<(usize, usize)>| {
            let (ti, tj) = (&p.slots[i], &p.slots[j]);
            if overlap(&boxes[i], &boxes[j]) && !ti.iter().any(|v| tj.contains(v)) {
                *tested += 1;
                if points_meet(&corners[i], &corners[j]) {
                    let (a, b) = (p.order[i] as usize, p.order[j] as usize);
                    hits.push((a.min(b), a.max(b)));
                }
            }
            hits.len() >= most
        };
        self.patches_searched = p.patches.len();
        for patch in &p.patches {
            let (start, end) = (patch.start, patch.end);
            if patch.boundary.as_deref().is_some_and(|lp| embedded(x, &corners[start..end], lp)) {
                self.embedded += 1;
                continue;
            }
            // the patch's own pairs through the exhaustive search's broad phase
            let edges: f64 =
                corners[start..end].iter().map(|c| (0..3).map(|k| (c[(k + 1) % 3] - c[k]).norm()).sum::<f64>()).sum();
            let cell = 2.0 * edges / (3 * (end - start)) as f64;
            if !(cell.is_finite() && cell > 0.0) {
                return surface_intersections(x, triangles, most);
            }
            let mut full = false;
            box_pairs(&boxes[start..end], cell, |i, j| {
                full = test(start + i, start + j, &mut hits);
                full
            });
            if full {
                return hits;
            }
        }
        // patches cut for a shape the surface has left far behind are cut again
        // at the next search
        let disks = p.patches.iter().filter(|q| q.boundary.is_some()).count();
        self.stale = 2 * self.embedded < disks;
        let (mut near_a, mut near_b) = (Vec::new(), Vec::new());
        box_pairs(&patch_boxes, cell, |qa, qb| {
            *neighbours += 1;
            let (ba, bb) = (&patch_boxes[qa], &patch_boxes[qb]);
            // sweep along the longest side of the two boxes' overlap
            let side = |k: usize| ba.1[k].min(bb.1[k]) - ba.0[k].max(bb.0[k]);
            let axis = (0..3).max_by(|&i, &j| side(i).total_cmp(&side(j))).unwrap_or(0);
            let lo = |i: usize| boxes[i].0[axis];
            let hi = |i: usize| boxes[i].1[axis];
            for (near, q, other) in [(&mut near_a, qa, bb), (&mut near_b, qb, ba)] {
                near.clear();
                for &(s, e, _) in chunks[first_chunk[q]..first_chunk[q + 1]].iter().filter(|c| overlap(&c.2, other)) {
                    near.extend((s..e).filter(|&i| overlap(&boxes[i], other)));
                }
                near.sort_unstable_by(|&i, &j| lo(i).total_cmp(&lo(j)));
            }
            // each pair whose extents along the axis overlap, once: from the one
            // that starts first
            let (mut i, mut j) = (0, 0);
            while i < near_a.len() && j < near_b.len() {
                let (a, b) = (near_a[i], near_b[j]);
                if lo(a) <= lo(b) {
                    for &b in near_b[j..].iter().take_while(|&&b| lo(b) <= hi(a)) {
                        if test(a, b, &mut hits) {
                            return true;
                        }
                    }
                    i += 1;
                } else {
                    for &a in near_a[i..].iter().take_while(|&&a| lo(a) <= hi(b)) {
                        if test(a, b, &mut hits) {
                            return true;
                        }
                    }
                    j += 1;
                }
            }
            false
        });
        hits
    }
}

/// The box of a triangle's corners.
fn box_of(c: &[Point<3>; 3]) -> Aabb {
    (
        std::array::from_fn(|k| c[0][k].min(c[1][k]).min(c[2][k])),
        std::array::from_fn(|k| c[0][k].max(c[1][k]).max(c[2][k])),
    )
}

/// The box around `boxes`.
fn union<'a>(boxes: impl Iterator<Item = &'a Aabb>) -> Aabb {
    let mut u = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for b in boxes {
        for k in 0..3 {
            u.0[k] = u.0[k].min(b.0[k]);
            u.1[k] = u.1[k].max(b.1[k]);
        }
    }
    u
}

/// Whether the disk patch of triangles of `corners` and boundary loop `lp`
/// (vertices of `x`) projects one to one onto the coordinate plane most nearly
/// parallel to it (module documentation).
fn embedded(x: &[Point<3>], corners: &[[Point<3>; 3]], lp: &[usize]) -> bool {
    let mut n = [0.0f64; 3];
    for [a, b, c] in corners {
        let area = (b - a).cross(&(c - a));
        for k in 0..3 {
            n[k] += area[k];
        }
    }
    let k = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    // (u, w) in cyclic order after k: orient2d is the area vector's k-th component
    let (u, w) = ((k + 1) % 3, (k + 2) % 3);
    let flat = |p: &Point<3>| Coord { x: p[u], y: p[w] };
    let sign = n[k].signum();
    sign != 0.0
        && corners.iter().all(|[a, b, c]| orient2d(flat(a), flat(b), flat(c)) * sign > 0.0)
        && simple_loop(&lp.iter().map(|&v| flat(&x[v])).collect::<Vec<_>>())
}

/// Whether the closed polygon through `pts` is simple: no two of its edges meet
/// but consecutive ones, at their common corner only (decided exactly).
fn simple_loop(pts: &[Coord<f64>]) -> bool {
    let b = pts.len();
    if b < 3 {
        return false;
    }
    let next = |i: usize| if i + 1 == b { 0 } else { i + 1 };
    // the edges (index, ends, extent along x), by their left end
    let mut edges: Vec<(usize, Coord<f64>, Coord<f64>, f64, f64)> = (0..b)
        .map(|i| {
            let (p, q) = (pts[i], pts[next(i)]);
            (i, p, q, p.x.min(q.x), p.x.max(q.x))
        })
        .collect();
    edges.sort_unstable_by(|e, f| e.3.total_cmp(&f.3));
    for (m, &(i, p, q, _, right)) in edges.iter().enumerate() {
        for &(j, r, s, left, _) in &edges[m + 1..] {
            if left > right {
                break;
            }
            let meet = if j == next(i) {
                folds_back(p, q, s)
            } else if i == next(j) {
                folds_back(r, s, q)
            } else {
                p.y.max(q.y) >= r.y.min(s.y) && r.y.max(s.y) >= p.y.min(q.y) && segments_meet(p, q, r, s)
            };
            if meet {
                return false;
            }
        }
    }
    true
}

/// Whether the edges `p q` and `q r` overlap beyond `q`: collinear, `r` on the
/// side of `q` where `p` lies.
fn folds_back(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>) -> bool {
    if orient2d(p, q, r) != 0.0 {
        return false;
    }
    let side = |a: f64, b: f64| sign(a - b);
    let (sp, sr) = match p.x != q.x {
        true => (side(p.x, q.x), side(r.x, q.x)),
        false => (side(p.y, q.y), side(r.y, q.y)),
    };
    sp * sr >= 0
}

/// Whether the closed segments `p q` and `r s` meet.
fn segments_meet(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>, s: Coord<f64>) -> bool {
    let (d1, d2) = (sign(orient2d(p, q, r)), sign(orient2d(p, q, s)));
    if d1 == 0 && d2 == 0 {
        // on one line: their extents overlap
        let over = |a: f64, b: f64, c: f64, d: f64| a.min(b) <= c.max(d) && c.min(d) <= a.max(b);
        return over(p.x, q.x, r.x, s.x) && over(p.y, q.y, r.y, s.y);
    }
    let (d3, d4) = (sign(orient2d(r, s, p)), sign(orient2d(r, s, q)));
    d1 * d2 <= 0 && d3 * d4 <= 0
}

/// The sign of `v`: -1, 0 (either zero) or 1.
fn sign(v: f64) -> i8 {
    (v > 0.0) as i8 - (v < 0.0) as i8
}
