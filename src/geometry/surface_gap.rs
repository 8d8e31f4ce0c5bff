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

use super::distance::{barycentric, triangle_distance};
use super::surface_intersections::{box_pairs, mean_edge, Aabb, CELL_EDGES};
use super::{vertex_normals, Point};

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
pub fn curved_sheet_gap(x: &[Point<3>], triangles: &[[usize; 3]]) -> Option<(f64, [f64; 3])> {
    let normals = vertex_normals(x, triangles);
    // each edge's `(n_i − n_j)·(x_i − x_j)`, edge `k` from corner `k` to `k + 1`
    let bend = |t: &[usize; 3], k: usize| {
        let (i, j) = (t[k], t[(k + 1) % 3]);
        (normals[i] - normals[j]).dot(&(x[i] - x[j]))
    };
    let depth =
        |t: &[usize; 3], w: &[f64; 3]| -> f64 { (0..3).map(|k| 0.5 * w[k] * w[(k + 1) % 3] * bend(t, k)).sum() };
    // the farthest a triangle's smooth surface may lie outside it (each `b_i b_j`
    // is at most ¼)
    let reach: Vec<f64> = triangles.iter().map(|t| (0..3).map(|k| bend(t, k).max(0.0)).sum::<f64>() / 8.0).collect();
    let boxes: Vec<Aabb> = triangles
        .iter()
        .zip(&reach)
        .map(|(t, &r)| {
            let lo = std::array::from_fn(|k| t.iter().map(|&v| x[v][k]).fold(f64::INFINITY, f64::min) - r);
            let hi = std::array::from_fn(|k| t.iter().map(|&v| x[v][k]).fold(f64::NEG_INFINITY, f64::max) + r);
            (lo, hi)
        })
        .collect();
    let faces: Vec<Point<3>> =
        triangles.iter().map(|t| (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]])).normalize()).collect();
    let corners = |t: &[usize; 3]| t.map(|v| [x[v][0], x[v][1], x[v][2]]);
    let samples: Vec<[f64; 3]> = (0..=SAMPLES)
        .flat_map(|i| (0..=SAMPLES - i).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (a, b) = (i as f64 / SAMPLES as f64, j as f64 / SAMPLES as f64);
            [1.0 - a - b, a, b]
        })
        .collect();
    let mut best: Option<(f64, [f64; 3])> = None;
    box_pairs(&boxes, CELL_EDGES * mean_edge(x, triangles), |a, b| {
        let (ta, tb, na, nb) = (&triangles[a], &triangles[b], faces[a], faces[b]);
        if reach[a] + reach[b] <= 0.0 || na.dot(&nb) >= OPPOSITE || ta.iter().any(|v| tb.contains(v)) {
            return false;
        }
        if triangle_distance(&corners(ta), &corners(tb)) > reach[a] + reach[b] {
            return false;
        }
        let axis = (na - nb).normalize();
        let at = |t: &[usize; 3], w: &[f64; 3]| x[t[0]] * w[0] + x[t[1]] * w[1] + x[t[2]] * w[2];
        // from each sample of one triangle along the axis to the other's plane: the
        // flat height (`b` in front of `a` where they face across the outside)
        // and the curved one
        for (from, to, n_from, n_to, sign) in [(ta, tb, na, nb, 1.0), (tb, ta, nb, na, -1.0)] {
            for w in &samples {
                let p = at(from, w);
                let s = (x[to[0]] - p).dot(&n_to) / axis.dot(&n_to);
                let q = p + axis * s;
                let v = barycentric([q[0], q[1], q[2]], &corners(to));
                if v.iter().any(|&c| c < 0.0) {
                    continue;
                }
                if sign * s < 0.0 {
                    // across the inside
                    return false;
                }
                let lifted = (q + n_to * depth(to, &v)) - (p + n_from * depth(from, w));
                let gap = sign * lifted.dot(&axis);
                if best.is_none_or(|(g, _)| gap < g) {
                    let mid = p + axis * (0.5 * s);
                    best = Some((gap, [mid[0], mid[1], mid[2]]));
                }
            }
        }
        false
    });
    best
}

#[cfg(test)]
mod tests {
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
