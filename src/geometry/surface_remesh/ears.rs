//! A boundary loop of a surface closed without a new vertex: the loop projected
//! on the plane of its vector area and triangulated by clipping ears, for the
//! loops that no fan around one vertex closes without folding (a loop that is not
//! star-shaped seen along its normal).

use crate::geometry::intersect::cross;
use crate::geometry::{find_segment_intersections, Point};

/// Whether the triangle `a, b, c` is degenerate or folded against the direction
/// `s` (its normal `(b − a) × (c − a)` tiny beside `|s|`, or against `s`): the test
/// of every cap of a cluster's patch, fan or ears.
pub(super) fn folded(a: Point<3>, b: Point<3>, c: Point<3>, s: &Point<3>) -> bool {
    let m = (b - a).cross(&(c - a));
    m.norm() <= 1e-12 * s.norm() || m.dot(s) <= 0.0
}

/// Triangles over the loop `l` of `p` (each with two consecutive loop vertices in
/// the loop's direction), if its projection along `s` (its vector area) is a
/// simple polygon and no triangle is [`folded`]; `None` otherwise.
pub(super) fn ear_cap(p: &[Point<3>], l: &[usize], s: &Point<3>) -> Option<Vec<[usize; 3]>> {
    let n = s.try_normalize(0.0)?;
    let helper = if n.x.abs() < 0.9 { Point::<3>::x() } else { Point::<3>::y() };
    let e1 = n.cross(&helper).normalize();
    let e2 = n.cross(&e1);
    let q: Vec<Point<2>> = l.iter().map(|&v| Point::<2>::new(p[v].dot(&e1), p[v].dot(&e2))).collect();
    let sides: Vec<[usize; 2]> = (0..q.len()).map(|i| [i, (i + 1) % q.len()]).collect();
    if !find_segment_intersections(&q, &sides).is_empty() {
        return None; // the projection crosses itself
    }
    let turn = |a: usize, b: usize, c: usize| cross(q[b] - q[a], q[c] - q[a]);
    let mut left: Vec<usize> = (0..l.len()).collect();
    let mut triangles = Vec::with_capacity(l.len().saturating_sub(2));
    while left.len() > 3 {
        let m = left.len();
        let ear = (0..m).find(|&k| {
            let (a, b, c) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            turn(a, b, c) > 0.0
                && left.iter().all(|&v| {
                    v == a || v == b || v == c || turn(a, b, v) < 0.0 || turn(b, c, v) < 0.0 || turn(c, a, v) < 0.0
                })
        })?;
        triangles.push([left[(ear + m - 1) % m], left[ear], left[(ear + 1) % m]]);
        left.remove(ear);
    }
    triangles.push([left[0], left[1], left[2]]);
    let triangles: Vec<[usize; 3]> = triangles.into_iter().map(|t| t.map(|k| l[k])).collect();
    let folds = triangles.iter().any(|t| folded(p[t[0]], p[t[1]], p[t[2]], s));
    (!folds).then_some(triangles)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A counter-clockwise comb of 4 × 3 with two slots of 0.5 × 2 (12 vertices,
    /// not star-shaped about its centroid), lifted to the height `z(x, y)`.
    pub(in crate::geometry::surface_remesh) fn comb(z: impl Fn(f64, f64) -> f64) -> Vec<Point<3>> {
        [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [3.0, 3.0], [3.0, 1.0], [2.5, 1.0], [2.5, 3.0]]
            .into_iter()
            .chain([[1.5, 3.0], [1.5, 1.0], [1.0, 1.0], [1.0, 3.0], [0.0, 3.0]])
            .map(|[x, y]| Point::<3>::new(x, y, z(x, y)))
            .collect()
    }

    /// A comb-shaped loop (not star-shaped about any point near its centroid) on a
    /// bent sheet: the cap covers its projected area, each triangle turned with
    /// the loop; a loop that crosses itself in projection is refused.
    #[test]
    fn a_comb_is_closed_by_ears() {
        let p = comb(|x, _| 0.05 * x * x);
        let l: Vec<usize> = (0..p.len()).collect();
        let s = (0..l.len()).fold(Point::<3>::zeros(), |acc, i| acc + p[i].cross(&p[(i + 1) % l.len()])) * 0.5;
        let tris = ear_cap(&p, &l, &s).expect("the comb is capped");
        assert_eq!(tris.len(), l.len() - 2);
        let projected: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| p[v]);
                0.5 * ((b - a).cross(&(c - a))).z
            })
            .sum();
        // 4 × 3 minus the two slots of 0.5 × 2
        assert!((projected - 10.0).abs() < 1e-12, "{projected}");
        let bow: Vec<Point<3>> = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]
            .into_iter()
            .map(|[x, y]| Point::<3>::new(x, y, 0.0))
            .collect();
        assert!(ear_cap(&bow, &[0, 1, 2, 3], &Point::<3>::z()).is_none());
    }
}
