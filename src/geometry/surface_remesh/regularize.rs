//! Tangential regularization of a closed triangle surface that keeps its volume.

use super::adjacency::Stars;
use super::triangles::tri_normal;
use crate::geometry::{Point, SurfaceMesh};

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
    let stars = Stars::of(p.len(), tris);
    let mut normals: Vec<Point<3>> = Vec::with_capacity(16);
    for _ in 0..sweeps {
        for v in 0..p.len() {
            let star = stars.star(v);
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
