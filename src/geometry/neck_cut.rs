//! A neck of a closed surface cut on the mesh itself (the pinch-off surgery of
//! Kovács's "numerical surgery" for mean curvature flow): the triangles within a
//! ball around the neck are removed, and each hole they leave is capped by a fan
//! from the centroid of its rim. The rest of the mesh is left as it is.

use super::{Mesh, MeshError, Point, SurfaceMesh};
use std::collections::{HashMap, HashSet};

/// `mesh` with the triangles that have a corner within `radius` of `at` removed
/// and every hole capped; `None` if nothing is removed, or the holes' rims are not
/// simple loops (the ball cuts the surface in more than a neck), or the capped
/// mesh is not a valid closed surface.
pub fn cut_neck(mesh: &SurfaceMesh, at: Point<3>, radius: f64) -> Option<SurfaceMesh> {
    let x = mesh.positions();
    let near: Vec<bool> = x.iter().map(|p| (p - at).norm() < radius).collect();
    let kept: Vec<[usize; 3]> = mesh.elements().iter().filter(|t| !t.iter().any(|&v| near[v])).copied().collect();
    if kept.len() == mesh.elements().len() || kept.is_empty() {
        return None;
    }
    // the rims: directed edges of the kept triangles whose reverse is not one
    let mut directed: HashSet<(usize, usize)> = HashSet::with_capacity(3 * kept.len());
    for t in &kept {
        for k in 0..3 {
            directed.insert((t[k], t[(k + 1) % 3]));
        }
    }
    let mut next: HashMap<usize, usize> = HashMap::new();
    for &(a, b) in &directed {
        if !directed.contains(&(b, a)) && next.insert(a, b).is_some() {
            // two rims through one vertex
            return None;
        }
    }
    let mut positions: Vec<Point<3>> = x.to_vec();
    let mut triangles = kept;
    let mut seen: HashSet<usize> = HashSet::new();
    let mut starts: Vec<usize> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        let mut rim = vec![start];
        seen.insert(start);
        let mut v = next[&start];
        while v != start {
            if !seen.insert(v) || rim.len() > next.len() {
                return None;
            }
            rim.push(v);
            v = *next.get(&v)?;
        }
        if rim.len() < 3 {
            return None;
        }
        // the cap runs against the rim's direction in the kept triangles
        let centre = rim.iter().fold(Point::<3>::zeros(), |s, &v| s + x[v]) / rim.len() as f64;
        let c = positions.len();
        positions.push(centre);
        for k in 0..rim.len() {
            triangles.push([rim[(k + 1) % rim.len()], rim[k], c]);
        }
    }
    // without the vertices of removed triangles only
    let (used, triangles) = super::unions::used_vertices(&positions, &triangles);
    match Mesh::new(used, triangles) {
        Ok(m) => Some(m),
        Err(MeshError::Empty) => None,
        Err(e) => {
            tracing::debug!("a capped neck is not a closed surface: {e}");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{box_surface, icosphere};

    /// A ball that takes a band all around a 4×1×1 prism (its cross-section's
    /// corners are 0.71 from the axis) leaves two capped closed surfaces, each of
    /// about half the volume less the band; one around a point of a sphere's
    /// surface leaves one dented sphere; one that takes everything, nothing.
    #[test]
    fn a_band_around_a_neck_leaves_two_capped_surfaces() {
        let prism = box_surface([0.0; 3], [4.0, 1.0, 1.0], 8.0).unwrap();
        let two = cut_neck(&prism, Point::<3>::new(0.0, 0.0, 0.0), 0.8).unwrap();
        let volumes = two.component_measures();
        assert_eq!(volumes.len(), 2);
        for v in volumes {
            assert!((1.2..2.0).contains(&v), "a part of volume {v}");
        }
        let sphere = icosphere([0.0; 3], 1.0, 3).unwrap();
        let dent = cut_neck(&sphere, Point::<3>::new(1.0, 0.0, 0.0), 0.3).unwrap();
        assert_eq!(dent.component_labels().1, 1);
        assert!(dent.enclosed_measure() < sphere.enclosed_measure());
        assert!(cut_neck(&sphere, Point::<3>::new(0.0, 0.0, 0.0), 0.5).is_none(), "nothing within the ball");
        assert!(cut_neck(&sphere, Point::<3>::new(0.0, 0.0, 0.0), 1.5).is_none(), "everything within it");
    }
}
