//! Where two sheets of a surface face each other: the vertices near a sheet that
//! is not their own, found through a grid of the reach.

use super::super::distance::point_triangle_distance;
use super::super::{vertex_normals, Point, SurfaceMesh};
use std::collections::{HashMap, HashSet, VecDeque};

/// Most cosine between two vertices' normals for them to be on facing sheets.
const OPPOSITE: f64 = -0.5;

/// Most triangles a patch takes (a contact wider than that is not zipped).
const MOST_TRIANGLES: usize = 4096;

/// A surface's vertices binned by a grid of `reach`, with their normals and stars.
pub(super) struct Facing<'a> {
    mesh: &'a SurfaceMesh,
    reach: f64,
    normals: Vec<Point<3>>,
    grid: HashMap<[i64; 3], Vec<usize>>,
    stars: Vec<Vec<usize>>,
}

impl<'a> Facing<'a> {
    pub(super) fn new(mesh: &'a SurfaceMesh, reach: f64) -> Self {
        let x = mesh.positions();
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (v, p) in x.iter().enumerate() {
            grid.entry(cell(p, reach)).or_default().push(v);
        }
        let mut stars = vec![Vec::new(); x.len()];
        for (t, tri) in mesh.elements().iter().enumerate() {
            for &v in tri {
                stars[v].push(t);
            }
        }
        Facing { mesh, reach, normals: vertex_normals(x, mesh.elements()), grid, stars }
    }

    pub(super) fn normal(&self, v: usize) -> Point<3> {
        self.normals[v]
    }

    /// The vertices within `reach` of `v` whose normals are nearly opposite to
    /// `v`'s (neighbours on one smooth sheet never are), and, if `in_front`,
    /// that lie in front of `v` along its normal with `v` in front of them
    /// along theirs (the sheets face each other across the outside).
    fn facing(&self, v: usize, in_front: bool) -> impl Iterator<Item = usize> + '_ {
        let x = self.mesh.positions();
        let c = cell(&x[v], self.reach);
        (0..27i64)
            .flat_map(move |d| self.grid.get(&[c[0] + d % 3 - 1, c[1] + (d / 3) % 3 - 1, c[2] + d / 9 - 1]))
            .flatten()
            .copied()
            .filter(move |&u| {
                let gap = x[u] - x[v];
                u != v
                    && gap.norm() < self.reach
                    && self.normals[v].dot(&self.normals[u]) < OPPOSITE
                    && (!in_front || (self.normals[v].dot(&gap) > 0.0 && self.normals[u].dot(&gap) < 0.0))
            })
    }

    /// The closest two vertices on facing sheets, if any.
    pub(super) fn closest_pair(&self) -> Option<(usize, usize)> {
        let x = self.mesh.positions();
        let mut best: Option<(f64, usize, usize)> = None;
        for v in 0..x.len() {
            for u in self.facing(v, true).filter(|&u| u > v) {
                let d = (x[u] - x[v]).norm();
                if best.is_none_or(|(b, _, _)| d < b) {
                    best = Some((d, v, u));
                }
            }
        }
        best.map(|(_, v, u)| (v, u))
    }

    /// The distance from `v` to the facing sheet (its triangles at the facing
    /// vertices within reach), infinite where none faces it.
    pub(super) fn apart(&self, v: usize) -> f64 {
        let x = self.mesh.positions();
        let t = self.mesh.elements();
        let mut best = f64::INFINITY;
        for u in self.facing(v, false) {
            for &e in &self.stars[u] {
                let arr = |p: Point<3>| [p[0], p[1], p[2]];
                best = best.min(point_triangle_distance(arr(x[v]), &t[e].map(|w| arr(x[w]))));
            }
        }
        best
    }

    /// The patch of the sheet at `v` that is closer than `within` to the facing
    /// sheet: `v`'s star and the triangles joined to it across edges whose three
    /// corners are; `None` if it grows beyond [`MOST_TRIANGLES`].
    pub(super) fn patch(&self, v: usize, within: f64) -> Option<Vec<usize>> {
        let t = self.mesh.elements();
        let mut close: HashMap<usize, bool> = HashMap::new();
        let mut near = |w: usize| *close.entry(w).or_insert_with(|| self.apart(w) < within);
        let mut taken: HashSet<usize> = self.stars[v].iter().copied().collect();
        let mut queue: VecDeque<usize> = taken.iter().copied().collect();
        while let Some(e) = queue.pop_front() {
            for &w in &t[e] {
                for &f in &self.stars[w] {
                    let across = t[f].iter().filter(|c| t[e].contains(c)).count() == 2;
                    if across && !taken.contains(&f) && t[f].iter().all(|&c| near(c)) {
                        taken.insert(f);
                        queue.push_back(f);
                        if taken.len() > MOST_TRIANGLES {
                            return None;
                        }
                    }
                }
            }
        }
        let mut patch: Vec<usize> = taken.into_iter().collect();
        patch.sort_unstable();
        Some(patch)
    }
}

fn cell(p: &Point<3>, reach: f64) -> [i64; 3] {
    [0, 1, 2].map(|a| (p[a] / reach).floor() as i64)
}
