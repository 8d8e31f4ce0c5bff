//! Marching squares: the zero level of a sampled 2D function as closed polygons,
//! one per connected piece of the level set, each with the positive side on its
//! left (outer boundaries counter-clockwise, holes clockwise). Crossings are placed
//! on the grid edges by linear interpolation (sub-pixel); a saddle cell is resolved
//! by the mean of its four corners. Samples outside the grid count as negative, so
//! every polygon closes.

use crate::geometry::Point;
use std::collections::HashMap;

/// A closed polygon in grid coordinates (sample `(i, j)` at `(i, j)`).
pub type Polygon = Vec<[f64; 2]>;

/// `poly` as a closed loop of points `to_point(q)` on a grid of `l` samples per
/// unit length: a point within a tenth of a sample of the one kept before it is
/// dropped, and so are the last points within that of the first; `None` if fewer
/// than three are left.
pub fn polygon_loop(poly: Polygon, l: f64, to_point: impl Fn([f64; 2]) -> Point<2>) -> Option<Vec<Point<2>>> {
    let mut pts: Vec<Point<2>> = Vec::with_capacity(poly.len());
    for q in poly {
        let x = to_point(q);
        if pts.last().is_none_or(|p| (p - x).norm() * l > 0.1) {
            pts.push(x);
        }
    }
    while pts.len() > 3 && (pts[0] - pts[pts.len() - 1]).norm() * l <= 0.1 {
        pts.pop();
    }
    (pts.len() >= 3).then_some(pts)
}

/// The zero level of `value(i, j)` over the samples `i ∈ [i0, i1)`, `j ∈ [j0, j1)`
/// (a window of a larger grid; outside it the function is negative). `value` must
/// not be 0 (callers keep `|v|` above a floor).
pub fn zero_level(window: [usize; 4], value: impl Fn(usize, usize) -> f64) -> Vec<Polygon> {
    let [i0, i1, j0, j1] = window;
    let (w, h) = ((i1 - i0) as isize, (j1 - j0) as isize);
    let at = |i: isize, j: isize| -> f64 {
        if i < 0 || j < 0 || i >= w || j >= h {
            -1.0
        } else {
            value(i0 + i as usize, j0 + j as usize)
        }
    };
    // an edge between two samples: (i, j, horizontal?) of its lower/left sample
    type Edge = (isize, isize, bool);
    let crossing = |e: Edge| -> [f64; 2] {
        let (i, j, horizontal) = e;
        let (a, b) = (at(i, j), if horizontal { at(i + 1, j) } else { at(i, j + 1) });
        let t = a / (a - b);
        let (x, y) = if horizontal { (i as f64 + t, j as f64) } else { (i as f64, j as f64 + t) };
        [x + i0 as f64, y + j0 as f64]
    };
    let mut next: HashMap<Edge, Edge> = HashMap::new();
    for j in -1..h {
        for i in -1..w {
            // corners counter-clockwise: a (i, j), b (i+1, j), c (i+1, j+1), d (i, j+1)
            let v = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            let inside = v.map(|x| x > 0.0);
            if inside.iter().all(|&s| s) || inside.iter().all(|&s| !s) {
                continue;
            }
            // the cell's edges in the same order, each as its grid edge
            let edges: [Edge; 4] = [(i, j, true), (i + 1, j, false), (i, j + 1, true), (i, j, false)];
            let exits: Vec<usize> = (0..4).filter(|&k| inside[k] && !inside[(k + 1) % 4]).collect();
            let centre_inside = v.iter().sum::<f64>() > 0.0;
            for &k in &exits {
                // the entry edge (outside → inside) that closes this piece: the next
                // one around the cell when the centre is inside, else the previous
                let entry = if exits.len() == 1 || centre_inside {
                    (1..4).map(|s| (k + s) % 4).find(|&m| !inside[m] && inside[(m + 1) % 4])
                } else {
                    (1..4).map(|s| (k + 4 - s) % 4).find(|&m| !inside[m] && inside[(m + 1) % 4])
                };
                if let Some(m) = entry {
                    next.insert(edges[k], edges[m]);
                }
            }
        }
    }
    let mut out = Vec::new();
    let mut keys: Vec<Edge> = next.keys().copied().collect();
    keys.sort_unstable();
    for start in keys {
        if !next.contains_key(&start) {
            continue;
        }
        let mut poly = Vec::new();
        let mut e = start;
        while let Some(n) = next.remove(&e) {
            poly.push(crossing(e));
            e = n;
        }
        if poly.len() >= 3 {
            out.push(poly);
        }
    }
    out
}

/// Twice the signed area of a polygon (positive counter-clockwise).
pub fn signed_area2(p: &[[f64; 2]]) -> f64 {
    (0..p.len())
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % p.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_with_a_hole() {
        let (w, h) = (40, 40);
        let f = |i: usize, j: usize| {
            let r = (i as f64 - 20.0).hypot(j as f64 - 20.0);
            (r - 6.0).min(14.0 - r) + 1e-3
        };
        let polys = zero_level([0, w, 0, h], f);
        assert_eq!(polys.len(), 2);
        let mut areas: Vec<f64> = polys.iter().map(|p| 0.5 * signed_area2(p)).collect();
        areas.sort_by(f64::total_cmp);
        let pi = std::f64::consts::PI;
        assert!((areas[0] + pi * 36.0).abs() < 0.03 * pi * 36.0, "{areas:?}");
        assert!((areas[1] - pi * 196.0).abs() < 0.01 * pi * 196.0, "{areas:?}");
    }

    #[test]
    fn a_window_at_the_border_closes() {
        let polys = zero_level([2, 5, 3, 6], |_, _| 1.0);
        assert_eq!(polys.len(), 1);
        // the 3×3 samples to halfway to the outside ones, corners cut: 9 − 4/8
        assert!((0.5 * signed_area2(&polys[0]) - 8.5).abs() < 1e-12, "{}", signed_area2(&polys[0]));
    }
}
