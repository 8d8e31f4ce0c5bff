//! Several shapes as one mesh: the union of curves (each component keeping its
//! orientation, the parts not intersecting each other) and of surfaces. The
//! `union` initial shape and the automatic initial contours of segmentation both
//! build their meshes here.

use super::curves::from_polylines;
use super::{CurveMesh, Mesh, MeshError, SurfaceMesh};

/// Several curves as one mesh (the components keep their own orientation). The
/// parts must not intersect each other (checked by the mesh constructor).
pub fn union(parts: &[CurveMesh]) -> Result<CurveMesh, MeshError> {
    let mut polylines = Vec::new();
    for part in parts {
        for cyc in part.cycles() {
            polylines.push(cyc.iter().map(|&v| part.positions()[v]).collect());
        }
    }
    from_polylines(polylines)
}

/// Several closed surfaces as one mesh (their triangles side by side, vertices
/// renumbered), validated by the mesh constructor.
pub fn surface_union(parts: &[SurfaceMesh]) -> Result<SurfaceMesh, MeshError> {
    let mut positions = Vec::new();
    let mut elements = Vec::new();
    for p in parts {
        let base = positions.len();
        positions.extend_from_slice(p.positions());
        elements.extend(p.elements().iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }
    Mesh::new(positions, elements)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere};

    #[test]
    fn union_counts_components_and_rejects_overlap() {
        let a = circle([0.0, 0.0], 1.0, 64).unwrap();
        let b = circle([3.0, 0.0], 1.0, 64).unwrap();
        let u = union(&[a.clone(), b]).unwrap();
        assert_eq!(u.num_components(), 2);
        let c = circle([1.5, 0.0], 1.0, 64).unwrap();
        assert!(matches!(union(&[a, c]), Err(MeshError::SelfIntersection { .. })));
    }

    #[test]
    fn a_surface_union_keeps_every_part() {
        let a = icosphere([0.0; 3], 1.0, 1).unwrap();
        let b = icosphere([3.0, 0.0, 0.0], 1.0, 1).unwrap();
        let u = surface_union(&[a.clone(), b]).unwrap();
        assert_eq!(u.num_vertices(), 2 * a.num_vertices());
        assert_eq!(u.num_components(), 2);
        assert!((u.enclosed_measure() - 2.0 * a.enclosed_measure()).abs() < 1e-12);
    }
}
