//! Built-in closed surfaces (`Mesh<3>`): icosphere, ellipsoid, box, torus. Every
//! builder returns a validated mesh with outward-facing triangles.

use super::{Mesh, MeshError, Point, SurfaceMesh};
use std::collections::HashMap;
use std::f64::consts::PI;

/// Validate and, if the enclosed volume came out negative, flip every triangle.
fn oriented(positions: Vec<Point<3>>, mut elements: Vec<[usize; 3]>) -> Result<SurfaceMesh, MeshError> {
    let vol: f64 = elements.iter().map(|t| positions[t[0]].dot(&positions[t[1]].cross(&positions[t[2]]))).sum();
    if vol < 0.0 {
        for t in &mut elements {
            t.swap(1, 2);
        }
    }
    Mesh::new(positions, elements)
}

/// Icosphere: the icosahedron refined `level` times by edge midpoints projected to
/// the sphere; `10·4^level + 2` vertices (level 4: 2,562; 5: 10,242; 6: 40,962;
/// 7: 163,842). Vertices lie exactly on the sphere.
pub fn icosphere(center: [f64; 3], radius: f64, level: u32) -> Result<SurfaceMesh, MeshError> {
    let (unit, tris) = unit_icosphere(level);
    let c = Point::<3>::from(center);
    oriented(unit.into_iter().map(|p| c + p * radius).collect(), tris)
}

/// Ellipsoid with the given semi-axes: an icosphere of level `level` scaled per axis.
pub fn ellipsoid(center: [f64; 3], semi_axes: [f64; 3], level: u32) -> Result<SurfaceMesh, MeshError> {
    let (unit, tris) = unit_icosphere(level);
    let c = Point::<3>::from(center);
    let s = Point::<3>::from(semi_axes);
    oriented(unit.into_iter().map(|p| c + p.component_mul(&s)).collect(), tris)
}

fn unit_icosphere(level: u32) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let raw = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut pts: Vec<Point<3>> = raw.iter().map(|p| Point::<3>::from(*p).normalize()).collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(usize, usize), usize> = HashMap::with_capacity(tris.len() * 2);
        let mut next = Vec::with_capacity(tris.len() * 4);
        let mut midpoint = |a: usize, b: usize, pts: &mut Vec<Point<3>>| {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                pts.push(((pts[a] + pts[b]) * 0.5).normalize());
                pts.len() - 1
            })
        };
        for &[a, b, c] in &tris {
            let ab = midpoint(a, b, &mut pts);
            let bc = midpoint(b, c, &mut pts);
            let ca = midpoint(c, a, &mut pts);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    (pts, tris)
}

/// Axis-aligned box of the given centre and side lengths, each face a uniform grid
/// of right triangles with `divisions` grid cells per unit length (at least one per
/// side). The 8×1×1 prism of the paper (§4.4.1) at 8 divisions has 2,178 vertices.
pub fn box_surface(center: [f64; 3], size: [f64; 3], divisions: f64) -> Result<SurfaceMesh, MeshError> {
    let n: [usize; 3] = std::array::from_fn(|a| ((size[a] * divisions).round() as usize).max(1));
    let mut index: HashMap<[usize; 3], usize> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |ijk: [usize; 3], positions: &mut Vec<Point<3>>| {
        *index.entry(ijk).or_insert_with(|| {
            let p: [f64; 3] = std::array::from_fn(|a| center[a] + size[a] * (ijk[a] as f64 / n[a] as f64 - 0.5));
            positions.push(Point::<3>::from(p));
            positions.len() - 1
        })
    };
    let mut tris = Vec::new();
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        for side in [0, n[a]] {
            for i in 0..n[u] {
                for j in 0..n[v] {
                    let at = |di: usize, dj: usize| {
                        let mut ijk = [0; 3];
                        ijk[a] = side;
                        ijk[u] = i + di;
                        ijk[v] = j + dj;
                        ijk
                    };
                    let q = [
                        vertex(at(0, 0), &mut positions),
                        vertex(at(1, 0), &mut positions),
                        vertex(at(1, 1), &mut positions),
                        vertex(at(0, 1), &mut positions),
                    ];
                    // e_u × e_v = e_a: counter-clockwise in (u, v) faces +e_a.
                    let (t1, t2) = if (i + j) % 2 == 0 {
                        ([q[0], q[1], q[2]], [q[0], q[2], q[3]])
                    } else {
                        ([q[0], q[1], q[3]], [q[1], q[2], q[3]])
                    };
                    if side == 0 {
                        tris.push([t1[0], t1[2], t1[1]]);
                        tris.push([t2[0], t2[2], t2[1]]);
                    } else {
                        tris.push(t1);
                        tris.push(t2);
                    }
                }
            }
        }
    }
    Mesh::new(positions, tris)
}

/// Torus around the z axis with major radius `major`, minor radius `minor`,
/// `n_major` segments around the axis and `n_minor` around the tube.
pub fn torus(
    center: [f64; 3],
    major: f64,
    minor: f64,
    n_major: usize,
    n_minor: usize,
) -> Result<SurfaceMesh, MeshError> {
    let c = Point::<3>::from(center);
    let mut positions = Vec::with_capacity(n_major * n_minor);
    for i in 0..n_major {
        let th = 2.0 * PI * i as f64 / n_major as f64;
        for j in 0..n_minor {
            let ph = 2.0 * PI * j as f64 / n_minor as f64;
            let rr = major + minor * ph.cos();
            positions.push(c + Point::<3>::new(rr * th.cos(), rr * th.sin(), minor * ph.sin()));
        }
    }
    let id = |i: usize, j: usize| (i % n_major) * n_minor + (j % n_minor);
    let mut tris = Vec::with_capacity(2 * n_major * n_minor);
    for i in 0..n_major {
        for j in 0..n_minor {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let shifted: Vec<Point<3>> = positions.iter().map(|p| p - c).collect();
    let vol: f64 = tris.iter().map(|t| shifted[t[0]].dot(&shifted[t[1]].cross(&shifted[t[2]]))).sum();
    if vol < 0.0 {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    Mesh::new(positions, tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_counts_and_volume() {
        let s = icosphere([0.0; 3], 1.0, 4).unwrap();
        assert_eq!(s.num_vertices(), 2562);
        let v = s.enclosed_measure();
        assert!((v - 4.0 / 3.0 * PI).abs() < 0.01 * v, "{v}");
        assert_eq!(s.num_components(), 1);
    }

    #[test]
    fn paper_prism_has_2178_vertices() {
        let b = box_surface([0.0; 3], [8.0, 1.0, 1.0], 8.0).unwrap();
        assert_eq!(b.num_vertices(), 2178);
        assert!((b.enclosed_measure() - 8.0).abs() < 1e-12);
        assert!((b.boundary_measure() - 34.0).abs() < 1e-12);
    }

    #[test]
    fn torus_volume() {
        let t = torus([1.0, 2.0, 3.0], 2.0, 0.5, 128, 48).unwrap();
        let exact = 2.0 * PI * PI * 2.0 * 0.25;
        assert!((t.enclosed_measure() - exact).abs() < 0.01 * exact);
    }

    #[test]
    fn flipped_triangle_is_rejected_with_its_edge() {
        let s = icosphere([0.0; 3], 1.0, 1).unwrap();
        let mut tris = s.elements().to_vec();
        tris[3].swap(1, 2);
        let err = Mesh::new(s.positions().to_vec(), tris).unwrap_err();
        assert!(matches!(err, MeshError::InconsistentEdge { .. }), "{err}");
    }
}
