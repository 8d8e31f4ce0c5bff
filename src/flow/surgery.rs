//! Topological surgery of surfaces by a local level set: the surface is sampled
//! as a signed distance on a grid of about its mean edge length
//! ([`signed_distance`], one function per component) and rebuilt as the zero
//! level of a combination of them by marching tetrahedra ([`zero_level_3d`]).
//!
//! - *Merge*: components in contact (the flow's intersection rule stopped them a
//!   hair apart) become one: their functions are combined by a smooth maximum of
//!   width `blend`, `max(a, b) + max(blend − |a − b|, 0)²/(4 blend)`, which equals the
//!   union away from the contact and bridges a gap narrower than `blend/2` by a
//!   neck of about the mesh size.
//! - *Pinch*: a neck thinner than the mesh resolves is cut: the function is lowered
//!   by `depth` within `radius` of the neck (a smooth bump), so that the zero level
//!   parts there, and nowhere else.
//!
//! The rebuilt surface then has the grid's resolution; the flow's mesh management
//! tidies it before the flow goes on. A flow that conserves the enclosed
//! volume gets it back ([`with_volume`]: each new component offset along its
//! normals in proportion to its volume).

use crate::geometry::{Mesh, MeshError, Point, SurfaceMesh};
use crate::imaging::isosurface::zero_level_3d;
use crate::imaging::signed_distance::{signed_distance, SampleGrid};

/// Grid samples a rebuild may use at most (a surface too fine for it is not
/// operated on: the flow stops as it would without surgery).
pub const MAX_SAMPLES: usize = 16_000_000;

/// What a rebuild changes where.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Operation {
    /// Components closer than `blend / 2` join.
    Merge { blend: f64 },
    /// The level is lowered by `depth` within `radius` of `at`.
    Cut { at: Point<3>, radius: f64, depth: f64 },
}

/// `mesh` rebuilt by `op` on a grid of `spacing`; `None` if the grid would need
/// more than [`MAX_SAMPLES`] samples or nothing is left. The result has the
/// triangles of marching tetrahedra (slivers among them), to be tidied by the
/// mesh management before the flow goes on.
pub fn rebuild(mesh: &SurfaceMesh, spacing: f64, op: Operation) -> Result<Option<SurfaceMesh>, MeshError> {
    let x: Vec<[f64; 3]> = mesh.positions().iter().map(|p| [p[0], p[1], p[2]]).collect();
    let band = 3.0 * spacing;
    let margin = band + spacing;
    let lo = [0, 1, 2].map(|a| x.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min) - margin);
    let hi = [0, 1, 2].map(|a| x.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max) + margin);
    let dims = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / spacing).ceil() as usize + 1);
    if !(spacing > 0.0) || dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d)).is_none_or(|n| n > MAX_SAMPLES) {
        return Ok(None);
    }
    let grid = SampleGrid { origin: lo, spacing, dims };
    let (labels, count) = mesh.component_labels();
    let mut level: Option<Vec<f64>> = None;
    for c in 0..count {
        let triangles: Vec<[usize; 3]> = mesh.elements().iter().filter(|t| labels[t[0]] == c).copied().collect();
        let sd = signed_distance(&grid, &x, &triangles, band);
        level = Some(match (level, op) {
            (None, _) => sd,
            (Some(f), Operation::Merge { blend }) => {
                f.iter().zip(&sd).map(|(&a, &b)| smooth_max(a, b, blend)).collect()
            }
            (Some(f), Operation::Cut { .. }) => f.iter().zip(&sd).map(|(&a, &b)| a.max(b)).collect(),
        });
    }
    let Some(mut level) = level else { return Ok(None) };
    if let Operation::Cut { at, radius, depth } = op {
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = grid.point(i, j, k);
                    let r = (Point::<3>::new(p[0], p[1], p[2]) - at).norm() / radius;
                    if r < 1.0 {
                        level[grid.index(i, j, k)] -= depth * (1.0 - r * r).powi(2);
                    }
                }
            }
        }
    }
    let (vertices, triangles) =
        zero_level_3d([0, dims[0], 0, dims[1], 0, dims[2]], |i, j, k| level[grid.index(i, j, k)]);
    if triangles.is_empty() {
        return Ok(None);
    }
    let positions = vertices
        .iter()
        .map(|q| Point::<3>::new(lo[0] + q[0] * spacing, lo[1] + q[1] * spacing, lo[2] + q[2] * spacing));
    Ok(Some(Mesh::new(positions.collect(), triangles)?))
}

/// `mesh` with the enclosed volume `before` shared by its components in
/// proportion to their own (each offset along its normals).
pub fn with_volume(mesh: SurfaceMesh, before: f64) -> SurfaceMesh {
    let after = mesh.component_measures();
    let total: f64 = after.iter().sum();
    if !(total > 0.0 && before > 0.0) {
        return mesh;
    }
    let targets: Vec<f64> = after.iter().map(|m| m * before / total).collect();
    mesh.with_component_measures(&targets)
}

/// The midpoint of the edge whose two triangles turn most sharply for its length
/// (the largest `β/h`: a neck's ring), if the mesh has an edge between two triangles.
pub fn sharpest_edge(mesh: &SurfaceMesh) -> Option<Point<3>> {
    let p = mesh.positions();
    let normals = mesh.element_normals();
    let mut faces: std::collections::HashMap<(usize, usize), usize> = std::collections::HashMap::new();
    let mut best: Option<(f64, Point<3>)> = None;
    for (t, tri) in mesh.elements().iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            match faces.remove(&key) {
                None => {
                    faces.insert(key, t);
                }
                Some(other) => {
                    let beta = normals[t].dot(&normals[other]).clamp(-1.0, 1.0).acos();
                    let sharp = beta / (p[b] - p[a]).norm();
                    if best.is_none_or(|(s, _)| sharp > s) {
                        best = Some((sharp, (p[a] + p[b]) * 0.5));
                    }
                }
            }
        }
    }
    best.map(|(_, at)| at)
}

/// The smooth maximum of `a` and `b` of width `k` (the polynomial one): `max(a, b)`
/// where they differ by `k` or more, at most `k/4` above it where they meet.
fn smooth_max(a: f64, b: f64, k: f64) -> f64 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.max(b) + h * h * k * 0.25
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{icosphere, surface_union};

    /// Two unit spheres 0.01 apart merge into one closed surface whose volume is
    /// that of the two, within a few per cent (the bridge adds a little).
    #[test]
    fn two_spheres_a_hair_apart_merge_into_one() {
        let a = icosphere([-1.005, 0.0, 0.0], 1.0, 3).unwrap();
        let b = icosphere([1.005, 0.0, 0.0], 1.0, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        assert_eq!(two.component_labels().1, 2);
        let merged = rebuild(&two, 0.1, Operation::Merge { blend: 0.2 }).unwrap().unwrap();
        assert_eq!(merged.component_labels().1, 1);
        let (v0, v1) = (two.enclosed_measure(), merged.enclosed_measure());
        assert!((v1 / v0 - 1.0).abs() < 0.05, "{v0} → {v1}");
        let conserved = with_volume(rebuild(&two, 0.1, Operation::Merge { blend: 0.2 }).unwrap().unwrap(), v0);
        assert!((conserved.enclosed_measure() / v0 - 1.0).abs() < 1e-3);
    }

    /// A dumbbell's bar cut at its middle leaves the two balls.
    #[test]
    fn a_cut_at_a_thin_bar_leaves_two_parts() {
        let a = icosphere([-1.0, 0.0, 0.0], 0.6, 3).unwrap();
        let b = icosphere([1.0, 0.0, 0.0], 0.6, 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        // merged first into one body (a fat bridge), then cut at the middle
        let one = rebuild(&two, 0.08, Operation::Merge { blend: 1.2 }).unwrap().unwrap();
        assert_eq!(one.component_labels().1, 1);
        let cut = Operation::Cut { at: Point::<3>::zeros(), radius: 0.5, depth: 1.0 };
        let parts = with_volume(rebuild(&one, 0.08, cut).unwrap().unwrap(), one.enclosed_measure());
        assert_eq!(parts.component_labels().1, 2);
        assert!((parts.enclosed_measure() / one.enclosed_measure() - 1.0).abs() < 1e-3);
    }
}
