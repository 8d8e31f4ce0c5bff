//! A boundary loop of a surface closed without a new vertex: the loop projected
//! on the plane of its vector area and triangulated by clipping ears, for the
//! loops that no fan around one vertex closes without folding (a loop that is not
//! star-shaped seen along its normal).

use crate::geometry::Point;

/// Triangles over the loop `l` of `p` (each with two consecutive loop vertices in
/// the loop's direction), if its projection along `s` (its vector area) is a
/// simple polygon and no triangle is degenerate or folded against `s`; `None`
/// otherwise.
pub(super) fn ear_cap(p: &[Point<3>], l: &[usize], s: &Point<3>) -> Option<Vec<[usize; 3]>> {
    let n = s.try_normalize(0.0)?;
    let helper = if n.x.abs() < 0.9 { Point::<3>::x() } else { Point::<3>::y() };
    let e1 = n.cross(&helper).normalize();
    let e2 = n.cross(&e1);
    let q: Vec<[f64; 2]> = l.iter().map(|&v| [p[v].dot(&e1), p[v].dot(&e2)]).collect();
    if !simple(&q) {
        return None;
    }
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let mut left: Vec<usize> = (0..l.len()).collect();
    let mut triangles = Vec::with_capacity(l.len().saturating_sub(2));
    while left.len() > 3 {
        let m = left.len();
        let ear = (0..m).find(|&k| {
            let (a, b, c) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            cross(q[a], q[b], q[c]) > 0.0
                && left.iter().all(|&v| {
                    v == a || v == b || v == c || {
                        let x = q[v];
                        cross(q[a], q[b], x) < 0.0 || cross(q[b], q[c], x) < 0.0 || cross(q[c], q[a], x) < 0.0
                    }
                })
        })?;
        triangles.push([left[(ear + m - 1) % m], left[ear], left[(ear + 1) % m]]);
        left.remove(ear);
    }
    triangles.push([left[0], left[1], left[2]]);
    let triangles: Vec<[usize; 3]> = triangles.into_iter().map(|t| t.map(|k| l[k])).collect();
    let folds = triangles.iter().any(|t| {
        let m = (p[t[1]] - p[t[0]]).cross(&(p[t[2]] - p[t[0]]));
        m.norm() <= 1e-12 * s.norm() || m.dot(s) <= 0.0
    });
    (!folds).then_some(triangles)
}

/// Whether the closed polygon `q` has no two non-adjacent sides that meet.
fn simple(q: &[[f64; 2]]) -> bool {
    let n = q.len();
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).signum()
    };
    for i in 0..n {
        let (a, b) = (q[i], q[(i + 1) % n]);
        for j in i + 2..n {
            if (j + 1) % n == i {
                continue;
            }
            let (c, d) = (q[j], q[(j + 1) % n]);
            if orient(a, b, c) != orient(a, b, d) && orient(c, d, a) != orient(c, d, b) {
                return false;
            }
        }
    }
    true
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
