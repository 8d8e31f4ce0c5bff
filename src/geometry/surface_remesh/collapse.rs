//! Coarsening of a triangle surface by edge collapses.

use super::adjacency::Adjacency;
use super::triangles::{tri_normal, unit_normals};
use super::{Frozen, SurfaceRemeshSettings};
use crate::geometry::Point;

/// Coarsening by edge collapses: an edge shorter than `h_min`, or flat (`h β` below
/// `ε/8` at every edge around both ends) and shorter than `h_max/2`, is collapsed to
/// its midpoint when the link condition holds (exactly two common neighbours), no
/// triangle turns by more than 30°, becomes degenerate or gets an angle wider than
/// `max_angle_deg`, and no new edge exceeds `h_max`. One collapse per vertex star
/// and pass.
pub(super) fn collapse_edges(
    p: &mut [Point<3>],
    tris: &mut Vec<[usize; 3]>,
    adjacency: &Adjacency,
    s: &SurfaceRemeshSettings,
    frozen: &Frozen,
) -> bool {
    let n = p.len();
    let edges = &adjacency.edges;
    let unit = unit_normals(p, tris);
    let mut flat_vertex = vec![true; n];
    for e in edges {
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
    let stars = &adjacency.stars;
    let mut locked: Vec<bool> = (0..n).map(|v| frozen.any(&[v])).collect();
    let mut dead = vec![false; tris.len()];
    let mut remap: Vec<usize> = (0..n).collect();
    let mut any = false;
    let neighbours = |v: usize, tris: &[[usize; 3]]| -> Vec<usize> {
        let mut nb: Vec<usize> = stars.star(v).iter().flat_map(|&t| tris[t]).filter(|&x| x != v).collect();
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
        let star: Vec<usize> = stars.star(a).iter().chain(stars.star(b)).copied().collect();
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
