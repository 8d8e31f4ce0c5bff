//! Edge flips of a triangle surface towards valence 6.

use super::adjacency::Adjacency;
use super::triangles::{angle_at, thin_triangles, tri_normal};
use super::{Frozen, SurfaceRemeshSettings};
use crate::geometry::Point;
use std::collections::HashSet;

/// Edge flips towards valence 6 between nearly coplanar triangles (dihedral angle
/// below 20°), when neither new triangle is degenerate, turned by more than 60°,
/// or wider than the angle limit, and the new edge does not exist yet. A pair
/// with a sliver may also flip to widen its smallest angle; a sliver beside a
/// proper triangle is judged by the proper one's normal alone (a cap, one angle
/// near 180°, has a normal of rounding noise, and one kept turns over in a step
/// of any length).
pub(super) fn flip_edges(
    p: &[Point<3>],
    tris: &mut [[usize; 3]],
    adjacency: &Adjacency,
    s: &SurfaceRemeshSettings,
    frozen: &Frozen,
) -> bool {
    let mut valence = vec![0i64; p.len()];
    let edges = &adjacency.edges;
    for e in edges {
        valence[e.a] += 1;
        valence[e.b] += 1;
    }
    let thin = thin_triangles(p, tris, 15.0);
    // edges created by earlier flips of this pass (removed ones need no record: a
    // flipped edge's triangles are touched and not considered again)
    let mut added: HashSet<(usize, usize)> = HashSet::new();
    let mut touched = vec![false; tris.len()];
    let mut any = false;
    for e in edges {
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
        if c == d
            || frozen.any(&[a, b, c, d])
            || adjacency.edge(c, d).is_some()
            || added.contains(&(c.min(d), c.max(d)))
        {
            continue;
        }
        let (n0, n1) = (tri_normal(p, &t0), tri_normal(p, &t1));
        // the normal of a sliver beside a proper triangle says nothing of the
        // surface (a cap, one angle near 180°, has a normal of rounding noise):
        // the proper one's normal stands for both
        let (i0, i1) = if tris[ts[0]] == t0 { (ts[0], ts[1]) } else { (ts[1], ts[0]) };
        let up = match (thin[i0], thin[i1]) {
            (true, false) => n1 / n1.norm(),
            (false, true) => n0 / n0.norm(),
            _ => {
                let crease = if after < before { 20f64 } else { 60f64 };
                if n0.dot(&n1) < crease.to_radians().cos() * n0.norm() * n1.norm() {
                    continue;
                }
                n0 / n0.norm() + n1 / n1.norm()
            }
        };
        let new0 = [c, a, d];
        let new1 = [d, b, c];
        let angles = |t: &[usize; 3]| {
            [angle_at(p, t[0], t[1], t[2]), angle_at(p, t[1], t[2], t[0]), angle_at(p, t[2], t[0], t[1])]
        };
        let good = [new0, new1].iter().all(|t| {
            let nt = tri_normal(p, t);
            nt.norm() > 1e-12 * n0.norm().max(n1.norm())
                && nt.dot(&up) > 0.5 * nt.norm() * up.norm()
                && angles(t).iter().all(|&x| x <= s.max_angle_deg)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::icosphere;

    /// A cap (a vertex pushed onto the middle of the opposite edge, 1e-9 off the
    /// sphere's surface): its own normal lies in the tangent plane, so a crease
    /// test on it would refuse the flip; the proper triangle across the long edge
    /// stands for both, and the long edge is flipped away.
    #[test]
    fn a_cap_beside_a_proper_triangle_is_flipped() {
        let sphere = icosphere([0.0; 3], 1.0, 2).unwrap();
        let mut p = sphere.positions().to_vec();
        let mut tris = sphere.elements().to_vec();
        let [a, b, c] = tris[0];
        let mid = (p[a] + p[b]) * 0.5;
        p[c] = mid + mid.normalize() * 1e-9;
        let before = Adjacency::of(p.len(), &tris);
        assert!(before.edge(a, b).is_some());
        let s = SurfaceRemeshSettings { epsilon: 1.0, h_min: 1e-3, h_max: 1.0, max_angle_deg: 150.0 };
        assert!(flip_edges(&p, &mut tris, &before, &s, &Frozen(&[])));
        let after = Adjacency::of(p.len(), &tris);
        assert!(after.edge(a, b).is_none(), "the cap's long edge is gone");
        let widest = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3], t[(k + 2) % 3])))
            .map(|(x, y, z)| angle_at(&p, x, y, z))
            .fold(0.0, f64::max);
        assert!(widest < 179.0, "{widest}");
    }
}
