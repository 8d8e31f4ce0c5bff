//! The signed distance of a closed, oriented triangle surface, sampled on a
//! regular grid: positive inside, negative outside, its magnitude the distance to
//! the nearest triangle within `band` of the surface and clamped to `band`
//! beyond. Distances come from each triangle to the grid points of its box grown
//! by `band`; the sign from the winding number along the grid's x rows: a row
//! crosses a triangle whose outward normal points against +x on its way in and
//! one that points along +x on its way out, and a point is inside where the
//! crossings before it add up to a non-zero winding. Rows are shifted by a tiny
//! irrational fraction of the spacing, so that none passes exactly through an
//! edge or a vertex (each crossing counts once).

/// A grid: its first sample's position, its spacing and its samples per axis
/// (x fastest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleGrid {
    pub origin: [f64; 3],
    pub spacing: f64,
    pub dims: [usize; 3],
}

impl SampleGrid {
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    pub fn point(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let s = self.spacing;
        [self.origin[0] + i as f64 * s, self.origin[1] + j as f64 * s, self.origin[2] + k as f64 * s]
    }

    /// The samples from `lo` to `hi` along axis `a` (clamped to the grid).
    fn range(&self, a: usize, lo: f64, hi: f64) -> std::ops::Range<usize> {
        let first = ((lo - self.origin[a]) / self.spacing).ceil().max(0.0) as usize;
        let last = ((hi - self.origin[a]) / self.spacing).floor();
        let end = if last < 0.0 { 0 } else { (last as usize + 1).min(self.dims[a]) };
        first.min(end)..end
    }
}

/// The signed distance of the surface (`positions`, `triangles`: closed and
/// oriented with outward normals) at every sample of `grid`, clamped to `band`.
pub fn signed_distance(grid: &SampleGrid, positions: &[[f64; 3]], triangles: &[[usize; 3]], band: f64) -> Vec<f64> {
    let mut distance = vec![band; grid.len()];
    for t in triangles {
        let p = t.map(|v| positions[v]);
        let lo = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min) - band);
        let hi = [0, 1, 2].map(|a| p.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max) + band);
        let (ri, rj, rk) = (grid.range(0, lo[0], hi[0]), grid.range(1, lo[1], hi[1]), grid.range(2, lo[2], hi[2]));
        for k in rk {
            for j in rj.clone() {
                for i in ri.clone() {
                    let at = grid.index(i, j, k);
                    let d = point_triangle_distance(grid.point(i, j, k), &p);
                    if d < distance[at] {
                        distance[at] = d;
                    }
                }
            }
        }
    }
    let winding = winding_numbers(grid, positions, triangles);
    distance.iter().zip(&winding).map(|(&d, &w)| if w != 0 { d } else { -d }).collect()
}

/// The winding number of the surface at every sample (see the module documentation).
fn winding_numbers(grid: &SampleGrid, positions: &[[f64; 3]], triangles: &[[usize; 3]]) -> Vec<i32> {
    let s = grid.spacing;
    // each row's (y, z), shifted off every edge and vertex
    let (dy, dz) = (s * 1.234_567_891e-7, s * 2.718_281_828e-7);
    let rows = grid.dims[1] * grid.dims[2];
    let mut crossings: Vec<Vec<(f64, i32)>> = vec![Vec::new(); rows];
    for t in triangles {
        let p = t.map(|v| positions[v]);
        let lo = |a: usize| p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
        let hi = |a: usize| p.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max);
        let (rj, rk) = (grid.range(1, lo(1) - dy, hi(1) - dy), grid.range(2, lo(2) - dz, hi(2) - dz));
        for k in rk {
            for j in rj.clone() {
                let q = grid.point(0, j, k);
                let (y, z) = (q[1] + dy, q[2] + dz);
                // barycentric coordinates of (y, z) in the triangle's (y, z) projection
                let area = |a: &[f64; 3], b: &[f64; 3], y: f64, z: f64| {
                    (b[1] - a[1]) * (z - a[2]) - (b[2] - a[2]) * (y - a[1])
                };
                let total = area(&p[0], &p[1], p[2][1], p[2][2]);
                if total == 0.0 {
                    continue;
                }
                let w = [
                    area(&p[1], &p[2], y, z) / total,
                    area(&p[2], &p[0], y, z) / total,
                    area(&p[0], &p[1], y, z) / total,
                ];
                if w.iter().any(|&c| c < 0.0) {
                    continue;
                }
                let x = w[0] * p[0][0] + w[1] * p[1][0] + w[2] * p[2][0];
                // outward normal's x component: (p1 − p0) × (p2 − p0), x part, has the sign of `total`
                let entering = if total < 0.0 { 1 } else { -1 };
                crossings[j + grid.dims[1] * k].push((x, entering));
            }
        }
    }
    let mut winding = vec![0; grid.len()];
    for (row, list) in crossings.iter_mut().enumerate() {
        if list.is_empty() {
            continue;
        }
        list.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (j, k) = (row % grid.dims[1], row / grid.dims[1]);
        let (mut w, mut next) = (0, 0);
        for i in 0..grid.dims[0] {
            let x = grid.point(i, j, k)[0];
            while next < list.len() && list[next].0 < x {
                w += list[next].1;
                next += 1;
            }
            winding[grid.index(i, j, k)] = w;
        }
    }
    winding
}

pub use crate::geometry::distance::point_triangle_distance;

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron of "radius" 1 (outward normals): inside where |x|+|y|+|z| < 1.
    fn octahedron() -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let v = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v, t)
    }

    #[test]
    fn the_signed_distance_of_an_octahedron_is_exact_near_it() {
        let (v, t) = octahedron();
        let grid = SampleGrid { origin: [-1.5; 3], spacing: 0.1, dims: [31; 3] };
        let sd = signed_distance(&grid, &v, &t, 0.4);
        for k in 0..31 {
            for j in 0..31 {
                for i in 0..31 {
                    let p = grid.point(i, j, k);
                    let l1 = p[0].abs() + p[1].abs() + p[2].abs();
                    let got = sd[grid.index(i, j, k)];
                    // near a face (not an edge or vertex region): the plane's distance
                    let exact = (1.0 - l1) / 3f64.sqrt();
                    if exact.abs() < 0.3 && p.iter().all(|c| c.abs() > 0.35) {
                        assert!((got - exact).abs() < 1e-9, "{p:?}: {got} vs {exact}");
                    }
                    if (l1 - 1.0).abs() > 1e-6 {
                        assert_eq!(got > 0.0, l1 < 1.0, "{p:?}: {got}");
                    }
                }
            }
        }
    }
}
