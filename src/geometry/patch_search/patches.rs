//! The patches of a connectivity: the triangles of a cell of a grid whose
//! normals point most nearly along one of the six axis directions, connected
//! across edges and ordered ring by ring, each with its boundary loop when it is
//! a disk. A cell is as wide as a square of [`PATCH_TRIANGLES`] triangles of
//! the surface's mean area when the patches are cut.

use super::super::Point;
use super::groups::Groups;
use super::seams::{seams, Seam};
use std::collections::VecDeque;

/// A cell's side is that of a square of this many triangles of mean area.
pub(super) const PATCH_TRIANGLES: usize = 512;

/// A patch: its triangles (a range of [`Patches::order`]), the plane of its
/// class (the axis of the normals' largest component, and whether that is
/// positive: the plane it projects onto best when cut) and, when it is a
/// topological disk, its boundary loop (vertices in order).
#[derive(Debug, Clone)]
pub(super) struct Patch {
    pub start: usize,
    pub end: usize,
    pub plane: (usize, bool),
    pub boundary: Option<Vec<usize>>,
}

/// Triangles of a run along a patch's rings, boxed together.
pub(super) const CHUNK: usize = 16;

/// A run of [`CHUNK`] triangles of a patch (a range of slots) and its vertices
/// (a range of [`Patches::chunk_vertices`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Chunk {
    pub start: usize,
    pub end: usize,
    pub vertices: (u32, u32),
}

/// The patches of one connectivity.
#[derive(Debug, Clone, Default)]
pub(super) struct Patches {
    pub triangles: Vec<[usize; 3]>,
    /// Triangles grouped by patch: the triangle in each slot, and its vertices.
    pub order: Vec<u32>,
    pub slots: Vec<[usize; 3]>,
    pub patches: Vec<Patch>,
    /// The runs of each patch's triangles (patch `q`'s from `first_chunk[q]`
    /// to `first_chunk[q + 1]`), and the vertices of each run, once.
    pub chunks: Vec<Chunk>,
    pub first_chunk: Vec<usize>,
    pub chunk_vertices: Vec<u32>,
    /// The patches proved embedded at the first search after the cut (the
    /// shape they were cut for).
    pub embedded_at_cut: std::cell::Cell<Option<usize>>,
    /// The pairs of disk patches that share one arc of their loops.
    pub seams: Vec<Seam>,
    /// The patches glued into larger disks.
    pub groups: Groups,
}

/// A directed edge's key.
fn key(a: usize, b: usize) -> u64 {
    (a as u64) << 32 | b as u64
}

impl Patches {
    /// The patches of `triangles` at positions `x`. Only the connectivity of a
    /// closed oriented manifold surface is cut into patches of many triangles
    /// (each directed edge used once and reversed once, every vertex's triangles
    /// one fan); any other gets one patch per triangle, which certifies nothing.
    pub fn new(x: &[Point<3>], triangles: &[[usize; 3]]) -> Patches {
        let (n, vertices) = (triangles.len(), x.len());
        let singletons = || {
            Patches {
                triangles: triangles.to_vec(),
                order: (0..n as u32).collect(),
                slots: triangles.to_vec(),
                patches: (0..n).map(|t| Patch { start: t, end: t + 1, plane: (2, true), boundary: None }).collect(),
                ..Patches::default()
            }
            .chunked()
        };
        if n >= u32::MAX as usize || vertices >= u32::MAX as usize {
            return singletons();
        }
        // the triangle across each directed edge (the one using it reversed)
        let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * n);
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                edges.push((key(tri[k], tri[(k + 1) % 3]), t as u32));
            }
        }
        edges.sort_unstable();
        if edges.windows(2).any(|w| w[0].0 == w[1].0) {
            return singletons();
        }
        let find = |a: usize, b: usize| edges.binary_search_by_key(&key(a, b), |e| e.0).ok().map(|i| edges[i].1);
        let mut across = vec![[0u32; 3]; n];
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                match find(tri[(k + 1) % 3], tri[k]) {
                    Some(u) => across[t][k] = u,
                    None => return singletons(),
                }
            }
        }
        if super::super::validate::validate_surface(vertices, triangles).is_err() {
            return singletons();
        }
        // patches: the triangles of a grid cell (by centroid) connected across
        // edges, the cell about PATCH_TRIANGLES triangles wide
        let centroid = |t: &[usize; 3]| (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
        let area: f64 = triangles.iter().map(|t| (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]])).norm() / 2.0).sum();
        let side = (PATCH_TRIANGLES as f64 * area / n as f64).sqrt();
        if !(side.is_finite() && side > 0.0) {
            return singletons();
        }
        // and of one class of normals (the axis and sign of the largest
        // component): a patch projects well onto one coordinate plane
        let class = |t: &[usize; 3]| {
            let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            let k = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
            2 * k as i64 + i64::from(n[k] > 0.0)
        };
        let cell: Vec<[i64; 4]> = triangles
            .iter()
            .map(|t| {
                let c = centroid(t);
                [(c[0] / side).floor() as i64, (c[1] / side).floor() as i64, (c[2] / side).floor() as i64, class(t)]
            })
            .collect();
        let mut patch_of = vec![u32::MAX; n];
        let mut order = Vec::with_capacity(n);
        let mut patches = Vec::new();
        let mut ring = VecDeque::new();
        for seed in 0..n {
            if patch_of[seed] != u32::MAX {
                continue;
            }
            let id = patches.len() as u32;
            let start = order.len();
            ring.push_back(seed as u32);
            patch_of[seed] = id;
            while let Some(t) = ring.pop_front() {
                order.push(t);
                for &u in &across[t as usize] {
                    if patch_of[u as usize] == u32::MAX && cell[u as usize] == cell[seed] {
                        patch_of[u as usize] = id;
                        ring.push_back(u);
                    }
                }
            }
            let members: Vec<usize> = order[start..].iter().map(|&t| t as usize).collect();
            let boundary = disk_boundary(&members, triangles, &across, &patch_of, id);
            let c = cell[seed][3];
            patches.push(Patch { start, end: order.len(), plane: ((c / 2) as usize, c % 2 == 1), boundary });
        }
        let slots = order.iter().map(|&t| triangles[t as usize]).collect();
        let across = |u: usize, v: usize| find(v, u).map_or(u32::MAX, |t| patch_of[t as usize]);
        let loops: Vec<Option<&Vec<usize>>> = patches.iter().map(|q| q.boundary.as_ref()).collect();
        let seams = seams(&loops, across);
        let cells: Vec<[i64; 4]> = patches.iter().map(|q| cell[order[q.start] as usize]).collect();
        let groups = Groups::new(&loops, &cells, vertices, across);
        Patches { triangles: triangles.to_vec(), order, slots, patches, seams, groups, ..Patches::default() }.chunked()
    }

    /// The patches with their runs of [`CHUNK`] triangles drawn.
    fn chunked(mut self) -> Patches {
        let (chunks, first, vertices) = (&mut self.chunks, &mut self.first_chunk, &mut self.chunk_vertices);
        let mut run = Vec::with_capacity(3 * CHUNK);
        for patch in &self.patches {
            first.push(chunks.len());
            for start in (patch.start..patch.end).step_by(CHUNK) {
                let end = (start + CHUNK).min(patch.end);
                run.clear();
                run.extend(self.slots[start..end].iter().flatten().map(|&v| v as u32));
                run.sort_unstable();
                run.dedup();
                let from = vertices.len() as u32;
                vertices.extend_from_slice(&run);
                chunks.push(Chunk { start, end, vertices: (from, vertices.len() as u32) });
            }
        }
        first.push(chunks.len());
        self
    }
}

/// The boundary loop of patch `id` (its `members`), vertices in order, when the
/// patch is a disk: one loop through vertices each on two boundary edges, and
/// Euler characteristic 1 (every vertex's triangles being one fan of the mesh).
fn disk_boundary(
    members: &[usize],
    triangles: &[[usize; 3]],
    across: &[[u32; 3]],
    patch_of: &[u32],
    id: u32,
) -> Option<Vec<usize>> {
    // boundary edges, directed as in their triangle: from → to
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut interior = 0;
    for &t in members {
        for k in 0..3 {
            if patch_of[across[t][k] as usize] == id {
                interior += 1;
            } else {
                out.push((triangles[t][k], triangles[t][(k + 1) % 3]));
            }
        }
    }
    let mut vertices: Vec<usize> = members.iter().flat_map(|&t| triangles[t]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let edges = interior / 2 + out.len();
    if out.len() < 3 || vertices.len() + members.len() != edges + 1 {
        return None;
    }
    out.sort_unstable();
    if out.windows(2).any(|w| w[0].0 == w[1].0) {
        // a vertex on more than two boundary edges
        return None;
    }
    let next = |a: usize| out.binary_search_by_key(&a, |e| e.0).ok().map(|i| out[i].1);
    let mut lp = vec![out[0].0];
    let mut at = out[0].1;
    while at != out[0].0 {
        if lp.len() >= out.len() {
            return None;
        }
        lp.push(at);
        at = next(at)?;
    }
    (lp.len() == out.len()).then_some(lp)
}
