//! Mesh management for closed triangle surfaces (paper §4.1): volume-preserving
//! tangential regularization, and adaptivity by edge split, collapse and flip with
//! angle-width control. Pure functions from a surface mesh to a surface mesh.

use super::measures::vertex_normals;
use super::{Mesh, Point, SurfaceMesh};
use std::collections::HashSet;

/// Parameters of surface mesh management.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceRemeshSettings {
    /// Refine an edge where `h β > epsilon` (`β` the angle between the normals of the
    /// two triangles sharing it); collapse where far below.
    pub epsilon: f64,
    pub h_min: f64,
    pub h_max: f64,
    /// Angle-width control: split the edge opposite an angle wider than this (degrees).
    pub max_angle_deg: f64,
}

fn tri_normal(p: &[Point<3>], t: &[usize; 3]) -> Point<3> {
    (p[t[1]] - p[t[0]]).cross(&(p[t[2]] - p[t[0]]))
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

/// Tangential regularization by `sweeps` Gauss–Seidel sweeps: every vertex moves
/// towards the area-weighted centroid of its incident triangles (which evens out
/// areas and angles in the vertex star), with the component along the volume
/// gradient `g_i = Σ_{(i,j,k)} X_j × X_k / 6` removed. The enclosed volume is linear
/// in one vertex with the others fixed, so each move keeps it exactly; `g_i` is the
/// area-weighted normal, so the move is tangential. A move that would turn an
/// incident triangle by more than 60° is skipped.
pub fn regularize_surface(mesh: &SurfaceMesh, sweeps: usize) -> SurfaceMesh {
    let mut p = mesh.positions().to_vec();
    let tris = mesh.elements();
    let (start, list) = vertex_triangles(p.len(), tris);
    let mut normals: Vec<Point<3>> = Vec::with_capacity(16);
    for _ in 0..sweeps {
        for v in 0..p.len() {
            let star = &list[start[v]..start[v + 1]];
            let mut c = Point::<3>::zeros();
            let mut w = 0.0;
            let mut g = Point::<3>::zeros();
            normals.clear();
            for &t in star {
                let tr = tris[t];
                let (j, l) = if tr[0] == v {
                    (tr[1], tr[2])
                } else if tr[1] == v {
                    (tr[2], tr[0])
                } else {
                    (tr[0], tr[1])
                };
                // (X_j − X_v) × (X_l − X_v): the triangle's normal times twice its area
                let n = (p[j] - p[v]).cross(&(p[l] - p[v]));
                let area = 0.5 * n.norm();
                c += (p[v] + p[j] + p[l]) * (area / 3.0);
                w += area;
                g += p[j].cross(&p[l]) / 6.0;
                normals.push(n);
            }
            let gg = g.norm_squared();
            if w <= 0.0 || gg <= 0.0 {
                continue;
            }
            let mut d = c / w - p[v];
            d -= g * (d.dot(&g) / gg);
            let old = p[v];
            p[v] = old + d;
            let ok = star.iter().zip(&normals).all(|(&t, n0)| {
                let n1 = tri_normal(&p, &tris[t]);
                n1.dot(n0) > 0.5 * n1.norm() * n0.norm()
            });
            if !ok {
                p[v] = old;
            }
        }
    }
    mesh.with_positions(p)
}

fn angle_at(p: &[Point<3>], a: usize, b: usize, c: usize) -> f64 {
    let (u, w) = (p[b] - p[a], p[c] - p[a]);
    (u.dot(&w) / (u.norm() * w.norm())).clamp(-1.0, 1.0).acos().to_degrees()
}

/// An edge `a < b` with the two triangles containing it (`t[1] = usize::MAX` if only one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceEdge {
    pub a: usize,
    pub b: usize,
    pub t: [usize; 2],
}

/// All edges, sorted by `(a, b)`, built in `O(n)` through per-vertex buckets.
pub fn surface_edges(n: usize, tris: &[[usize; 3]]) -> Vec<SurfaceEdge> {
    let mut start = vec![0usize; n + 1];
    for t in tris {
        for e in 0..3 {
            start[t[e].min(t[(e + 1) % 3]) + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut slot = vec![(0usize, 0usize); start[n]];
    for (k, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3]));
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

/// Unit normals of the triangles.
fn unit_normals(p: &[Point<3>], tris: &[[usize; 3]]) -> Vec<Point<3>> {
    tris.iter().map(|t| tri_normal(p, t).normalize()).collect()
}

/// Per triangle: its vertex with an angle wider than `max_deg`, or `usize::MAX`.
fn wide_vertices(p: &[Point<3>], tris: &[[usize; 3]], max_deg: f64) -> Vec<usize> {
    let cos_max = max_deg.to_radians().cos();
    tris.iter()
        .map(|t| {
            (0..3)
                .find(|&k| {
                    let (c, a, b) = (p[t[k]], p[t[(k + 1) % 3]], p[t[(k + 2) % 3]]);
                    let (u, w) = (a - c, b - c);
                    u.dot(&w) < cos_max * u.norm() * w.norm()
                })
                .map_or(usize::MAX, |k| t[k])
        })
        .collect()
}

/// Per triangle: has it an angle below `min_deg`?
fn thin_triangles(p: &[Point<3>], tris: &[[usize; 3]], min_deg: f64) -> Vec<bool> {
    let cos_min = min_deg.to_radians().cos();
    tris.iter()
        .map(|t| {
            (0..3).any(|k| {
                let (c, a, b) = (p[t[k]], p[t[(k + 1) % 3]], p[t[(k + 2) % 3]]);
                let (u, w) = (a - c, b - c);
                u.dot(&w) > cos_min * u.norm() * w.norm()
            })
        })
        .collect()
}

/// Index of edge `{a, b}` in a sorted edge list.
fn edge_index(edges: &[SurfaceEdge], a: usize, b: usize) -> Option<usize> {
    let key = (a.min(b), a.max(b));
    edges.binary_search_by(|e| (e.a, e.b).cmp(&key)).ok()
}

/// Mean edge length, the largest `h β` and the largest `β/h` over the edges (`β` the
/// angle between the normals of the two triangles at the edge).
pub fn edge_statistics(mesh: &SurfaceMesh) -> (f64, f64, f64) {
    let p = mesh.positions();
    let edges = surface_edges(p.len(), mesh.elements());
    let normals = mesh.element_normals();
    let (mut sum, mut hb, mut bh) = (0.0, 0.0f64, 0.0f64);
    for e in &edges {
        let h = (p[e.b] - p[e.a]).norm();
        sum += h;
        if e.t[1] != usize::MAX {
            let beta = normals[e.t[0]].dot(&normals[e.t[1]]).clamp(-1.0, 1.0).acos();
            hb = hb.max(h * beta);
            bh = bh.max(beta / h);
        }
    }
    (sum / edges.len().max(1) as f64, hb, bh)
}

/// Refinement by edge splits: an edge is split when longer than `h_max`, when
/// `h β > ε` and its halves stay above `h_min`, or when it lies opposite an angle
/// wider than `max_angle_deg` (angle-width control). The new vertex is the edge
/// midpoint lifted by the sagitta `e·(n_b − n_a)/8` along the mean normal, which is
/// exact on a sphere with exact normals. Triangles with one, two or three split edges
/// are divided into two, three or four.
fn split_edges(p: &mut Vec<Point<3>>, tris: &[[usize; 3]], s: &SurfaceRemeshSettings) -> Option<Vec<[usize; 3]>> {
    let edges = surface_edges(p.len(), tris);
    let unit = unit_normals(p, tris);
    let wide = wide_vertices(p, tris, s.max_angle_deg);
    let mut normals: Option<Vec<Point<3>>> = None;
    let mut mid = vec![usize::MAX; edges.len()];
    let mut count = 0;
    for (k, edge) in edges.iter().enumerate() {
        let (a, b) = (edge.a, edge.b);
        if edge.t[1] == usize::MAX {
            continue;
        }
        let ts = &edge.t;
        let h = (p[b] - p[a]).norm();
        // the edge faces a wide angle of one of its triangles
        let faces_wide = ts.iter().any(|&t| wide[t] != usize::MAX && wide[t] != a && wide[t] != b);
        let split = h > s.h_max
            || faces_wide
            || (h > 2.0 * s.h_min && h * unit[ts[0]].dot(&unit[ts[1]]).clamp(-1.0, 1.0).acos() > s.epsilon);
        if split {
            let normals = normals.get_or_insert_with(|| vertex_normals(p, tris));
            let e = p[b] - p[a];
            let nm = (normals[a] + normals[b]).normalize();
            let lift = e.dot(&(normals[b] - normals[a])) / 8.0;
            p.push((p[a] + p[b]) * 0.5 + nm * lift);
            mid[k] = p.len() - 1;
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let m = |a: usize, b: usize| edge_index(&edges, a, b).map(|k| mid[k]).filter(|&x| x != usize::MAX);
    let mut out = Vec::with_capacity(tris.len() + 3 * count);
    for &t in tris {
        let ms = [m(t[0], t[1]), m(t[1], t[2]), m(t[2], t[0])];
        match ms.iter().filter(|x| x.is_some()).count() {
            0 => out.push(t),
            1 => {
                let k = ms.iter().position(|x| x.is_some()).unwrap();
                let (a, b, c, x) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3], ms[k].unwrap());
                out.push([a, x, c]);
                out.push([x, b, c]);
            }
            2 => {
                let k = ms.iter().position(|x| x.is_none()).unwrap();
                // edge k (t[k] → t[k+1]) is whole; the other two are split
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (y, z) = (ms[(k + 1) % 3].unwrap(), ms[(k + 2) % 3].unwrap()); // on b–c and c–a
                out.push([z, y, c]);
                // split the quad a, b, y, z along its shorter diagonal
                if (p[y] - p[a]).norm() < (p[z] - p[b]).norm() {
                    out.push([a, b, y]);
                    out.push([a, y, z]);
                } else {
                    out.push([a, b, z]);
                    out.push([b, y, z]);
                }
            }
            _ => {
                let (x, y, z) = (ms[0].unwrap(), ms[1].unwrap(), ms[2].unwrap());
                out.push([t[0], x, z]);
                out.push([x, t[1], y]);
                out.push([z, y, t[2]]);
                out.push([x, y, z]);
            }
        }
    }
    Some(out)
}

/// Coarsening by edge collapses: an edge shorter than `h_min`, or flat (`h β` below
/// `ε/8` at every edge around both ends) and shorter than `h_max/2`, is collapsed to
/// its midpoint when the link condition holds (exactly two common neighbours), no
/// triangle turns by more than 30°, becomes degenerate or gets an angle wider than
/// `max_angle_deg`, and no new edge exceeds `h_max`. One collapse per vertex star
/// and pass.
fn collapse_edges(p: &mut [Point<3>], tris: &mut Vec<[usize; 3]>, s: &SurfaceRemeshSettings) -> bool {
    let n = p.len();
    let edges = surface_edges(n, tris);
    let unit = unit_normals(p, tris);
    let mut flat_vertex = vec![true; n];
    for e in &edges {
        let (a, b, ts) = (e.a, e.b, e.t);
        if ts[1] != usize::MAX && (flat_vertex[a] || flat_vertex[b]) {
            let beta = unit[ts[0]].dot(&unit[ts[1]]).clamp(-1.0, 1.0).acos();
            if (p[b] - p[a]).norm() * beta >= s.epsilon / 8.0 {
                flat_vertex[a] = false;
                flat_vertex[b] = false;
            }
        }
    }
    // the candidates, shortest first
    let mut keys: Vec<(f64, usize, usize)> = edges
        .iter()
        .map(|e| ((p[e.b] - p[e.a]).norm(), e.a, e.b))
        .filter(|&(h, a, b)| h < s.h_min || (flat_vertex[a] && flat_vertex[b] && h < 0.5 * s.h_max))
        .collect();
    if keys.is_empty() {
        return false;
    }
    keys.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let (start, list) = vertex_triangles(n, tris);
    let mut locked = vec![false; n];
    let mut dead = vec![false; tris.len()];
    let mut remap: Vec<usize> = (0..n).collect();
    let mut any = false;
    let neighbours = |v: usize, tris: &[[usize; 3]]| -> Vec<usize> {
        let mut nb: Vec<usize> =
            list[start[v]..start[v + 1]].iter().flat_map(|&t| tris[t]).filter(|&x| x != v).collect();
        nb.sort_unstable();
        nb.dedup();
        nb
    };
    for (h, a, b) in keys {
        let short = h < s.h_min;
        let flat = flat_vertex[a] && flat_vertex[b] && h < 0.5 * s.h_max;
        if !(short || flat) || locked[a] || locked[b] {
            continue;
        }
        let (na, nb) = (neighbours(a, tris), neighbours(b, tris));
        let common = na.iter().filter(|x| nb.binary_search(x).is_ok()).count();
        if common != 2 || na.len() < 4 || nb.len() < 4 {
            continue;
        }
        let target = (p[a] + p[b]) * 0.5;
        // triangles around a or b that survive, with b replaced by a
        let star: Vec<usize> =
            list[start[a]..start[a + 1]].iter().chain(&list[start[b]..start[b + 1]]).copied().collect();
        let mut ok = true;
        for &t in &star {
            let tr = tris[t];
            if tr.contains(&a) && tr.contains(&b) {
                continue;
            }
            let moved = tr.map(|x| if x == b { a } else { x });
            let n0 = tri_normal(p, &tr);
            let q = |x: usize| if x == a { target } else { p[x] };
            let n1 = (q(moved[1]) - q(moved[0])).cross(&(q(moved[2]) - q(moved[0])));
            let longest = (0..3).map(|e| (q(moved[(e + 1) % 3]) - q(moved[e])).norm()).fold(0.0, f64::max);
            let wide = (0..3).any(|e| {
                let (u, w) = (q(moved[(e + 1) % 3]) - q(moved[e]), q(moved[(e + 2) % 3]) - q(moved[e]));
                (u.dot(&w) / (u.norm() * w.norm())).clamp(-1.0, 1.0).acos().to_degrees() > s.max_angle_deg
            });
            if n1.norm() <= 1e-12 * n0.norm()
                || n1.dot(&n0) < 0.866 * n1.norm() * n0.norm()
                || longest > s.h_max
                || wide
            {
                ok = false;
                break;
            }
        }
        if !ok {
            continue;
        }
        for &v in na.iter().chain(&nb) {
            locked[v] = true;
        }
        locked[a] = true;
        locked[b] = true;
        p[a] = target;
        remap[b] = a;
        for &t in &star {
            if tris[t].contains(&a) && tris[t].contains(&b) {
                dead[t] = true;
            }
        }
        any = true;
    }
    if any {
        let kept: Vec<[usize; 3]> =
            tris.iter().zip(&dead).filter(|(_, d)| !**d).map(|(t, _)| t.map(|x| remap[x])).collect();
        *tris = kept;
    }
    any
}

/// Edge flips towards valence 6 between nearly coplanar triangles (dihedral angle
/// below 20°), when neither new triangle is degenerate, turned, or wider than the
/// angle limit, and the new edge does not exist yet.
fn flip_edges(p: &[Point<3>], tris: &mut [[usize; 3]], s: &SurfaceRemeshSettings) -> bool {
    let n = p.len();
    let mut valence = vec![0i64; n];
    let edges = surface_edges(n, tris);
    for e in &edges {
        valence[e.a] += 1;
        valence[e.b] += 1;
    }
    let thin = thin_triangles(p, tris, 15.0);
    // edges created by earlier flips of this pass (removed ones need no record: a
    // flipped edge's triangles are touched and not considered again)
    let mut added: HashSet<(usize, usize)> = HashSet::new();
    let mut touched = vec![false; tris.len()];
    let mut any = false;
    for e in &edges {
        let (a, b, ts) = (e.a, e.b, e.t);
        if ts[1] == usize::MAX || touched[ts[0]] || touched[ts[1]] {
            continue;
        }
        let (t0, t1) = (tris[ts[0]], tris[ts[1]]);
        // orient: t0 = (a, b, c) in its own rotation, t1 = (b, a, d)
        let k0 = (0..3).find(|&k| t0[k] == a && t0[(k + 1) % 3] == b);
        let (t0, t1, a, b) = match k0 {
            Some(_) => (t0, t1, a, b),
            None => (t1, t0, a, b),
        };
        let Some(k0) = (0..3).find(|&k| t0[k] == a && t0[(k + 1) % 3] == b) else { continue };
        let c = t0[(k0 + 2) % 3];
        let Some(k1) = (0..3).find(|&k| t1[k] == b && t1[(k + 1) % 3] == a) else { continue };
        let d = t1[(k1 + 2) % 3];
        let dev =
            |va: i64, vb: i64, vc: i64, vd: i64| (va - 6).pow(2) + (vb - 6).pow(2) + (vc - 6).pow(2) + (vd - 6).pow(2);
        let before = dev(valence[a], valence[b], valence[c], valence[d]);
        let after = dev(valence[a] - 1, valence[b] - 1, valence[c] + 1, valence[d] + 1);
        // a pair with a sliver (an angle below 15°) may also flip across a sharper
        // crease (up to 60°), if that widens its smallest angle
        let sliver = thin[ts[0]] || thin[ts[1]];
        if after >= before && !sliver {
            continue;
        }
        if c == d || edge_index(&edges, c, d).is_some() || added.contains(&(c.min(d), c.max(d))) {
            continue;
        }
        let (n0, n1) = (tri_normal(p, &t0), tri_normal(p, &t1));
        let crease = if after < before { 20f64 } else { 60f64 };
        if n0.dot(&n1) < crease.to_radians().cos() * n0.norm() * n1.norm() {
            continue;
        }
        let new0 = [c, a, d];
        let new1 = [d, b, c];
        let up = n0 / n0.norm() + n1 / n1.norm();
        let angles = |t: &[usize; 3]| {
            [angle_at(p, t[0], t[1], t[2]), angle_at(p, t[1], t[2], t[0]), angle_at(p, t[2], t[0], t[1])]
        };
        let good = [new0, new1].iter().all(|t| {
            let nt = tri_normal(p, t);
            nt.norm() > 1e-12 * n0.norm() && nt.dot(&up) > 0.0 && angles(t).iter().all(|&x| x <= s.max_angle_deg)
        });
        if !good {
            continue;
        }
        if after >= before {
            let smallest = |ts: [&[usize; 3]; 2]| ts.iter().flat_map(|t| angles(t)).fold(180.0, f64::min);
            if smallest([&new0, &new1]) <= smallest([&t0, &t1]) + 1.0 {
                continue;
            }
        }
        let (i0, i1) = if tris[ts[0]] == t0 { (ts[0], ts[1]) } else { (ts[1], ts[0]) };
        tris[i0] = new0;
        tris[i1] = new1;
        touched[i0] = true;
        touched[i1] = true;
        added.insert((c.min(d), c.max(d)));
        valence[a] -= 1;
        valence[b] -= 1;
        valence[c] += 1;
        valence[d] += 1;
        any = true;
    }
    any
}

/// One adaptation pass: splits (refinement and angle-width control), collapses,
/// flips, each stage kept only if its result is a valid closed oriented surface (a
/// stage that would break it is skipped, the others still apply). Returns `None`
/// if nothing changed.
pub fn adapt_surface(mesh: &SurfaceMesh, s: &SurfaceRemeshSettings) -> Option<SurfaceMesh> {
    let mut p = mesh.positions().to_vec();
    let mut tris = mesh.elements().to_vec();
    let mut changed = false;
    let mut stage = |op: &dyn Fn(&mut Vec<Point<3>>, &mut Vec<[usize; 3]>) -> bool,
                     p: &mut Vec<Point<3>>,
                     tris: &mut Vec<[usize; 3]>| {
        let (mut p2, mut t2) = (p.clone(), tris.clone());
        if op(&mut p2, &mut t2) && closed_and_oriented(&p2, &t2) {
            *p = p2;
            *tris = t2;
            changed = true;
        }
    };
    stage(
        &|p, t| match split_edges(p, t, s) {
            Some(new) => {
                *t = new;
                true
            }
            None => false,
        },
        &mut p,
        &mut tris,
    );
    stage(&|p, t| collapse_edges(p, t, s), &mut p, &mut tris);
    stage(&|p, t| flip_edges(p, t, s), &mut p, &mut tris);
    if !changed {
        return None;
    }
    // drop vertices no longer used and renumber
    let mut used = vec![usize::MAX; p.len()];
    let mut positions = Vec::with_capacity(p.len());
    for t in &tris {
        for &v in t {
            if used[v] == usize::MAX {
                used[v] = positions.len();
                positions.push(p[v]);
            }
        }
    }
    let tris: Vec<[usize; 3]> = tris.iter().map(|t| t.map(|v| used[v])).collect();
    Some(Mesh::from_trusted_parts(positions, tris))
}

/// The checks a remeshing pass can break: every edge in exactly two triangles, in
/// opposite directions, and no degenerate triangle (the link condition of the
/// collapses keeps vertex stars manifold).
fn closed_and_oriented(p: &[Point<3>], tris: &[[usize; 3]]) -> bool {
    let edges = surface_edges(p.len(), tris);
    if edges.windows(2).any(|w| (w[0].a, w[0].b) == (w[1].a, w[1].b)) {
        return false;
    }
    let forward = |t: &[usize; 3], a: usize, b: usize| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    let scale: f64 = tris.iter().map(|t| tri_normal(p, t).norm()).sum::<f64>() / tris.len().max(1) as f64;
    edges.iter().all(|e| e.t[1] != usize::MAX && forward(&tris[e.t[0]], e.a, e.b) != forward(&tris[e.t[1]], e.a, e.b))
        && tris.iter().all(|t| tri_normal(p, t).norm() > 1e-10 * scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{ellipsoid, icosphere};

    #[test]
    fn regularization_keeps_volume_and_improves_angles() {
        let s = icosphere([0.0; 3], 1.0, 3).unwrap();
        // shear the vertices tangentially
        let p: Vec<Point<3>> = s
            .positions()
            .iter()
            .map(|x| {
                let t = Point::<3>::new(-x.y, x.x, 0.0) * (0.15 * (3.0 * x.z).sin());
                (x + t).normalize()
            })
            .collect();
        let bad = s.with_positions(p);
        let q0 = bad.quality();
        let r = regularize_surface(&bad, 10);
        let q1 = r.quality();
        assert!((r.enclosed_measure() - bad.enclosed_measure()).abs() < 1e-12, "volume kept");
        assert!(q1.min_angle_deg > q0.min_angle_deg + 5.0, "{q0:?} -> {q1:?}");
    }

    #[test]
    fn adaptivity_refines_tips_and_controls_wide_angles() {
        let e = ellipsoid([0.0; 3], [2.0, 0.5, 0.5], 3).unwrap();
        let mean = {
            let q = e.quality();
            0.5 * (q.min_edge + q.max_edge)
        };
        let s = SurfaceRemeshSettings { epsilon: 0.02, h_min: 0.1 * mean, h_max: 2.0 * mean, max_angle_deg: 120.0 };
        let mut m = e.clone();
        for _ in 0..6 {
            if let Some(next) = adapt_surface(&m, &s) {
                m = regularize_surface(&next, 3);
            }
        }
        let q = m.quality();
        assert!(q.max_angle_deg <= 125.0, "{q:?}");
        let mean_edge = |pred: &dyn Fn(f64) -> bool| {
            let mut sum = 0.0;
            let mut cnt = 0.0;
            for t in m.elements() {
                let c = (m.positions()[t[0]] + m.positions()[t[1]] + m.positions()[t[2]]) / 3.0;
                if pred(c.x) {
                    sum += (m.positions()[t[1]] - m.positions()[t[0]]).norm();
                    cnt += 1.0;
                }
            }
            sum / cnt
        };
        let tips = mean_edge(&|x| x.abs() > 1.8);
        let flanks = mean_edge(&|x| x.abs() < 0.5);
        eprintln!("tips {tips} flanks {flanks} vertices {} quality {q:?}", m.num_vertices());
        assert!(flanks > 1.5 * tips, "tips {tips} flanks {flanks}");
    }
}
