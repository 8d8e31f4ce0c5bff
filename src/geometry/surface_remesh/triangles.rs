//! Measures of single triangles that the remeshing operations test.

use crate::geometry::Point;

/// The normal of triangle `t` times twice its area.
pub(super) fn tri_normal(p: &[Point<3>], t: &[usize; 3]) -> Point<3> {
    (p[t[1]] - p[t[0]]).cross(&(p[t[2]] - p[t[0]]))
}

/// The angle at `a` of the triangle `a, b, c`, in degrees.
pub(super) fn angle_at(p: &[Point<3>], a: usize, b: usize, c: usize) -> f64 {
    let (u, w) = (p[b] - p[a], p[c] - p[a]);
    (u.dot(&w) / (u.norm() * w.norm())).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Unit normals of the triangles.
pub(super) fn unit_normals(p: &[Point<3>], tris: &[[usize; 3]]) -> Vec<Point<3>> {
    tris.iter().map(|t| tri_normal(p, t).normalize()).collect()
}

/// Per triangle: its vertex with an angle wider than `max_deg`, or `usize::MAX`.
pub(super) fn wide_vertices(p: &[Point<3>], tris: &[[usize; 3]], max_deg: f64) -> Vec<usize> {
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
pub(super) fn thin_triangles(p: &[Point<3>], tris: &[[usize; 3]], min_deg: f64) -> Vec<bool> {
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
