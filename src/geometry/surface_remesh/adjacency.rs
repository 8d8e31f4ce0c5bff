//! The adjacency of a triangle surface that the remeshing operations read: its
//! edges with their triangles, and the triangles around each vertex. It is built
//! once per connectivity: [`super::adapt_surface`] builds it for the input and
//! again for the result of each operation that changed the triangles, which then
//! serves both that result's check and the next operation.

/// The triangles around each vertex.
pub(super) struct Stars {
    /// Triangles around vertex `v`: `list[start[v]..start[v + 1]]`.
    start: Vec<usize>,
    list: Vec<usize>,
}

impl Stars {
    pub(super) fn of(n: usize, tris: &[[usize; 3]]) -> Stars {
        let (start, list) = vertex_triangles(n, tris);
        Stars { start, list }
    }

    /// The triangles that contain vertex `v`.
    pub(super) fn star(&self, v: usize) -> &[usize] {
        &self.list[self.start[v]..self.start[v + 1]]
    }
}

/// The edges and vertex stars of a triangle surface.
pub(super) struct Adjacency {
    /// Every edge, sorted by `(a, b)`.
    pub edges: Vec<SurfaceEdge>,
    pub stars: Stars,
}

impl Adjacency {
    /// The adjacency of the triangles `tris` on `n` vertices.
    pub(super) fn of(n: usize, tris: &[[usize; 3]]) -> Adjacency {
        Adjacency { edges: surface_edges(n, tris), stars: Stars::of(n, tris) }
    }

    /// The index of edge `{a, b}` in [`Adjacency::edges`].
    pub(super) fn edge(&self, a: usize, b: usize) -> Option<usize> {
        let key = (a.min(b), a.max(b));
        self.edges.binary_search_by(|e| (e.a, e.b).cmp(&key)).ok()
    }
}

/// Incident triangles of every vertex (CSR).
fn vertex_triangles(n: usize, tris: &[[usize; 3]]) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; n + 1];
    for t in tris {
        for &v in t {
            start[v + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut list = vec![0usize; start[n]];
    for (k, t) in tris.iter().enumerate() {
        for &v in t {
            list[fill[v]] = k;
            fill[v] += 1;
        }
    }
    (start, list)
}

/// An edge `a < b` with the two triangles containing it (`t[1] = usize::MAX` if only one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceEdge {
    pub a: usize,
    pub b: usize,
    pub t: [usize; 2],
}

/// All edges, sorted by `(a, b)`, built in `O(n)` through per-vertex buckets
/// (`K = 3`: a generic length only so that meshes of any `D` can pass theirs).
pub fn surface_edges<const K: usize>(n: usize, tris: &[[usize; K]]) -> Vec<SurfaceEdge> {
    let mut start = vec![0usize; n + 1];
    for t in tris {
        for e in 0..K {
            start[t[e].min(t[(e + 1) % K]) + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut slot = vec![(0usize, 0usize); start[n]];
    for (k, t) in tris.iter().enumerate() {
        for e in 0..K {
            let (a, b) = (t[e].min(t[(e + 1) % K]), t[e].max(t[(e + 1) % K]));
            slot[fill[a]] = (b, k);
            fill[a] += 1;
        }
    }
    let mut out = Vec::with_capacity(start[n] / 2 + 1);
    for a in 0..n {
        let list = &mut slot[start[a]..start[a + 1]];
        list.sort_unstable();
        let mut i = 0;
        while i < list.len() {
            let b = list[i].0;
            let mut t = [list[i].1, usize::MAX];
            if i + 1 < list.len() && list[i + 1].0 == b {
                t[1] = list[i + 1].1;
                i += 1;
            }
            out.push(SurfaceEdge { a, b, t });
            i += 1;
        }
    }
    out
}
