//! Built-in closed curves (`Mesh<2>`): circle, ellipse, rectangle, polygon, union.
//! Every builder takes a resolution (number of vertices) and returns a validated
//! mesh whose components run counter-clockwise.

use super::{CurveMesh, Mesh, MeshError, Point};
use std::f64::consts::PI;

/// Build a curve mesh from closed polylines, one per component, each listed once
/// (the closing segment is implied). Orientation is taken as given.
pub(crate) fn from_polylines(parts: Vec<Vec<Point<2>>>) -> Result<CurveMesh, MeshError> {
    let (positions, elements) = polyline_parts(parts);
    Mesh::new(positions, elements)
}

/// Closed polygons as one mesh, each keeping its orientation (counter-clockwise
/// for an outer boundary, clockwise for a hole); validated like any mesh.
pub fn curves_from_loops(loops: Vec<Vec<Point<2>>>) -> Result<CurveMesh, MeshError> {
    from_polylines(loops)
}

/// `mesh` without its closed components of `|area| < min_area` (a contour that
/// shrank to nothing), or `None` if there is none, or if they are all there is
/// (the last one is kept), or for a periodic mesh.
pub fn drop_small_loops(mesh: &CurveMesh, min_area: f64) -> Option<CurveMesh> {
    if mesh.period().is_some() {
        return None;
    }
    let loops: Vec<Vec<Point<2>>> =
        mesh.cycles().into_iter().map(|c| c.iter().map(|&v| mesh.positions()[v]).collect()).collect();
    let keep: Vec<bool> = loops.iter().map(|l| super::curve_loop::loop_area(l).abs() >= min_area).collect();
    if keep.iter().all(|&k| k) || keep.iter().all(|&k| !k) {
        return None;
    }
    let kept = loops.into_iter().zip(keep).filter_map(|(l, k)| k.then_some(l)).collect();
    from_polylines_trusted(kept).ok()
}

/// Whether every closed component of `mesh` encloses less than `min_area` (what
/// [`drop_small_loops`] would remove, were it allowed to remove all); `false` for
/// periodic curves.
pub fn all_loops_below(mesh: &CurveMesh, min_area: f64) -> bool {
    mesh.period().is_none()
        && mesh.cycles().iter().all(|c| {
            let l: Vec<Point<2>> = c.iter().map(|&v| mesh.positions()[v]).collect();
            super::curve_loop::loop_area(&l).abs() < min_area
        })
}

/// Like [`from_polylines`] for the remeshing kernels, which keep every component
/// closed with at least three distinct vertices: no validation pass (an
/// intersection created by a remeshing step is resolved by the topology step of
/// the next one). Empty input is still an error.
pub(crate) fn from_polylines_trusted(parts: Vec<Vec<Point<2>>>) -> Result<CurveMesh, MeshError> {
    if parts.iter().all(|p| p.is_empty()) {
        return Err(MeshError::Empty);
    }
    let (positions, elements) = polyline_parts(parts);
    Ok(Mesh::from_trusted_parts(positions, elements))
}

fn polyline_parts(parts: Vec<Vec<Point<2>>>) -> (Vec<Point<2>>, Vec<[usize; 2]>) {
    let mut positions = Vec::new();
    let mut elements = Vec::new();
    for part in parts {
        let base = positions.len();
        let n = part.len();
        positions.extend(part);
        for k in 0..n {
            elements.push([base + k, base + (k + 1) % n]);
        }
    }
    (positions, elements)
}

/// Circle of the given centre and radius with `n` equally spaced vertices (at the
/// angles `2πk/n`, exactly on the circle).
pub fn circle(center: [f64; 2], radius: f64, n: usize) -> Result<CurveMesh, MeshError> {
    let pts = (0..n)
        .map(|k| {
            let t = 2.0 * PI * k as f64 / n as f64;
            Point::<2>::new(center[0] + radius * t.cos(), center[1] + radius * t.sin())
        })
        .collect();
    from_polylines(vec![pts])
}

/// Ellipse with semi-axes `(a, b)`, rotated by `rotation` radians, with `n` vertices
/// equally spaced in arclength.
pub fn ellipse(center: [f64; 2], semi_axes: [f64; 2], rotation: f64, n: usize) -> Result<CurveMesh, MeshError> {
    let [a, b] = semi_axes;
    let at = |th: f64| Point::<2>::new(a * th.cos(), b * th.sin());
    let fine = 64 * n.max(3);
    let mut s = vec![0.0; fine + 1];
    for k in 0..fine {
        let th0 = 2.0 * PI * k as f64 / fine as f64;
        let th1 = 2.0 * PI * (k + 1) as f64 / fine as f64;
        s[k + 1] = s[k] + (at(th1) - at(th0)).norm();
    }
    let total = s[fine];
    let (c, r) = (rotation.cos(), rotation.sin());
    let mut pts = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let target = total * k as f64 / n as f64;
        while s[j + 1] < target {
            j += 1;
        }
        let f = if s[j + 1] > s[j] { (target - s[j]) / (s[j + 1] - s[j]) } else { 0.0 };
        let th = 2.0 * PI * (j as f64 + f) / fine as f64;
        let p = at(th);
        pts.push(Point::<2>::new(center[0] + c * p.x - r * p.y, center[1] + r * p.x + c * p.y));
    }
    from_polylines(vec![pts])
}

/// Axis-aligned rectangle of the given centre and side lengths with about `n`
/// vertices spread evenly along the perimeter (corners always included).
pub fn rectangle(center: [f64; 2], size: [f64; 2], n: usize) -> Result<CurveMesh, MeshError> {
    let [w, h] = size;
    let corners = vec![
        Point::<2>::new(center[0] - 0.5 * w, center[1] - 0.5 * h),
        Point::<2>::new(center[0] + 0.5 * w, center[1] - 0.5 * h),
        Point::<2>::new(center[0] + 0.5 * w, center[1] + 0.5 * h),
        Point::<2>::new(center[0] - 0.5 * w, center[1] + 0.5 * h),
    ];
    polygon(&corners, Some(n))
}

/// Closed polygon through `points` (either orientation; returned counter-clockwise).
/// With `Some(n)`, the edges are subdivided so that the result has about `n` vertices
/// evenly spaced in arclength, the given corners kept.
pub fn polygon(points: &[Point<2>], n: Option<usize>) -> Result<CurveMesh, MeshError> {
    let mut pts: Vec<Point<2>> = points.to_vec();
    let area: f64 = (0..pts.len())
        .map(|k| {
            let (p, q) = (pts[k], pts[(k + 1) % pts.len()]);
            0.5 * (p.x * q.y - q.x * p.y)
        })
        .sum();
    if area < 0.0 {
        pts.reverse();
    }
    if let Some(n) = n {
        let m = pts.len();
        let lens: Vec<f64> = (0..m).map(|k| (pts[(k + 1) % m] - pts[k]).norm()).collect();
        let total: f64 = lens.iter().sum();
        let spacing = total / n.max(m) as f64;
        let mut out = Vec::with_capacity(n);
        for k in 0..m {
            let pieces = ((lens[k] / spacing).round() as usize).max(1);
            for j in 0..pieces {
                let f = j as f64 / pieces as f64;
                out.push(pts[k] + (pts[(k + 1) % m] - pts[k]) * f);
            }
        }
        pts = out;
    }
    from_polylines(vec![pts])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_measures() {
        let c = circle([0.0, 0.0], 2.0, 512).unwrap();
        assert!((c.enclosed_measure() - PI * 4.0).abs() < 1e-3);
        assert!((c.boundary_measure() - 4.0 * PI).abs() < 1e-3);
        assert_eq!(c.num_components(), 1);
    }

    #[test]
    fn clockwise_polygon_is_reoriented_and_bowtie_rejected() {
        let sq = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]].map(|p| Point::<2>::new(p[0], p[1]));
        let m = polygon(&sq, Some(40)).unwrap();
        assert!((m.enclosed_measure() - 1.0).abs() < 1e-12);
        assert_eq!(m.num_vertices(), 40);
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]].map(|p| Point::<2>::new(p[0], p[1]));
        assert!(matches!(polygon(&bow, None), Err(MeshError::SelfIntersection { .. })));
    }
}
