//! Shapes back onto the sample grid: inside/outside masks of closed curves and
//! surfaces (nonzero winding at sample centres), and contours drawn over an image.

use super::grid::Grid;
use crate::geometry::Point;

/// Sample centres along one axis: `(i + ½)/L`.
#[inline]
fn centre(i: usize, l: f64) -> f64 {
    (i as f64 + 0.5) / l
}

/// The mask of the region enclosed by closed polygons (`segments` index
/// `positions`), on a 2D grid of `dims` with `L = max(dims)`; row `j = 0` at the
/// bottom. Nonzero winding, so orientation errors cannot punch holes.
pub fn rasterize_curve(positions: &[Point<2>], segments: &[[usize; 2]], dims: [usize; 2]) -> Vec<bool> {
    let l = dims[0].max(dims[1]) as f64;
    rasterize_curve_window(positions, segments, l, [0, dims[0], 0, dims[1]])
}

/// [`rasterize_curve`] on the window `[i0, i1) × [j0, j1)` of a grid with `L`
/// samples per unit (the mask of the window's samples, row by row).
pub fn rasterize_curve_window(
    positions: &[Point<2>],
    segments: &[[usize; 2]],
    l: f64,
    window: [usize; 4],
) -> Vec<bool> {
    let [i0, i1, j0, j1] = window;
    let (w, h) = (i1 - i0, j1 - j0);
    let mut rows: Vec<Vec<(f64, i32)>> = vec![Vec::new(); h];
    for s in segments {
        let (a, b) = (positions[s[0]], positions[s[1]]);
        if a.y == b.y {
            continue;
        }
        let (lo, hi) = (a.y.min(b.y), a.y.max(b.y));
        // rows whose centre y satisfies lo <= y < hi
        let r0 = ((lo * l - 0.5).ceil().max(j0 as f64)) as usize;
        let r1 = ((hi * l - 0.5).ceil().min(j1 as f64)).max(j0 as f64) as usize;
        for j in r0..r1.max(r0) {
            let y = centre(j, l);
            if y < lo || y >= hi {
                continue;
            }
            let x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
            rows[j - j0].push((x, if b.y > a.y { 1 } else { -1 }));
        }
    }
    let mut mask = vec![false; w * h];
    for (r, row) in rows.iter_mut().enumerate() {
        fill_line(row, i0, w, l, |i, inside| mask[i + w * r] = inside);
    }
    mask
}

/// Along one grid line: sort the boundary crossings `(coordinate, ±1)` and report
/// for each of the `n` cell centres from `first` on whether the winding number
/// there is nonzero (`set(i − first, inside)`).
fn fill_line(hits: &mut [(f64, i32)], first: usize, n: usize, l: f64, mut set: impl FnMut(usize, bool)) {
    hits.sort_by(|p, q| p.0.total_cmp(&q.0));
    let (mut winding, mut next) = (0, 0);
    for i in 0..n {
        let x = centre(first + i, l);
        while next < hits.len() && hits[next].0 < x {
            winding += hits[next].1;
            next += 1;
        }
        set(i, winding != 0);
    }
}

/// The mask of the solid enclosed by a closed triangle surface, on a 3D grid of
/// `dims` (`L = max(dims)`), by casting one ray along `z` per column.
pub fn rasterize_surface(positions: &[Point<3>], triangles: &[[usize; 3]], dims: [usize; 3]) -> Vec<bool> {
    let l = dims.iter().copied().max().unwrap_or(1) as f64;
    rasterize_surface_window(positions, triangles, l, [0, dims[0], 0, dims[1], 0, dims[2]])
}

/// [`rasterize_surface`] on the window `[i0, i1) × [j0, j1) × [k0, k1)` of a grid
/// with `L` samples per unit (`x` fastest).
pub fn rasterize_surface_window(
    positions: &[Point<3>],
    triangles: &[[usize; 3]],
    l: f64,
    window: [usize; 6],
) -> Vec<bool> {
    let [i0, i1, j0, j1, k0, k1] = window;
    let (w, h, d) = (i1 - i0, j1 - j0, k1 - k0);
    // tiny irrational offsets keep rays off edges and vertices
    let (ox, oy) = (1.3e-7, 2.9e-7);
    let mut columns: Vec<Vec<(f64, i32)>> = vec![Vec::new(); w * h];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v]);
        let (xmin, xmax) = (a.x.min(b.x).min(c.x), a.x.max(b.x).max(c.x));
        let (ymin, ymax) = (a.y.min(b.y).min(c.y), a.y.max(b.y).max(c.y));
        let range = |lo: f64, hi: f64, from: usize, to: usize| {
            let s0 = ((lo * l - 0.5).floor().max(from as f64)) as usize;
            let s1 = ((hi * l - 0.5).ceil() + 1.0).clamp(from as f64, to as f64) as usize;
            s0..s1.max(s0)
        };
        let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if det == 0.0 {
            continue;
        }
        for j in range(ymin, ymax, j0, j1) {
            for i in range(xmin, xmax, i0, i1) {
                let (x, y) = (centre(i, l) + ox, centre(j, l) + oy);
                let l1 = ((b.x - x) * (c.y - y) - (c.x - x) * (b.y - y)) / det;
                let l2 = ((c.x - x) * (a.y - y) - (a.x - x) * (c.y - y)) / det;
                let l3 = 1.0 - l1 - l2;
                if l1 < 0.0 || l2 < 0.0 || l3 < 0.0 {
                    continue;
                }
                let z = l1 * a.z + l2 * b.z + l3 * c.z;
                columns[(i - i0) + w * (j - j0)].push((z, if det > 0.0 { 1 } else { -1 }));
            }
        }
    }
    let mut mask = vec![false; w * h * d];
    for (col, hits) in columns.iter_mut().enumerate() {
        fill_line(hits, k0, d, l, |k, inside| mask[col + w * h * k] = inside);
    }
    mask
}

/// An RGB picture (rows top to bottom, as in image files) of a 2D grid in gray
/// with the curve's segments drawn over it in red.
pub fn draw_overlay(image: &Grid, positions: &[Point<2>], segments: &[[usize; 2]]) -> Vec<u8> {
    let [w, h, _] = image.dims;
    let l = image.scale();
    let gray = image.normalized(255.0).unwrap_or_else(|| Grid { values: vec![128.0; image.len()], ..image.clone() });
    let mut rgb = vec![0u8; w * h * 3];
    for j in 0..h {
        for i in 0..w {
            let v = gray.values[i + w * j].round().clamp(0.0, 255.0) as u8;
            let o = 3 * (i + w * (h - 1 - j));
            rgb[o..o + 3].copy_from_slice(&[v, v, v]);
        }
    }
    let half = (l / 512.0).floor() as isize; // thicker lines on large images
    for s in segments {
        let (a, b) = (positions[s[0]] * l, positions[s[1]] * l);
        let steps = ((b - a).norm() * 4.0).ceil().max(1.0) as usize;
        for q in 0..=steps {
            let p = a + (b - a) * (q as f64 / steps as f64);
            let (ci, cj) = ((p.x - 0.5).round() as isize, (p.y - 0.5).round() as isize);
            for dj in -half..=half {
                for di in -half..=half {
                    let (i, j) = (ci + di, cj + dj);
                    if i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h {
                        let o = 3 * (i as usize + w * (h - 1 - j as usize));
                        rgb[o..o + 3].copy_from_slice(&[230, 30, 30]);
                    }
                }
            }
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere};

    #[test]
    fn disc_and_ball_masks_have_the_right_measure() {
        let c = circle([0.5, 0.5], 0.3, 400).unwrap();
        let n = 200;
        let m = rasterize_curve(c.positions(), c.elements(), [n, n]);
        let area = m.iter().filter(|&&b| b).count() as f64 / (n * n) as f64;
        assert!((area - c.enclosed_measure()).abs() < 2e-3, "{area}");
        let s = icosphere([0.5, 0.5, 0.5], 0.3, 4).unwrap();
        let n = 64;
        let m = rasterize_surface(s.positions(), s.elements(), [n, n, n]);
        let vol = m.iter().filter(|&&b| b).count() as f64 / (n * n * n) as f64;
        assert!((vol - s.enclosed_measure()).abs() < 0.01 * s.enclosed_measure(), "{vol}");
    }
}
