//! Several shapes as one mesh: the union of curves (each component keeping its
//! orientation, the parts not intersecting each other) and of surfaces. The
//! `union` initial shape and the automatic initial contours of segmentation both
//! build their meshes here.

use super::curves::from_polylines;
use super::{CurveMesh, Mesh, MeshError, Point, SurfaceMesh};

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

impl<const D: usize> Mesh<D> {
    /// The mesh (not periodic) of the components `c` (of [`Mesh::component_labels`])
    /// with `keep[c]`, vertices renumbered in their order; `None` if none is kept.
    pub fn with_components(&self, keep: &[bool]) -> Option<Mesh<D>> {
        let (labels, _) = self.component_labels();
        let kept: Vec<[usize; D]> =
            self.elements().iter().filter(|e| keep.get(labels[e[0]]).copied().unwrap_or(false)).copied().collect();
        let (positions, elements) = used_vertices(self.positions(), &kept);
        (!elements.is_empty()).then(|| Mesh::from_trusted_parts(positions, elements))
    }
}

/// The vertices that `elements` use, in their order, and `elements` renumbered to
/// them.
pub(crate) fn used_vertices<const D: usize, const K: usize>(
    positions: &[Point<D>],
    elements: &[[usize; K]],
) -> (Vec<Point<D>>, Vec<[usize; K]>) {
    let mut in_use = vec![false; positions.len()];
    elements.iter().flatten().for_each(|&v| in_use[v] = true);
    let mut index = vec![usize::MAX; positions.len()];
    let mut used = Vec::new();
    for v in (0..positions.len()).filter(|&v| in_use[v]) {
        index[v] = used.len();
        used.push(positions[v]);
    }
    (used, elements.iter().map(|e| e.map(|v| index[v])).collect())
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
        let second = u.with_components(&[false, true]).unwrap();
        assert_eq!(second.num_vertices(), a.num_vertices());
        assert!((second.positions()[0][0] - a.positions()[0][0] - 3.0).abs() < 1e-12);
        assert!((second.enclosed_measure() - a.enclosed_measure()).abs() < 1e-12);
        assert!(u.with_components(&[false, false]).is_none());
    }
}
