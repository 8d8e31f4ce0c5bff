//! The exhaustive intersection search of a surface whose connectivity is reused
//! from one search to the next (a flow's trial steps), with most pairs of
//! neighbouring triangles proved apart a patch at a time instead of tested.
//!
//! The connectivity is cut once into patches ([`patches`]: the triangles of a
//! cell of a grid, about 500 triangles wide, whose normals point most nearly along
//! one of the six axis directions, connected across edges); each that is a
//! topological disk keeps its boundary loop. At each search a disk patch is
//! *embedded* (no two of its triangles meet outside the vertices and edges they
//! share) when, dropping the axis `k` of its class (else that of the largest
//! component of its area vector), every triangle projects with the same strict
//! orientation and the
//! projected boundary loop is simple, both decided exactly (`orient2d` on the
//! coordinates as they are). The proof is the degree of the projection `π`:
//! orientation-preserving on every triangle, its number of preimages of a point
//! off `π(∂P)` is the winding number of `π(∂P)` around it, at most 1 for a simple
//! loop; so `π` is injective and the patch a graph over the plane. (A loop is
//! proved simple by a star test, every edge turning one way seen from the mean
//! of its corners and the loop once round it, or else by a sweep.)
//!
//! The same argument proves larger disks embedded: [`groups`] (disk patches of
//! one class glued along single arcs, block by block of an octree of cells and
//! then over the whole grid, their loops kept) and [`seams`] (two disk patches
//! sharing one arc). A group or seam is embedded when all its triangles project
//! with one strict orientation onto one coordinate plane and its loop projects
//! simple there. Groups are tried from the top level down: one inside a group
//! proved already is not tried. The boxes of the runs of triangles below are
//! drawn from each run's vertices, once each; those of single triangles only
//! where two patches' boxes overlap.
//!
//! Pairs within an embedded patch, group or seam are not tested. All other
//! pairs of triangles whose boxes overlap are, with the narrow phase of
//! [`surface_intersections`]: those within a patch not proved embedded (through the exhaustive search's
//! broad phase), and those of two patches whose boxes overlap (the triangles of
//! each inside the other's box, found by runs of [`patches::CHUNK`] triangles and swept
//! along the longest side of the overlap). The result is the exhaustive search's:
//! the same pairs, in another order. When fewer than half as many patches are
//! embedded as at the first search after their cut (the surface has left the
//! shape they were cut for far behind), they are cut again at the next search;
//! patches few of which were embedded from the start are not cut again and
//! again.
//!
//! [`surface_intersections`]: super::surface_intersections

mod certify;
mod groups;
mod patches;
mod seams;
#[cfg(test)]
mod tests;

use super::surface_intersections::{around, bounds, box_pairs, overlap, points_meet, surface_intersections, Aabb};
use super::Point;
use certify::{embedded, loop_projects_simple};
use patches::Patches;

/// The search (see the module documentation); it keeps the patches of the last
/// two connectivities searched (a flow checks a new connectivity of the mesh
/// management, and its state before, in turn).
#[derive(Debug, Clone, Default)]
pub struct PatchSearch {
    patches: Patches,
    previous: Patches,
    /// Scratch: the boxes of a patch's triangles, and the runs of triangles
    /// (slots) with their boxes.
    boxes: Vec<Aabb>,
    chunk_boxes: Vec<(usize, usize, Aabb)>,
    /// Scratch: the plane over which each patch was proved embedded.
    planes: Vec<Option<(usize, bool)>>,
    /// Whether the patches are cut again at the next search.
    stale: bool,
    /// The last answer of [`PatchSearch::intersections_of_state`], and that of
    /// the last search that found every pair (or of [`PatchSearch::remember`]).
    kept: Option<Answer>,
    last: Option<Answer>,
    /// Of the last search: patches, patches proved embedded, pairs of patches
    /// whose boxes overlap, and pairs of triangles tested (for tests and
    /// benchmarks).
    pub patches_searched: usize,
    pub embedded: usize,
    pub neighbours: usize,
    pub tested: usize,
    /// Of the last search: groups proved embedded, and seams (not in one of
    /// them) whose two patches were proved embedded together.
    pub groups: usize,
    pub sealed: usize,
}

/// Positions, triangles and all their pairs that meet, sorted.
type Answer = (Vec<Point<3>>, Vec<[usize; 3]>, Vec<(usize, usize)>);

/// The pairs of `answer` if it is that of `x` and `triangles`.
fn known<'a>(answer: &'a Option<Answer>, x: &[Point<3>], triangles: &[[usize; 3]]) -> Option<&'a [(usize, usize)]> {
    let (kx, kt, pairs) = answer.as_ref()?;
    (kx.as_slice() == x && kt.as_slice() == triangles).then_some(pairs.as_slice())
}

impl PatchSearch {
    /// Whether the patches kept are those of `triangles` (a search of them
    /// cuts none).
    pub fn knows(&self, triangles: &[[usize; 3]]) -> bool {
        self.patches.triangles == triangles || self.previous.triangles == triangles
    }

    /// All pairs that meet at a state searched again and again (the state a
    /// flow's trial steps start from, against which each finds its new pairs),
    /// sorted: [`PatchSearch::intersections`], its last answer kept for the same
    /// positions and triangles.
    pub fn intersections_of_state(&mut self, x: &[Point<3>], triangles: &[[usize; 3]]) -> Vec<(usize, usize)> {
        if let Some(pairs) = known(&self.kept, x, triangles) {
            return pairs.to_vec();
        }
        let mut pairs = self.intersections(x, triangles, usize::MAX);
        pairs.sort_unstable();
        self.kept = Some((x.to_vec(), triangles.to_vec(), pairs.clone()));
        pairs
    }

    /// Keep `pairs` as every pair of `triangles` that meets at `x` (found by the
    /// caller, as [`revert_new_intersections`] finds them around the vertices it
    /// put back): the next search of that state answers with them.
    ///
    /// [`revert_new_intersections`]: crate::geometry::revert_new_intersections
    pub fn remember(&mut self, x: &[Point<3>], triangles: &[[usize; 3]], mut pairs: Vec<(usize, usize)>) {
        pairs.sort_unstable();
        self.last = Some((x.to_vec(), triangles.to_vec(), pairs));
    }

    /// Forget the answers kept: the next search of any state searches (for
    /// benchmarks of the search itself).
    pub fn forget(&mut self) {
        (self.kept, self.last) = (None, None);
    }

    /// Up to `most` pairs `(a, b)`, `a < b`, of `triangles` that share no vertex
    /// and meet at `x`, each once ([`surface_intersections`] of the same input:
    /// the same pairs when all are asked for). A state searched last in full (a
    /// flow's trial step, searched by its contact rule and then by its check) is
    /// answered from that search, in sorted order; the counts below are then
    /// those of that search.
    ///
    /// [`surface_intersections`]: super::surface_intersections
    pub fn intersections(&mut self, x: &[Point<3>], triangles: &[[usize; 3]], most: usize) -> Vec<(usize, usize)> {
        if let Some(pairs) = known(&self.last, x, triangles).or_else(|| known(&self.kept, x, triangles)) {
            return pairs.iter().take(most).copied().collect();
        }
        let hits = self.search(x, triangles, most);
        if hits.len() < most {
            self.remember(x, triangles, hits.clone());
        }
        hits
    }

    /// [`PatchSearch::intersections`] by a search.
    fn search(&mut self, x: &[Point<3>], triangles: &[[usize; 3]], most: usize) -> Vec<(usize, usize)> {
        let mut hits = Vec::new();
        (self.patches_searched, self.embedded, self.neighbours, self.tested) = (0, 0, 0, 0);
        (self.groups, self.sealed) = (0, 0);
        if triangles.len() < 2 || most == 0 {
            return hits;
        }
        if self.patches.triangles != triangles && self.previous.triangles == triangles {
            std::mem::swap(&mut self.patches, &mut self.previous);
            self.stale = false;
        }
        if self.patches.triangles != triangles {
            self.previous = std::mem::replace(&mut self.patches, Patches::new(x, triangles));
        } else if self.stale {
            self.patches = Patches::new(x, triangles);
        }
        let (p, tested, neighbours) = (&self.patches, &mut self.tested, &mut self.neighbours);
        // everything by slot (a triangle's place in the patches' order): a
        // patch's triangles lie side by side in memory
        // runs of `CHUNK` triangles of a patch (along its rings) and their boxes:
        // a patch's triangles near another patch are found run by run (the
        // boxes of triangles are drawn only there)
        let first_chunk = &p.first_chunk;
        let chunks = &mut self.chunk_boxes;
        chunks.clear();
        chunks.extend(p.chunks.iter().map(|c| {
            let (from, to) = c.vertices;
            (c.start, c.end, around(p.chunk_vertices[from as usize..to as usize].iter().map(|&v| &x[v as usize])))
        }));
        let chunks = &*chunks;
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
        let mut test = |(i, bi): (usize, &Aabb), (j, bj): (usize, &Aabb), hits: &mut Vec<(usize, usize)>| {
            let (ti, tj) = (&p.slots[i], &p.slots[j]);
            if overlap(bi, bj) && !ti.iter().any(|v| tj.contains(v)) {
                *tested += 1;
                if points_meet(&ti.map(|v| x[v]), &tj.map(|v| x[v])) {
                    let (a, b) = (p.order[i] as usize, p.order[j] as usize);
                    hits.push((a.min(b), a.max(b)));
                }
            }
            hits.len() >= most
        };
        self.patches_searched = p.patches.len();
        let planes = &mut self.planes;
        planes.clear();
        for patch in &p.patches {
            let (start, end) = (patch.start, patch.end);
            planes.push(patch.boundary.as_deref().and_then(|lp| embedded(x, &p.slots[start..end], lp, patch.plane)));
            if planes.last().is_some_and(Option::is_some) {
                self.embedded += 1;
                continue;
            }
            // the patch's own pairs through the exhaustive search's broad phase
            let edges: f64 = p.slots[start..end]
                .iter()
                .map(|t| (0..3).map(|k| (x[t[(k + 1) % 3]] - x[t[k]]).norm()).sum::<f64>())
                .sum();
            let cell = 2.0 * edges / (3 * (end - start)) as f64;
            if !(cell.is_finite() && cell > 0.0) {
                return surface_intersections(x, triangles, most);
            }
            let mut full = false;
            let boxes = &mut self.boxes;
            boxes.clear();
            boxes.extend(p.slots[start..end].iter().map(|t| bounds(x, t)));
            box_pairs(boxes, cell, |i, j| {
                full = test((start + i, &boxes[i]), (start + j, &boxes[j]), &mut hits);
                full
            });
            if full {
                return hits;
            }
        }
        // patches cut for a shape the surface has left far behind (fewer than
        // half as many embedded as on that shape) are cut again at the next
        // search; patches that were few embedded from the start are kept
        let at_cut = p.embedded_at_cut.get().unwrap_or(self.embedded);
        p.embedded_at_cut.set(Some(at_cut));
        self.stale = 2 * self.embedded < at_cut;
        // groups of patches embedded over one plane, and seams of two such patches
        // not in one of them, whose unions are too
        let certified = p.groups.certify(|g| {
            let plane = planes[g.patches[0] as usize];
            plane.is_some_and(|(k, ccw)| {
                g.patches.iter().all(|&q| planes[q as usize] == plane) && loop_projects_simple(x, &g.boundary, k, ccw)
            })
        });
        self.groups = certified.iter().filter(|&&c| c).count();
        let together = |a: usize, b: usize| p.groups.together(a, b, &certified);
        let loops: Vec<Option<&Vec<usize>>> = p.patches.iter().map(|q| q.boundary.as_ref()).collect();
        let of = |q: usize| &p.slots[p.patches[q].start..p.patches[q].end];
        let sealed: Vec<(u32, u32)> = (p.seams.iter())
            .filter(|seam| !together(seam.a as usize, seam.b as usize) && seam.sealed(x, &loops, of, planes))
            .map(|seam| (seam.a, seam.b))
            .collect();
        self.sealed = sealed.len();
        let (mut near_a, mut near_b) = (Vec::new(), Vec::new());
        box_pairs(&patch_boxes, cell, |qa, qb| {
            if together(qa, qb) || sealed.binary_search(&(qa.min(qb) as u32, qa.max(qb) as u32)).is_ok() {
                return false;
            }
            *neighbours += 1;
            let (ba, bb) = (&patch_boxes[qa], &patch_boxes[qb]);
            // sweep along the longest side of the two boxes' overlap
            let side = |k: usize| ba.1[k].min(bb.1[k]) - ba.0[k].max(bb.0[k]);
            let axis = (0..3).max_by(|&i, &j| side(i).total_cmp(&side(j))).unwrap_or(0);
            let lo = |(_, b): &(usize, Aabb)| b.0[axis];
            let hi = |(_, b): &(usize, Aabb)| b.1[axis];
            for (near, q, other) in [(&mut near_a, qa, bb), (&mut near_b, qb, ba)] {
                near.clear();
                for &(s, e, _) in chunks[first_chunk[q]..first_chunk[q + 1]].iter().filter(|c| overlap(&c.2, other)) {
                    near.extend((s..e).map(|i| (i, bounds(x, &p.slots[i]))).filter(|(_, b)| overlap(b, other)));
                }
                near.sort_unstable_by(|a, b| lo(a).total_cmp(&lo(b)));
            }
            // each pair whose extents along the axis overlap, once: from the one
            // that starts first
            let (mut i, mut j) = (0, 0);
            while i < near_a.len() && j < near_b.len() {
                let (a, b) = (&near_a[i], &near_b[j]);
                if lo(a) <= lo(b) {
                    for b in near_b[j..].iter().take_while(|b| lo(b) <= hi(a)) {
                        if test((a.0, &a.1), (b.0, &b.1), &mut hits) {
                            return true;
                        }
                    }
                    i += 1;
                } else {
                    for a in near_a[i..].iter().take_while(|a| lo(a) <= hi(b)) {
                        if test((a.0, &a.1), (b.0, &b.1), &mut hits) {
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
