//! The gap between two facing sheets of a surface, measured on the curved
//! surface that its vertex normals describe instead of on its flat triangles.
//!
//! A mesh of flat triangles interpolates a smooth surface at its vertices; inside a
//! triangle the smooth surface lies off the face by the interpolation error of a
//! quadratic, `s(b) = ½ Σ_{i<j} b_i b_j (n_i − n_j)·(x_i − x_j)` at the barycentric
//! point `b` (the second derivative along an edge `e = x_i − x_j` is `κ_e |e|²`,
//! and the vertex normals give it: `(n_i − n_j)·e ≈ κ_e |e|²`). It is outwards on a
//! convex sheet: on a sphere of radius `R` with edges `h`, up to `h²/(6R)` at a
//! face's centroid. Two convex sheets that close on each other therefore meet on
//! the flat mesh only once their smooth surfaces overlap by up to the sum of
//! those depths, and a contact seen on the triangles comes late by that
//! overlap over the closing speed: two spheres of resolution 3 (radii 0.15 and
//! 0.22, 0.032 apart) met 4.8 % after the time their radii's ODE gives, with the
//! spheres through their vertices overlapping by 0.0015.
//!
//! The curved gap of two facing triangles is the least height of the one's curved
//! patch above the other's along their common axis `u = (n_a − n_b)/|n_a − n_b|`,
//! sampled at the points of each triangle on a grid of a quarter of its edges
//! (the gap is a quadratic of the position across the axis; on spheres of
//! resolution 3 the result is within 12 % of the faces' depth of the smooth gap,
//! against up to 100 % for the flat distance).

mod cones;

use super::distance::{barycentric, triangle_distance};
use super::surface_intersections::{bounds, overlap, Aabb};
use super::Point;
use cones::Cones;

/// Most cosine between two triangles' normals for them to lie on facing sheets.
const OPPOSITE: f64 = -0.5;

/// Samples of a triangle per edge: its points of barycentric coordinates in
/// steps of `1 / SAMPLES`.
const SAMPLES: usize = 4;

/// The least curved gap between two triangles that share no vertex and lie on
/// sheets facing each other across the outside (normals nearly opposite, the one
/// flat triangle in front of the other along their axis), among those close
/// enough for it to be negative, with the point halfway across it; `None` if no
/// two triangles come that close. Neighbours on one smooth sheet never face each
/// other; two sheets that a flow brought together (of two components, or of
/// one) do; the two sides of a thin part face each other across the inside, and
/// are not measured. The triangles must not meet.
///
/// Only the triangles of patches that may face each other are measured
/// ([`cones`]: the patches' boxes and the cones of their normals); the answer
/// is that of every pair whose boxes, grown by their reach, overlap.
pub fn curved_sheet_gap(x: &[Point<3>], triangles: &[[usize; 3]]) -> Option<(f64, [f64; 3])> {
    let mut cones = Cones::new(x, triangles)?;
    let facing = cones.facing();
    if facing.is_empty() {
        return None;
    }
    let mut wanted = vec![false; cones.len()];
    for &(p, q) in &facing {
        (wanted[p], wanted[q]) = (true, true);
    }
    let members = cones.members(&wanted);
    let sheets = Sheets::new(x, triangles, std::mem::take(&mut cones.faces));
    // each wanted patch's triangles with their boxes grown by their reach
    let boxed: Vec<Vec<(usize, Aabb)>> =
        members.iter().map(|m| m.iter().map(|&t| (t, sheets.grown_box(t))).collect()).collect();
    let mut best: Option<(f64, [f64; 3])> = None;
    for (p, q) in facing {
        // the triangles of one patch that lie in the other's box and whose
        // normals may face one of its cone's
        let near = |from: usize, to: usize| -> Vec<(usize, Aabb)> {
            boxed[from].iter().filter(|(t, b)| cones.may_face(sheets.faces[*t], b, to)).copied().collect()
        };
        let (from_p, from_q) = (near(p, q), near(q, p));
        for (i, (a, box_a)) in from_p.iter().enumerate() {
            let others = if p == q { &from_p[i + 1..] } else { &from_q[..] };
            for (b, box_b) in others {
                if !overlap(box_a, box_b) {
                    continue;
                }
                if let Some(g) = sheets.gap(*a, *b).filter(|g| best.is_none_or(|b| g.0 < b.0)) {
                    best = Some(g);
                }
            }
        }
    }
    best
}

/// The triangles of a surface with what their curved gap is measured from.
struct Sheets<'a> {
    x: &'a [Point<3>],
    triangles: &'a [[usize; 3]],
    /// Unit vertex normals (area-weighted).
    normals: Vec<Point<3>>,
    /// Unit face normals.
    faces: Vec<Point<3>>,
}

impl<'a> Sheets<'a> {
    fn new(x: &'a [Point<3>], triangles: &'a [[usize; 3]], faces: Vec<Point<3>>) -> Self {
        let mut normals = vec![Point::<3>::zeros(); x.len()];
        for t in triangles {
            let c = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
            for &v in t {
                normals[v] += c;
            }
        }
        for n in &mut normals {
            let l = n.norm();
            if l > 0.0 {
                *n /= l;
            }
        }
        Sheets { x, triangles, normals, faces }
    }

    /// Edge `k`'s `(n_i − n_j)·(x_i − x_j)`, from corner `k` to `k + 1`.
    fn bend(&self, t: &[usize; 3], k: usize) -> f64 {
        let (i, j) = (t[k], t[(k + 1) % 3]);
        (self.normals[i] - self.normals[j]).dot(&(self.x[i] - self.x[j]))
    }

    /// The farthest triangle `t`'s smooth surface may lie outside it (each
    /// `b_i b_j` is at most ¼).
    fn reach(&self, t: usize) -> f64 {
        let t = &self.triangles[t];
        (0..3).map(|k| self.bend(t, k).max(0.0)).sum::<f64>() / 8.0
    }

    /// Triangle `t`'s box grown by its reach.
    fn grown_box(&self, t: usize) -> Aabb {
        let r = self.reach(t);
        let (lo, hi) = bounds(self.x, &self.triangles[t]);
        (lo.map(|c| c - r), hi.map(|c| c + r))
    }

    /// How far the smooth surface lies outside triangle `t` at barycentric `w`.
    fn depth(&self, t: &[usize; 3], w: &[f64; 3]) -> f64 {
        (0..3).map(|k| 0.5 * w[k] * w[(k + 1) % 3] * self.bend(t, k)).sum()
    }

    fn corners(&self, t: &[usize; 3]) -> [[f64; 3]; 3] {
        t.map(|v| [self.x[v][0], self.x[v][1], self.x[v][2]])
    }

    /// The curved gap of triangles `a` and `b` with the point halfway across it,
    /// if they share no vertex, face each other across the outside and are close
    /// enough for it to be negative.
    fn gap(&self, a: usize, b: usize) -> Option<(f64, [f64; 3])> {
        let (ta, tb, na, nb) = (&self.triangles[a], &self.triangles[b], self.faces[a], self.faces[b]);
        let reach = self.reach(a) + self.reach(b);
        if reach <= 0.0 || na.dot(&nb) >= OPPOSITE || ta.iter().any(|v| tb.contains(v)) {
            return None;
        }
        if triangle_distance(&self.corners(ta), &self.corners(tb)) > reach {
            return None;
        }
        let x = self.x;
        let axis = (na - nb).normalize();
        let at = |t: &[usize; 3], w: &[f64; 3]| x[t[0]] * w[0] + x[t[1]] * w[1] + x[t[2]] * w[2];
        let mut best: Option<(f64, [f64; 3])> = None;
        // from each sample of one triangle along the axis to the other's plane: the
        // flat height (`b` in front of `a` where they face across the outside)
        // and the curved one
        for (from, to, n_from, n_to, sign) in [(ta, tb, na, nb, 1.0), (tb, ta, nb, na, -1.0)] {
            for w in samples() {
                let p = at(from, &w);
                let s = (x[to[0]] - p).dot(&n_to) / axis.dot(&n_to);
                let q = p + axis * s;
                let v = barycentric([q[0], q[1], q[2]], &self.corners(to));
                if v.iter().any(|&c| c < 0.0) {
                    continue;
                }
                if sign * s < 0.0 {
                    // across the inside
                    return None;
                }
                let lifted = (q + n_to * self.depth(to, &v)) - (p + n_from * self.depth(from, &w));
                let gap = sign * lifted.dot(&axis);
                if best.is_none_or(|(g, _)| gap < g) {
                    let mid = p + axis * (0.5 * s);
                    best = Some((gap, [mid[0], mid[1], mid[2]]));
                }
            }
        }
        best
    }
}

/// The barycentric points of a triangle in steps of `1 / SAMPLES`.
fn samples() -> impl Iterator<Item = [f64; 3]> {
    (0..=SAMPLES).flat_map(|i| (0..=SAMPLES - i).map(move |j| (i, j))).map(|(i, j)| {
        let (a, b) = (i as f64 / SAMPLES as f64, j as f64 / SAMPLES as f64);
        [1.0 - a - b, a, b]
    })
}

#[cfg(test)]
mod tests {
    use super::super::surface_intersections::mean_edge;
    use super::*;
    use crate::geometry::icosphere;

    /// Two spheres of radii `r` through their vertices, centred at `ca` and
    /// `cb`, as one mesh.
    fn two_spheres(r: [f64; 2], ca: Point<3>, cb: Point<3>) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
        let (a, b) = (icosphere(ca.into(), r[0], 3).unwrap(), icosphere(cb.into(), r[1], 3).unwrap());
        let mut x = a.positions().to_vec();
        let n = x.len();
        x.extend_from_slice(b.positions());
        let mut t = a.elements().to_vec();
        t.extend(b.elements().iter().map(|e| e.map(|v| v + n)));
        (x, t)
    }

    /// Spheres through their vertices whose smooth surfaces are `gap` apart
    /// (or overlap), turned so that a vertex, an edge or a face of one faces the
    /// other: the curved gap is the smooth one to within 15 % of the flat
    /// mesh's error there (up to the faces' depth `h²/(6R)`), and its place lies
    /// between the two; sheets farther apart than the faces' depths have none, or
    /// a positive one.
    #[test]
    fn the_curved_gap_of_two_spheres_is_the_gap_of_their_smooth_surfaces() {
        let mut measured = 0;
        for (r, dir) in
            [([0.15, 0.22], [1.0, 0.0, 0.0]), ([0.2, 0.2], [0.9, 0.3, -0.2]), ([0.1, 0.3], [0.7, -0.5, 0.4])]
        {
            let dir = Point::<3>::from(dir).normalize();
            for gap in [0.004, 0.0005, 0.0, -0.0005] {
                let (ca, cb) =
                    (Point::<3>::new(0.1, -0.2, 0.3), Point::<3>::new(0.1, -0.2, 0.3) + dir * (r[0] + r[1] + gap));
                let (x, t) = two_spheres(r, ca, cb);
                if !crate::geometry::surface_intersections(&x, &t, 1).is_empty() {
                    // the flat spheres meet: not a state of a flow
                    continue;
                }
                measured += 1;
                let h = mean_edge(&x, &t);
                let flat_error = h * h / (6.0 * r[0].min(r[1]));
                let Some((curved, at)) = curved_sheet_gap(&x, &t) else {
                    assert!(gap > 2.0 * flat_error, "{r:?} {dir:?}: no facing sheets {gap} apart");
                    continue;
                };
                if gap > flat_error {
                    // only pairs that might touch are measured
                    assert!(curved > 0.0, "{r:?} {dir:?}: {curved} for {gap}");
                    continue;
                }
                assert!(
                    (curved - gap).abs() < 0.15 * flat_error,
                    "{r:?} {dir:?}: {curved} for {gap} (flat error {flat_error})"
                );
                let touch = ca + dir * r[0];
                assert!((Point::<3>::from(at) - touch).norm() < h, "{at:?} against {touch:?}");
            }
        }
        assert!(measured >= 10, "{measured} cases measured");
    }

    /// The least gap over every pair of triangles whose boxes overlap, none
    /// skipped.
    fn every_pair(x: &[Point<3>], t: &[[usize; 3]]) -> Option<f64> {
        let faces = t.iter().map(|e| (x[e[1]] - x[e[0]]).cross(&(x[e[2]] - x[e[0]])).normalize()).collect();
        let s = Sheets::new(x, t, faces);
        let boxes: Vec<Aabb> = (0..t.len()).map(|a| s.grown_box(a)).collect();
        (0..t.len())
            .flat_map(|a| (a + 1..t.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| overlap(&boxes[a], &boxes[b]))
            .filter_map(|(a, b)| s.gap(a, b).map(|g| g.0))
            .min_by(f64::total_cmp)
    }

    /// The patches' cones skip only pairs that do not face each other: the
    /// answer is that of every pair, on spheres whose vertices are jittered
    /// (wider cones), coarse spheres (a patch holds a whole side) and a torus
    /// whose hole has almost closed (sheets of one component facing).
    #[test]
    fn the_patches_skip_no_pair_that_faces_another() {
        let mut next = crate::geometry::test_numbers::numbers(7);
        let mut jitter = || next() - 0.5;
        let mut cases = Vec::new();
        for (level, noise) in [(1, 0.0), (2, 0.1), (3, 0.0), (3, 0.15)] {
            for gap in [0.003, 0.0, -0.001] {
                let (a, b) = (
                    icosphere([0.0; 3], 0.2, level).unwrap(),
                    icosphere([0.43 + gap, 0.05, 0.0], 0.23, level).unwrap(),
                );
                let h = mean_edge(a.positions(), a.elements());
                let mut x: Vec<Point<3>> = a.positions().iter().chain(b.positions()).copied().collect();
                for p in &mut x {
                    *p += Point::<3>::new(jitter(), jitter(), jitter()) * (noise * h);
                }
                let n = a.num_vertices();
                let t: Vec<[usize; 3]> =
                    a.elements().iter().copied().chain(b.elements().iter().map(|e| e.map(|v| v + n))).collect();
                cases.push((x, t));
            }
        }
        for minor in [0.29, 0.295, 0.298] {
            let torus = crate::geometry::torus([0.0; 3], 0.3, minor, 48, 40).unwrap();
            cases.push((torus.positions().to_vec(), torus.elements().to_vec()));
        }
        let mut found = 0;
        for (x, t) in &cases {
            if !crate::geometry::surface_intersections(x, t, 1).is_empty() {
                continue;
            }
            let gap = curved_sheet_gap(x, t).map(|g| g.0);
            assert_eq!(gap, every_pair(x, t), "{} triangles", t.len());
            found += usize::from(gap.is_some());
        }
        assert!(found >= 8, "{found} cases with facing sheets");
    }

    /// One sphere alone has no facing sheets; a thin flat slab's two faces face
    /// each other across the inside, never the outside.
    #[test]
    fn one_smooth_sheet_and_the_inside_of_a_slab_are_no_gap() {
        let s = icosphere([0.0; 3], 0.3, 3).unwrap();
        assert!(curved_sheet_gap(s.positions(), s.elements()).is_none());
        let slab = crate::geometry::box_surface([0.0; 3], [1.0, 1.0, 0.01], 8.0).unwrap();
        assert!(curved_sheet_gap(slab.positions(), slab.elements()).is_none());
    }
}
