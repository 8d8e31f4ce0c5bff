//! Marching tetrahedra: the zero level of a sampled 3D function as a closed,
//! oriented triangle surface (outward normals point to the negative side). Each
//! cell of eight samples is cut into six tetrahedra around its main diagonal (the
//! same cut in every cell, so neighbouring cells agree on their shared faces), and
//! each tetrahedron contributes up to two triangles. Vertices lie on the grid's
//! edges (and face and cell diagonals), shared between cells, so the surface is
//! watertight; crossings are kept at least a tenth of an edge away from the
//! samples, so that no triangle degenerates. Outside the window the function is
//! negative.

use std::collections::HashMap;

/// Vertices (grid coordinates) and triangles of a surface.
pub type Surface = (Vec<[f64; 3]>, Vec<[usize; 3]>);

/// Corners of a cell as offsets, and its six tetrahedra around the diagonal 0–7.
const CORNERS: [[usize; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]];
const TETS: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]];

/// The zero level of `value(i, j, k)` over the samples of `window`
/// (`[i0, i1, j0, j1, k0, k1]`, half-open).
pub fn zero_level_3d(window: [usize; 6], value: impl Fn(usize, usize, usize) -> f64) -> Surface {
    let [i0, i1, j0, j1, k0, k1] = window;
    let n = [(i1 - i0) as isize, (j1 - j0) as isize, (k1 - k0) as isize];
    // padded sample index: −1 … n inclusive along each axis
    let key = |p: [isize; 3]| -> u64 {
        let s = |a: usize| (p[a] + 1) as u64;
        s(0) + (n[0] as u64 + 2) * (s(1) + (n[1] as u64 + 2) * s(2))
    };
    let at = |p: [isize; 3]| -> f64 {
        if (0..3).any(|a| p[a] < 0 || p[a] >= n[a]) {
            -1.0
        } else {
            value(i0 + p[0] as usize, j0 + p[1] as usize, k0 + p[2] as usize)
        }
    };
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut index: HashMap<(u64, u64), usize> = HashMap::new();
    let mut triangles = Vec::new();
    let origin = [i0 as f64, j0 as f64, k0 as f64];
    // the vertex on the segment a–b (by the keys of its ends), made once
    let mut vertex = |vertices: &mut Vec<[f64; 3]>, a: [isize; 3], fa: f64, b: [isize; 3], fb: f64| -> usize {
        let (ka, kb) = (key(a), key(b));
        let k = if ka < kb { (ka, kb) } else { (kb, ka) };
        *index.entry(k).or_insert_with(|| {
            let t = (fa / (fa - fb)).clamp(0.1, 0.9);
            vertices.push(std::array::from_fn(|c| origin[c] + a[c] as f64 + t * (b[c] - a[c]) as f64));
            vertices.len() - 1
        })
    };
    for k in -1..n[2] {
        for j in -1..n[1] {
            for i in -1..n[0] {
                let p: [[isize; 3]; 8] = std::array::from_fn(|c| {
                    [i + CORNERS[c][0] as isize, j + CORNERS[c][1] as isize, k + CORNERS[c][2] as isize]
                });
                let f: [f64; 8] = std::array::from_fn(|c| at(p[c]));
                let inside = f.map(|v| v > 0.0);
                if inside.iter().all(|&s| s) || inside.iter().all(|&s| !s) {
                    continue;
                }
                for tet in TETS {
                    let (ins, outs): (Vec<usize>, Vec<usize>) = tet.iter().partition(|&&c| inside[c]);
                    let tris: Vec<[(usize, usize); 3]> = match (ins.len(), outs.len()) {
                        (1, 3) => vec![[(ins[0], outs[0]), (ins[0], outs[1]), (ins[0], outs[2])]],
                        (3, 1) => vec![[(ins[0], outs[0]), (ins[1], outs[0]), (ins[2], outs[0])]],
                        (2, 2) => vec![
                            [(ins[0], outs[0]), (ins[0], outs[1]), (ins[1], outs[1])],
                            [(ins[0], outs[0]), (ins[1], outs[1]), (ins[1], outs[0])],
                        ],
                        _ => continue,
                    };
                    // a point of the inside, to orient the triangles away from it
                    let c_in: [f64; 3] = std::array::from_fn(|c| {
                        ins.iter().map(|&v| p[v][c] as f64).sum::<f64>() / ins.len() as f64 + origin[c]
                    });
                    for tri in tris {
                        let mut v = tri.map(|(a, b)| vertex(&mut vertices, p[a], f[a], p[b], f[b]));
                        let x = v.map(|q| vertices[q]);
                        let (u, w) = (sub(x[1], x[0]), sub(x[2], x[0]));
                        let normal = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
                        let out = sub(x[0], c_in);
                        if normal[0] * out[0] + normal[1] * out[1] + normal[2] * out[2] < 0.0 {
                            v.swap(1, 2);
                        }
                        triangles.push(v);
                    }
                }
            }
        }
    }
    (vertices, triangles)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ball of radius 6: closed (every edge in two triangles, once each way), the
    /// enclosed volume near 4/3 π r³.
    #[test]
    fn a_ball_is_closed_and_has_its_volume() {
        let (v, t) = zero_level_3d([0, 20, 0, 20, 0, 20], |i, j, k| {
            6.0 - ((i as f64 - 10.0).powi(2) + (j as f64 - 9.5).powi(2) + (k as f64 - 10.2).powi(2)).sqrt() + 1e-3
        });
        let mut edges = HashMap::new();
        for tri in &t {
            for e in 0..3 {
                *edges.entry((tri[e], tri[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        assert!(edges.iter().all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1)));
        let volume: f64 = t
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|q| v[q]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 216.0;
        assert!((volume / exact - 1.0).abs() < 0.03, "{volume} {exact}");
    }
}
