//! The triangles of a surface gathered by their centroids into patches (the
//! cells of a grid), each with the box of its triangles and the cone of their
//! face normals, and the pairs of patches that may hold two triangles facing
//! each other.
//!
//! A patch's cone is the axis of its face normals' sum with the largest angle
//! of a normal to it. Two triangles of patches whose cones are less than
//! `arccos(OPPOSITE)` apart at their widest (the angle of the axes plus both
//! half-angles), or of one patch whose cone is less than that wide, have normals
//! less than that angle apart, and do not face each other. A patch's box is
//! that of its triangles' corners grown by a bound of their reach (the farthest
//! their curved patch may lie off them): each `(n_i − n_j)·(x_i − x_j)` is at
//! most twice the edge for unit normals, so the reach, an eighth of the sum of
//! the three, is at most `¾` of the longest edge. Nothing here needs the vertex
//! normals: a surface with no facing patches is decided in two passes over its
//! triangles.

use super::super::surface_intersections::{around, box_pairs, overlap, Aabb};
use super::super::Point;
use super::OPPOSITE;
use std::f64::consts::{FRAC_PI_3, PI};

/// The side of the cells whose triangles are gathered into one patch, in mean
/// edges (a flat sheet along a cell's face holds about 150 of its triangles).
const PATCH_EDGES: f64 = 8.0;

/// Triangles sampled for the mean edge that sets the cells' side.
const EDGE_SAMPLES: usize = 256;

/// The patches of a surface (see the module documentation).
pub(super) struct Cones {
    /// Unit face normals, by triangle.
    pub faces: Vec<Point<3>>,
    /// The patch of each triangle.
    patch_of: Vec<u32>,
    patches: Vec<Patch>,
    cell: f64,
}

/// The widest angle of two normals that do not face each other,
/// `arccos(OPPOSITE)`, less a margin for rounding.
fn widest() -> f64 {
    OPPOSITE.acos() - 1e-9
}

struct Patch {
    bounds: Aabb,
    /// The sum of the face normals, then its direction (zero where it is nearly
    /// nothing).
    axis: Point<3>,
    /// The largest angle of a face normal to `axis` (π where the axis is zero or
    /// a face has no normal).
    half_angle: f64,
    /// The cosine of `arccos(OPPOSITE) − half_angle` (+∞ where that is
    /// negative): a normal whose cosine to the axis is at least this faces no
    /// normal of the patch.
    facing_cos: f64,
    count: usize,
    longest_edge: f64,
    degenerate: bool,
}

impl Cones {
    /// The patches of `triangles` at `x`; `None` for no triangles or a position
    /// that is not finite.
    pub fn new(x: &[Point<3>], triangles: &[[usize; 3]]) -> Option<Self> {
        let (lo, hi) = around(x.iter());
        if triangles.is_empty() || !(0..3).all(|k| lo[k].is_finite() && hi[k].is_finite()) {
            return None;
        }
        let step = (triangles.len() / EDGE_SAMPLES).max(1);
        let (sum, count) = triangles
            .iter()
            .step_by(step)
            .fold((0.0, 0), |(s, n), t| (s + (0..3).map(|k| (x[t[(k + 1) % 3]] - x[t[k]]).norm()).sum::<f64>(), n + 3));
        let mut cell = PATCH_EDGES * sum / count as f64;
        if !(cell.is_finite() && cell > 0.0) {
            cell = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        }
        let cells_of = |cell: f64| (0..3).map(|k| ((hi[k] - lo[k]) / cell).floor() + 1.0).product::<f64>();
        while cells_of(cell) > (2 * triangles.len() + 64) as f64 {
            cell *= 1.5;
        }
        let n: [usize; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / cell) as usize + 1);
        let per_cell = 1.0 / cell;
        let mut patch_of_cell = vec![u32::MAX; n.iter().product()];
        let mut patches: Vec<Patch> = Vec::new();
        let mut patch_of = Vec::with_capacity(triangles.len());
        let faces = triangles
            .iter()
            .map(|t| {
                let p = t.map(|v| x[v]);
                let (e0, e1, e2) = (p[1] - p[0], p[2] - p[1], p[0] - p[2]);
                let c = e0.cross(&(p[2] - p[0]));
                let face = c / c.norm();
                let centroid = (p[0] + p[1] + p[2]) / 3.0;
                let i: [usize; 3] =
                    std::array::from_fn(|k| (((centroid[k] - lo[k]) * per_cell) as usize).min(n[k] - 1));
                let slot = &mut patch_of_cell[i[0] + n[0] * (i[1] + n[1] * i[2])];
                if *slot == u32::MAX {
                    *slot = patches.len() as u32;
                    patches.push(Patch {
                        bounds: ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                        axis: Point::<3>::zeros(),
                        half_angle: 0.0,
                        facing_cos: 0.0,
                        count: 0,
                        longest_edge: 0.0,
                        degenerate: false,
                    });
                }
                patch_of.push(*slot);
                let patch = &mut patches[*slot as usize];
                patch.count += 1;
                patch.axis += face;
                patch.degenerate |= !face.iter().all(|c| c.is_finite());
                let longest = e0.norm_squared().max(e1.norm_squared()).max(e2.norm_squared());
                patch.longest_edge = patch.longest_edge.max(longest);
                for q in &p {
                    for k in 0..3 {
                        patch.bounds.0[k] = patch.bounds.0[k].min(q[k]);
                        patch.bounds.1[k] = patch.bounds.1[k].max(q[k]);
                    }
                }
                face
            })
            .collect::<Vec<_>>();
        for p in &mut patches {
            let norm = p.axis.norm();
            p.axis = if norm > 1e-9 * p.count as f64 { p.axis / norm } else { Point::<3>::zeros() };
            p.half_angle = 1.0; // the least cosine to the axis, below
            let reach = 0.75 * p.longest_edge.sqrt();
            p.bounds = (p.bounds.0.map(|c| c - reach), p.bounds.1.map(|c| c + reach));
        }
        for (face, &p) in faces.iter().zip(&patch_of) {
            let p = &mut patches[p as usize];
            p.half_angle = p.half_angle.min(face.dot(&p.axis));
        }
        for p in &mut patches {
            let wide = p.degenerate || p.axis == Point::<3>::zeros();
            p.half_angle = if wide { PI } else { p.half_angle.clamp(-1.0, 1.0).acos() };
            let margin = widest() - p.half_angle;
            // the cosine rounded up a little, so that no facing normal is missed
            p.facing_cos = if margin <= 0.0 { f64::INFINITY } else { margin.cos() + 1e-12 };
        }
        Some(Cones { faces, patch_of, patches, cell })
    }

    /// The pairs of patches that may hold two triangles facing each other
    /// (`(p, p)` for one patch that may): their boxes overlap and their cones
    /// are wide enough.
    pub fn facing(&self) -> Vec<(usize, usize)> {
        let widest = widest();
        let patches = &self.patches;
        let mut pairs: Vec<(usize, usize)> =
            (0..patches.len()).filter(|&p| 2.0 * patches[p].half_angle > widest).map(|p| (p, p)).collect();
        let boxes: Vec<Aabb> = patches.iter().map(|p| p.bounds).collect();
        // cells of two patches: a box covers one to eight of them
        box_pairs(&boxes, 2.0 * self.cell, |a, b| {
            let (p, q) = (&patches[a], &patches[b]);
            let cones = p.half_angle + q.half_angle;
            let along = p.axis.dot(&q.axis);
            // axes within 60° and cones within 60° together: apart, no arccos needed
            let near = cones <= widest - FRAC_PI_3 && along >= 0.5;
            if !near && along.clamp(-1.0, 1.0).acos() + cones > widest {
                pairs.push((a, b));
            }
            false
        });
        pairs
    }

    /// The triangles of each patch that `wanted` marks (empty lists for the
    /// others).
    pub fn members(&self, wanted: &[bool]) -> Vec<Vec<usize>> {
        let mut members = vec![Vec::new(); self.patches.len()];
        for (t, &p) in self.patch_of.iter().enumerate() {
            if wanted[p as usize] {
                members[p as usize].push(t);
            }
        }
        members
    }

    /// Whether a triangle of unit normal `face` and (grown) box `bounds` may
    /// face a triangle of patch `p`: its box overlaps the patch's, and its
    /// normal is farther from the patch's axis than `arccos(OPPOSITE)` less
    /// the cone's half-angle.
    pub fn may_face(&self, face: Point<3>, bounds: &Aabb, p: usize) -> bool {
        let p = &self.patches[p];
        // farther from the axis than that angle: a cosine below its cosine
        overlap(bounds, &p.bounds) && !(face.dot(&p.axis) >= p.facing_cos)
    }

    pub fn len(&self) -> usize {
        self.patches.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::icosphere;

    /// The pruning is a proof, checked pair by pair at its threshold: on
    /// spheres whose vertices are jittered by up to an edge (normals of every
    /// direction among neighbours) and on smooth tori whose tube turns within a
    /// few patches, every pair of triangles whose normals are
    /// more than `arccos(OPPOSITE)` apart and whose boxes, grown by the bound of
    /// the reach, overlap lies in a facing pair of patches and passes
    /// [`Cones::may_face`] both ways.
    #[test]
    fn no_pair_of_facing_triangles_is_pruned() {
        let mut next = crate::geometry::test_numbers::numbers(11);
        let mut jitter = || next() - 0.5;
        let mut checked = 0;
        let surfaces = [(0.3, 1.0, 2), (0.6, 1.0, 3), (1.0, 1.0, 3), (0.05, 1.0, 4), (0.0, 0.06, 0), (0.0, 0.1, 0)];
        for (noise, minor, level) in surfaces {
            // jittered spheres, and tori whose tube is a few patches round
            let s = if minor < 1.0 {
                crate::geometry::torus([0.0; 3], 0.3, minor, 96, 24).unwrap()
            } else {
                icosphere([0.0; 3], 0.3, level).unwrap()
            };
            let t = s.elements();
            let h = super::super::super::surface_intersections::mean_edge(s.positions(), t);
            let x: Vec<Point<3>> =
                s.positions().iter().map(|p| p + Point::<3>::new(jitter(), jitter(), jitter()) * (noise * h)).collect();
            let cones = Cones::new(&x, t).unwrap();
            let facing: std::collections::HashSet<(usize, usize)> =
                cones.facing().into_iter().flat_map(|(p, q)| [(p, q), (q, p)]).collect();
            let grown = |a: usize| {
                let (lo, hi) = crate::geometry::surface_intersections::bounds(&x, &t[a]);
                let r = 0.75 * (0..3).map(|k| (x[t[a][(k + 1) % 3]] - x[t[a][k]]).norm()).fold(0.0, f64::max);
                (lo.map(|c| c - r), hi.map(|c| c + r))
            };
            for a in 0..t.len() {
                for b in a + 1..t.len() {
                    if cones.faces[a].dot(&cones.faces[b]) >= OPPOSITE || !overlap(&grown(a), &grown(b)) {
                        continue;
                    }
                    checked += 1;
                    let (p, q) = (cones.patch_of[a] as usize, cones.patch_of[b] as usize);
                    assert!(facing.contains(&(p, q)), "triangles {a} and {b} in patches {p} and {q}");
                    assert!(
                        cones.may_face(cones.faces[a], &grown(a), q) && cones.may_face(cones.faces[b], &grown(b), p)
                    );
                }
            }
        }
        assert!(checked > 100, "{checked} facing pairs");
    }
}
