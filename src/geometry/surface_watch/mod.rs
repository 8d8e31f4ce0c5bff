//! Intersection checks of an evolving surface, continuous along each step, with
//! most pairs of triangles proved apart from a certificate instead of tested.
//!
//! The certificate keeps, for every vertex, an *anchor* (its position when last
//! anchored) and, for every pair of triangles that share no vertex and whose
//! anchored triangles lie closer than `2R` (the *near* pairs), their anchored
//! distance `g`. A point of a triangle lies within its corners' largest
//! displacement `D` from the anchored triangle's point of the same barycentric
//! coordinates, so two triangles stay at least `g − D_a − D_b` apart; and since the
//! distance does not change under a translation, also at least `g − ρ_a − ρ_b`,
//! where `ρ` are the corners' displacements relative to one corner of the pair. A
//! linear step from `old` to `new` keeps every point between its two ends, so the
//! bounds hold along the whole step when `D` and `ρ` are the larger of their values
//! at the two ends. Hence, while no vertex has moved by `R` from its anchor:
//!
//! - pairs that are not near were at least `2R` apart and cannot meet;
//! - a near pair cannot meet while `D_a + D_b < g` or `ρ_a + ρ_b < g` (a patch
//!   that moves nearly rigidly keeps its close neighbours apart however far it
//!   moves);
//! - the other near pairs are tested: exactly at `new` (`orient3d`), and along the
//!   step by a conservative advancement ([`sweep_apart`]).
//!
//! A vertex that reaches `R` is anchored again at `old` with the triangles around
//! it, and their near pairs drawn again from a hash grid of the anchored
//! triangles' boxes (grown by `R`); many such vertices, or a new connectivity,
//! draw the whole certificate again. A step longer than `R` is checked without the
//! certificate: every pair whose boxes swept over the step overlap is tested.

use super::distance::triangle_distance;
use super::surface_intersections::{
    bounds, box_pairs, mean_edge, overlap, overlap_cell, pack, points_meet, Aabb, MAX_CELLS,
};
use super::Point;
use std::collections::HashMap;
use swept::{pair_meets, swept_meetings};

mod swept;
pub use swept::swept_surface_intersections;

/// `R`, the displacement from the anchor that voids a vertex's part of the
/// certificate, in mean edge lengths.
const REACH_EDGES: f64 = 0.5;

/// Re-anchored vertices beyond this share of all draw the whole certificate again.
const REDRAW_SHARE: f64 = 0.2;

/// A near pair: two triangles and their anchored distance.
#[derive(Debug, Clone, Copy)]
struct Near {
    a: u32,
    b: u32,
    gap: f64,
}

#[derive(Debug, Clone)]
struct Certificate {
    triangles: Vec<[usize; 3]>,
    /// The triangles around each vertex (CSR).
    star_start: Vec<usize>,
    star: Vec<u32>,
    anchor: Vec<Point<3>>,
    reach: f64,
    cell: f64,
    /// The anchored triangles' boxes grown by `reach`.
    boxes: Vec<Aabb>,
    /// The cells each grown box covers (those of more than [`MAX_CELLS`] are kept
    /// in `large` instead).
    grid: HashMap<u64, Vec<u32>>,
    large: Vec<u32>,
    near: Vec<Near>,
    /// Rounding allowance of a computed distance.
    slack: f64,
}

/// Intersection checks between the steps of one surface flow (see the module
/// documentation).
#[derive(Debug, Clone, Default)]
pub struct SurfaceWatch {
    certificate: Option<Certificate>,
    /// Checks made, certificates drawn whole, partial re-anchorings, steps checked
    /// without the certificate, and near pairs tested (for tests and benchmarks).
    pub checks: usize,
    pub drawn: usize,
    pub reanchored: usize,
    pub swept: usize,
    pub tested: usize,
}

fn c(p: &Point<3>) -> [f64; 3] {
    [p[0], p[1], p[2]]
}

pub(super) fn corners(x: &[Point<3>], t: &[usize; 3]) -> [[f64; 3]; 3] {
    t.map(|v| c(&x[v]))
}

pub(super) fn shares(a: &[usize; 3], b: &[usize; 3]) -> bool {
    a.iter().any(|v| b.contains(v))
}

impl SurfaceWatch {
    /// Up to `most` pairs `(a, b)`, `a < b`, of `triangles` that share no vertex and
    /// meet at `new`, or may meet somewhere on the linear way from `old` (the same
    /// connectivity) to `new`: a pair that meets at `old` is one. None is missed;
    /// a pair may be reported that only comes within a rounding distance, or that
    /// slides past another for long at a hair's distance ([`sweep_apart`]).
    pub fn meetings(
        &mut self,
        old: &[Point<3>],
        new: &[Point<3>],
        triangles: &[[usize; 3]],
        most: usize,
    ) -> Vec<(usize, usize)> {
        self.checks += 1;
        if triangles.len() < 2 || most == 0 || old.len() != new.len() {
            return Vec::new();
        }
        let same = self.certificate.as_ref().is_some_and(|c| c.anchor.len() == old.len() && c.triangles == triangles);
        if !same {
            self.certificate = Certificate::draw(old, triangles);
            self.drawn += 1;
        }
        let Some(cert) = self.certificate.as_mut() else {
            self.swept += 1;
            return swept_meetings(old, new, triangles, most, 0.0);
        };
        let reach = cert.reach;
        let moved = |anchor: &[Point<3>], v: usize| (old[v] - anchor[v]).norm().max((new[v] - anchor[v]).norm());
        let mut vertex: Vec<f64> = (0..old.len()).map(|v| moved(&cert.anchor, v)).collect();
        let far: Vec<usize> = (0..old.len()).filter(|&v| vertex[v] >= reach).collect();
        if far.len() as f64 > REDRAW_SHARE * old.len() as f64 {
            self.certificate = Certificate::draw(old, triangles);
            self.drawn += 1;
            if let Some(cert) = &self.certificate {
                vertex = (0..old.len()).map(|v| moved(&cert.anchor, v)).collect();
            }
        } else if !far.is_empty() {
            cert.reanchor(&far, old);
            self.reanchored += 1;
            for &v in &far {
                vertex[v] = moved(&cert.anchor, v);
            }
        }
        let Some(cert) = self.certificate.as_ref() else {
            self.swept += 1;
            return swept_meetings(old, new, triangles, most, 0.0);
        };
        if vertex.iter().any(|&d| d >= cert.reach) {
            // the step itself is longer than the reach
            self.swept += 1;
            return swept_meetings(old, new, triangles, most, cert.slack);
        }
        let displacement: Vec<f64> =
            triangles.iter().map(|t| vertex[t[0]].max(vertex[t[1]]).max(vertex[t[2]])).collect();
        let mut hits = Vec::new();
        for p in &cert.near {
            let (a, b) = (p.a as usize, p.b as usize);
            if displacement[a] + displacement[b] < p.gap {
                continue;
            }
            let (ta, tb) = (&triangles[a], &triangles[b]);
            if cert.relative(old, ta, tb) + cert.relative(new, ta, tb) < p.gap {
                continue;
            }
            self.tested += 1;
            if pair_meets(old, new, ta, tb, cert.slack) {
                hits.push((a, b));
                if hits.len() >= most {
                    break;
                }
            }
        }
        hits
    }
}

impl Certificate {
    /// The certificate of `x` (every vertex anchored there); `None` for a surface
    /// without extent.
    fn draw(x: &[Point<3>], triangles: &[[usize; 3]]) -> Option<Certificate> {
        let h = mean_edge(x, triangles);
        let scale = x.iter().flat_map(|p| p.iter().map(|v| v.abs())).fold(0.0, f64::max);
        if !(h.is_finite() && h > 0.0 && scale.is_finite()) {
            return None;
        }
        let reach = REACH_EDGES * h;
        let mut star_start = vec![0usize; x.len() + 1];
        for t in triangles {
            for &v in t {
                star_start[v + 1] += 1;
            }
        }
        for v in 0..x.len() {
            star_start[v + 1] += star_start[v];
        }
        let mut fill = star_start.clone();
        let mut star = vec![0u32; star_start[x.len()]];
        for (e, t) in triangles.iter().enumerate() {
            for &v in t {
                star[fill[v]] = e as u32;
                fill[v] += 1;
            }
        }
        let mut cert = Certificate {
            triangles: triangles.to_vec(),
            star_start,
            star,
            anchor: x.to_vec(),
            reach,
            cell: 2.0 * (h + reach),
            boxes: Vec::with_capacity(triangles.len()),
            grid: HashMap::new(),
            large: Vec::new(),
            near: Vec::new(),
            slack: 64.0 * f64::EPSILON * scale.max(h),
        };
        cert.boxes = (0..triangles.len()).map(|t| cert.grown(t)).collect();
        for t in 0..triangles.len() {
            cert.insert(t);
        }
        let mut near = Vec::new();
        box_pairs(&cert.boxes, cert.cell, |a, b| {
            cert.consider(a, b, &mut near);
            false
        });
        cert.near = near;
        Some(cert)
    }

    /// The anchored box of triangle `t`, grown by the reach.
    fn grown(&self, t: usize) -> Aabb {
        let (lo, hi) = bounds(&self.anchor, &self.triangles[t]);
        (lo.map(|v| v - self.reach), hi.map(|v| v + self.reach))
    }

    fn cells(&self, b: &Aabb) -> Option<[[i64; 3]; 2]> {
        let index = |x: f64| (x / self.cell).floor() as i64;
        let (l, h) = (b.0.map(index), b.1.map(index));
        let count = (0..3).map(|k| (h[k] - l[k] + 1) as usize).product::<usize>();
        (count <= MAX_CELLS).then_some([l, h])
    }

    fn for_cells(&self, t: usize, mut f: impl FnMut(u64)) -> bool {
        let Some([l, h]) = self.cells(&self.boxes[t]) else { return false };
        for i in l[0]..=h[0] {
            for j in l[1]..=h[1] {
                for k in l[2]..=h[2] {
                    f(pack([i, j, k]));
                }
            }
        }
        true
    }

    fn insert(&mut self, t: usize) {
        let mut keys = Vec::new();
        if self.for_cells(t, |k| keys.push(k)) {
            for k in keys {
                self.grid.entry(k).or_default().push(t as u32);
            }
        } else {
            self.large.push(t as u32);
        }
    }

    fn remove(&mut self, t: usize) {
        let mut keys = Vec::new();
        if self.for_cells(t, |k| keys.push(k)) {
            for k in keys {
                if let Some(list) = self.grid.get_mut(&k) {
                    list.retain(|&u| u as usize != t);
                }
            }
        } else {
            self.large.retain(|&u| u as usize != t);
        }
    }

    /// Adds `(a, b)` to `near` if the two share no vertex and their anchored
    /// triangles lie closer than twice the reach.
    fn consider(&self, a: usize, b: usize, near: &mut Vec<Near>) {
        let (ta, tb) = (&self.triangles[a], &self.triangles[b]);
        if shares(ta, tb) || !overlap(&self.boxes[a], &self.boxes[b]) {
            return;
        }
        let x = &self.anchor;
        let gap = if points_meet(&ta.map(|v| x[v]), &tb.map(|v| x[v])) {
            0.0
        } else {
            (triangle_distance(&corners(x, ta), &corners(x, tb)) - self.slack).max(0.0)
        };
        if gap < 2.0 * self.reach {
            near.push(Near { a: a.min(b) as u32, b: a.max(b) as u32, gap });
        }
    }

    /// The largest displacement from the anchors, at `x`, of a corner of `ta` plus
    /// that of a corner of `tb`, both relative to the displacement of `ta`'s first
    /// corner.
    fn relative(&self, x: &[Point<3>], ta: &[usize; 3], tb: &[usize; 3]) -> f64 {
        let r = x[ta[0]] - self.anchor[ta[0]];
        let most = |t: &[usize; 3]| t.iter().map(|&v| (x[v] - self.anchor[v] - r).norm()).fold(0.0, f64::max);
        most(ta) + most(tb)
    }

    /// Anchors `vertices` again at `x`, with the near pairs of the triangles around
    /// them drawn again.
    fn reanchor(&mut self, vertices: &[usize], x: &[Point<3>]) {
        let mut dirty = vec![false; self.triangles.len()];
        let mut changed = Vec::new();
        for &v in vertices {
            for &t in &self.star[self.star_start[v]..self.star_start[v + 1]] {
                if !std::mem::replace(&mut dirty[t as usize], true) {
                    changed.push(t as usize);
                }
            }
        }
        for &t in &changed {
            self.remove(t);
        }
        for &v in vertices {
            self.anchor[v] = x[v];
        }
        for &t in &changed {
            self.boxes[t] = self.grown(t);
            self.insert(t);
        }
        self.near.retain(|p| !dirty[p.a as usize] && !dirty[p.b as usize]);
        let mut near = Vec::new();
        for &t in &changed {
            let mut partners = Vec::new();
            let in_grid = self.for_cells(t, |key| {
                for &u in self.grid.get(&key).map(Vec::as_slice).unwrap_or_default() {
                    let u = u as usize;
                    // a pair of two changed triangles once, from the lower; any pair
                    // once, in the cell of the lowest corner of its boxes' overlap
                    if u == t || (dirty[u] && u < t) || !overlap(&self.boxes[t], &self.boxes[u]) {
                        continue;
                    }
                    if overlap_cell(&self.boxes[t], &self.boxes[u], self.cell) == key {
                        partners.push(u);
                    }
                }
            });
            if in_grid {
                partners.extend(self.large.iter().map(|&u| u as usize).filter(|&u| !(dirty[u] && u < t)));
            } else {
                partners.extend((0..self.triangles.len()).filter(|&u| u != t && !(dirty[u] && u < t)));
            }
            for u in partners {
                self.consider(t, u, &mut near);
            }
        }
        self.near.extend(near);
    }
}

#[cfg(test)]
mod tests;
