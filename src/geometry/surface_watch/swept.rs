//! The continuous test of a step without a certificate: every pair of triangles
//! whose boxes swept over the step overlap, by conservative advancement.

use super::super::distance::sweep_apart;
use super::super::surface_intersections::{bounds, box_pairs, mean_edge, triangles_meet, Aabb};
use super::super::Point;
use super::{corners, shares};

/// Up to `most` pairs `(a, b)`, `a < b`, of `triangles` that share no vertex and
/// meet at `new`, or may meet somewhere on the linear way from `old` (the same
/// connectivity) to `new`, sorted: a pair that meets at `old` is one. None is
/// missed; a pair may be reported that only comes within a rounding distance
/// ([`sweep_apart`]).
pub fn swept_surface_intersections(
    old: &[Point<3>],
    new: &[Point<3>],
    triangles: &[[usize; 3]],
    most: usize,
) -> Vec<(usize, usize)> {
    if triangles.len() < 2 || most == 0 || old.len() != new.len() {
        return Vec::new();
    }
    let scale = old.iter().chain(new).flat_map(|p| p.iter().map(|c| c.abs())).fold(0.0, f64::max);
    swept_meetings(old, new, triangles, most, 64.0 * f64::EPSILON * scale)
}

/// Whether triangles `a`, `b` (sharing no vertex) meet at `new` or may meet on the
/// linear way from `old`.
pub(super) fn pair_meets(old: &[Point<3>], new: &[Point<3>], a: &[usize; 3], b: &[usize; 3], slack: f64) -> bool {
    triangles_meet(new, a, b)
        || !sweep_apart(&corners(old, a), &corners(new, a), &corners(old, b), &corners(new, b), slack)
}

/// [`SurfaceWatch::meetings`] without a certificate: every pair whose boxes swept
/// over the step overlap.
pub(super) fn swept_meetings(
    old: &[Point<3>],
    new: &[Point<3>],
    triangles: &[[usize; 3]],
    most: usize,
    slack: f64,
) -> Vec<(usize, usize)> {
    let boxes: Vec<Aabb> = triangles
        .iter()
        .map(|t| {
            let (b0, b1) = (bounds(old, t), bounds(new, t));
            (std::array::from_fn(|k| b0.0[k].min(b1.0[k])), std::array::from_fn(|k| b0.1[k].max(b1.1[k])))
        })
        .collect();
    let mut hits = Vec::new();
    box_pairs(&boxes, 2.0 * mean_edge(new, triangles), |a, b| {
        let (ta, tb) = (&triangles[a], &triangles[b]);
        if !shares(ta, tb) && pair_meets(old, new, ta, tb, slack) {
            hits.push((a.min(b), a.max(b)));
        }
        hits.len() >= most
    });
    hits.sort_unstable();
    hits
}
