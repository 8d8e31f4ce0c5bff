//! Refinement of a triangle surface by edge splits.

use super::adjacency::Adjacency;
use super::triangles::{unit_normals, wide_vertices};
use super::{Frozen, SurfaceRemeshSettings};
use crate::geometry::measures::vertex_normals;
use crate::geometry::Point;

/// Refinement by edge splits: an edge is split when longer than `h_max`, when
/// `h β > ε` and its halves stay above `h_min`, or when it lies opposite an angle
/// wider than `max_angle_deg` (angle-width control). The new vertex is the edge
/// midpoint lifted by the sagitta `e·(n_b − n_a)/8` along the mean normal, which is
/// exact on a sphere with exact normals. Triangles with one, two or three split edges
/// are divided into two, three or four.
pub(super) fn split_edges(
    p: &mut Vec<Point<3>>,
    tris: &[[usize; 3]],
    adjacency: &Adjacency,
    s: &SurfaceRemeshSettings,
    frozen: &Frozen,
) -> Option<Vec<[usize; 3]>> {
    let edges = &adjacency.edges;
    let unit = unit_normals(p, tris);
    let wide = wide_vertices(p, tris, s.max_angle_deg);
    let mut normals: Option<Vec<Point<3>>> = None;
    let mut mid = vec![usize::MAX; edges.len()];
    // the triangles with a split edge (the others are kept without a lookup)
    let mut touched = vec![false; tris.len()];
    let mut count = 0;
    for (k, edge) in edges.iter().enumerate() {
        let (a, b) = (edge.a, edge.b);
        if edge.t[1] == usize::MAX || frozen.any(&[a, b]) {
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
            touched[ts[0]] = true;
            touched[ts[1]] = true;
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let m = |a: usize, b: usize| adjacency.edge(a, b).map(|k| mid[k]).filter(|&x| x != usize::MAX);
    let mut out = Vec::with_capacity(tris.len() + 3 * count);
    for (&t, &touched) in tris.iter().zip(&touched) {
        if !touched {
            out.push(t);
            continue;
        }
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
