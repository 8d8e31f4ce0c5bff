//! Intersections of a flow's surfaces (`D = 3`; curves' crossings are the mesh
//! management's): which pairs of triangles meet, which are new in a trial step,
//! and when a step cut short by them is a contact.

use crate::geometry::{surface_intersections, Mesh, Point};

/// A step that intersections cut below this fraction of the spec's `τ` is a
/// contact: the surfaces touch, and shorter steps would only creep closer.
pub(super) const CONTACT: f64 = 1.0 / 1024.0;

/// A pair of triangles of `new` (`D = 3`, the connectivity of `old`) that share
/// no vertex and meet, of two components (or one) that did not meet in `old`:
/// components already in contact (a segmentation's objects split at a neck start
/// so) are the problem's to keep apart.
pub(super) fn new_intersection<const D: usize>(old: &Mesh<D>, new: &Mesh<D>) -> Option<(usize, usize)> {
    // the common case, no intersection, at the cost of one search
    surface_intersection(new)?;
    let (labels, _) = old.component_labels();
    let elements = old.elements();
    let pair = |(a, b): (usize, usize)| {
        let (ca, cb) = (labels[elements[a][0]], labels[elements[b][0]]);
        (ca.min(cb), ca.max(cb))
    };
    let mut before: Vec<(usize, usize)> = meeting_pairs(old, usize::MAX).into_iter().map(pair).collect();
    before.sort_unstable();
    meeting_pairs(new, usize::MAX).into_iter().find(|&p| before.binary_search(&pair(p)).is_err())
}

/// Where `new` (`D = 3`, the connectivity of `old`) first meets itself anew: the
/// mean of the centroids of a pair of its triangles that meet ([`new_intersection`]),
/// or of all its vertices if none do.
pub(super) fn contact_point<const D: usize>(old: &Mesh<D>, new: &Mesh<D>) -> [f64; 3] {
    let x = new.positions();
    let corners: Vec<usize> = match new_intersection(old, new) {
        Some((a, b)) => new.elements()[a].iter().chain(&new.elements()[b]).copied().collect(),
        None => (0..x.len()).collect(),
    };
    let n = corners.len().max(1) as f64;
    std::array::from_fn(|k| if k < D { corners.iter().map(|&v| x[v][k]).sum::<f64>() / n } else { 0.0 })
}

/// Up to `most` pairs of triangles of a surface mesh (`D = 3`) that share no
/// vertex and meet, sorted; none for curves (their crossings are the mesh
/// management's: topological changes).
fn meeting_pairs<const D: usize>(mesh: &Mesh<D>, most: usize) -> Vec<(usize, usize)> {
    if D != 3 {
        return Vec::new();
    }
    let x: Vec<Point<3>> = mesh.positions().iter().map(|p| Point::<3>::new(p[0], p[1], p[2])).collect();
    let t: Vec<[usize; 3]> = mesh.elements().iter().map(|e| [e[0], e[1], e[2]]).collect();
    let mut pairs = surface_intersections(&x, &t, most);
    pairs.sort_unstable();
    pairs
}

/// Two triangles of a surface mesh (`D = 3`) that share no vertex and meet.
pub(super) fn surface_intersection<const D: usize>(mesh: &Mesh<D>) -> Option<(usize, usize)> {
    meeting_pairs(mesh, 1).pop()
}
