//! Intersections of a flow's surfaces (`D = 3`; curves' crossings are the mesh
//! management's): which pairs of triangles meet, which are new in a trial step,
//! and when a step cut short by them is a contact.
//!
//! A trial step is searched at its end by the flow's [`PatchSearch`] (the
//! exhaustive search's pairs, most neighbours proved apart a patch at a time; its
//! patches cut again when the connectivity changed). A step on which some vertex
//! moves by more than [`SWEEP_EDGES`] mean edges is also checked along its way
//! ([`swept_surface_intersections`]): a part thinner than its motion could pass
//! wholly through a sheet within it and leave no intersection at the end.

use crate::geometry::{swept_surface_intersections, Mesh, PatchSearch, Point};

/// A step that intersections cut below this fraction of the spec's `τ` is a
/// contact: the surfaces touch, and shorter steps would only creep closer.
pub(super) const CONTACT: f64 = 1.0 / 1024.0;

/// A trial step on which a vertex moves by more than this many mean edges is
/// checked along its way, not only at its end.
pub(super) const SWEEP_EDGES: f64 = 0.25;

/// A pair of triangles of `new` (`D = 3`, the connectivity of `old`) that share
/// no vertex and meet at `new`, or may meet on the way from `old` (a step longer
/// than [`SWEEP_EDGES`]), of two components (or one) that did not meet in `old`:
/// components already in contact (a segmentation's objects split at a neck start
/// so) are the problem's to keep apart.
pub(super) fn new_intersection<const D: usize>(
    old: &Mesh<D>,
    new: &Mesh<D>,
    search: &mut PatchSearch,
) -> Option<(usize, usize)> {
    if D != 3 {
        return None;
    }
    let (x0, x1, t) = (points(old), points(new), triangles(new));
    let swept = sweeps(&x0, &x1, &t);
    // the common case, no intersection, at the cost of one search
    if search.intersections(&x1, &t, 1).is_empty()
        && (!swept || swept_surface_intersections(&x0, &x1, &t, 1).is_empty())
    {
        return None;
    }
    let (labels, _) = old.component_labels();
    let elements = old.elements();
    let pair = |(a, b): (usize, usize)| {
        let (ca, cb) = (labels[elements[a][0]], labels[elements[b][0]]);
        (ca.min(cb), ca.max(cb))
    };
    let mut before: Vec<(usize, usize)> = search.intersections_of_state(&x0, &t).into_iter().map(pair).collect();
    before.sort_unstable();
    let mut after = search.intersections(&x1, &t, usize::MAX);
    if swept {
        after.extend(swept_surface_intersections(&x0, &x1, &t, usize::MAX));
    }
    after.sort_unstable();
    after.into_iter().find(|&p| before.binary_search(&pair(p)).is_err())
}

/// Whether the step from `x0` to `x1` moves some vertex by more than
/// [`SWEEP_EDGES`] mean edges.
fn sweeps(x0: &[Point<3>], x1: &[Point<3>], t: &[[usize; 3]]) -> bool {
    let edges: f64 = t.iter().map(|e| (0..3).map(|k| (x1[e[(k + 1) % 3]] - x1[e[k]]).norm()).sum::<f64>()).sum();
    let mean = edges / (3 * t.len()).max(1) as f64;
    x0.iter().zip(x1).any(|(a, b)| (a - b).norm() > SWEEP_EDGES * mean)
}

/// Where `new` (`D = 3`, the connectivity of `old`) first meets itself anew: the
/// mean of the centroids of a pair of its triangles that meet ([`new_intersection`]),
/// or of all its vertices if none do.
pub(super) fn contact_point<const D: usize>(old: &Mesh<D>, new: &Mesh<D>, search: &mut PatchSearch) -> [f64; 3] {
    let x = new.positions();
    let corners: Vec<usize> = match new_intersection(old, new, search) {
        Some((a, b)) => new.elements()[a].iter().chain(&new.elements()[b]).copied().collect(),
        None => (0..x.len()).collect(),
    };
    let n = corners.len().max(1) as f64;
    std::array::from_fn(|k| if k < D { corners.iter().map(|&v| x[v][k]).sum::<f64>() / n } else { 0.0 })
}

/// A surface mesh's positions (`D = 3` only).
fn points<const D: usize>(mesh: &Mesh<D>) -> Vec<Point<3>> {
    mesh.positions().iter().map(|p| Point::<3>::new(p[0], p[1], p[2])).collect()
}

/// A surface mesh's triangles (`D = 3` only).
fn triangles<const D: usize>(mesh: &Mesh<D>) -> Vec<[usize; 3]> {
    mesh.elements().iter().map(|e| [e[0], e[1], e[2]]).collect()
}

/// Two triangles of a surface mesh (`D = 3`) that share no vertex and meet; none
/// for curves (their crossings are the mesh management's: topological changes).
/// A new connectivity (a remeshed or merged state) is cut into patches by
/// `search` here, and the cut serves the trial steps from it: one cut and one
/// search where the exhaustive search and a cut at the next step cost twice that
/// (BENCHMARKS.md).
pub(super) fn surface_intersection<const D: usize>(mesh: &Mesh<D>, search: &mut PatchSearch) -> Option<(usize, usize)> {
    if D != 3 {
        return None;
    }
    search.intersections(&points(mesh), &triangles(mesh), 1).pop()
}
