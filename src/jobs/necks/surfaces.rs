//! Necks of surfaces: the 3D counterpart of the curves' split.
//!
//! Each object of the converged surfaces (a component with its cavities) is
//! sampled on the image's grid as its signed distance; its inside samples are
//! split by [`SURFACE_NECKS`] ([`split_at_ridges`]), on the exact distance
//! to the surface ([`distance_inside`]: a voxel distance transform measures in
//! steps of the grid, which can put a neck just under the rule), where the cut is a
//! notch all around its rim ([`notched`]). An object that splits is traced again,
//! one closed surface per part, by marching tetrahedra of the signed distance
//! within the part's samples: the surface keeps its sub-voxel place away from
//! the cut, and the parts' surfaces pass a tenth of a sample from their own
//! samples across it (0.8 samples apart). The traced parts are tidied by the
//! caller (the mesh management's adaptation) and the flow goes on; the parts
//! then stay apart by the contact rule of surfaces.

use super::notch::notched;
use super::NeckSplit;
use crate::geometry::{first_surface_intersection, surface_union, Point, SurfaceMesh};
use crate::imaging::isosurface::zero_level_3d;
use crate::imaging::labels::{distance_transform, label_sizes, split_at_ridges, Necks};
use crate::imaging::signed_distance::{distance_inside, signed_distance_and_closest, SampleGrid};

/// The necks that split an object of converged surfaces ([`split_at_ridges`] on
/// the exact distance to the surface): at least 0.55 samples and 13 % of the
/// smaller side's inscribed radius below it, between sides whose inscribed radii
/// differ by at most 2.5 times. The initial shape's rule (1.5 samples, 18 %) is
/// set against the voxel noise of a thresholded image; a converged surface is
/// smooth, and the curvature term fills a neck's crease, so that a pair of
/// touching balls of unequal size keeps only a shallow neck. Measured on the
/// generated touching pairs (`scripts/touching_volumes.py`, seeds 1–12): the
/// saddles inside single balls are 0.30–0.39 samples (7–10 %) deep, the necks of
/// pairs the initial shape left whole 0.72, 1.05 and 1.23 samples (16–30 %).
/// Held out: seeds 13–20 and the volumes of single ellipsoids and beans (no
/// object split).
pub const SURFACE_NECKS: Necks = Necks { depth: 0.55, relative_depth: 0.13, size_ratio: 2.5 };

/// A neck cut by [`NeckSplit::split_surfaces`]: where (unit-box coordinates, the
/// widest sample of the cut) and into how many parts its object went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceCut {
    pub at: [f64; 3],
    pub parts: usize,
}

impl NeckSplit {
    /// `mesh` with every object that splits (by [`NeckSplit::necks`], or at
    /// the maxima [`NeckSplit::separation`] apart) replaced by its traced parts,
    /// each passed through `tidy`, and the cuts made; `None` if no object splits.
    /// An object whose parts would meet another surface (tidied, and as traced)
    /// stays whole; the other objects keep their triangles.
    pub fn split_surfaces(
        &self,
        mesh: &SurfaceMesh,
        tidy: impl Fn(SurfaceMesh) -> SurfaceMesh,
    ) -> Option<(SurfaceMesh, Vec<SurfaceCut>)> {
        let objects = mesh.objects();
        let root_of = |c: usize| objects.owner[c];
        let mut keep = vec![true; objects.owner.len()];
        let mut parts: Vec<SurfaceMesh> = Vec::new();
        let mut cuts = Vec::new();
        let mut result = None;
        for root in objects.roots() {
            let triangles: Vec<[usize; 3]> =
                mesh.elements().iter().filter(|t| root_of(objects.vertex_component[t[0]]) == root).copied().collect();
            let Some((traced, cut)) = self.split_surface_object(mesh, &triangles) else { continue };
            let without: Vec<bool> = keep.iter().enumerate().map(|(c, &k)| k && root_of(c) != root).collect();
            let kept = mesh.with_components(&without);
            // the surfaces with this object's parts instead of it, if they meet nothing
            let union = |own: &[SurfaceMesh]| {
                let all: Vec<SurfaceMesh> = kept.iter().chain(&parts).chain(own).cloned().collect();
                let union = surface_union(&all).inspect_err(|e| tracing::debug!("neck split: {e}")).ok()?;
                first_surface_intersection(union.positions(), union.elements()).is_none().then_some(union)
            };
            // tidied; where the tidying brought a part into contact with another
            // surface, as traced (the flow's mesh management tidies them then)
            let tidied: Vec<SurfaceMesh> = traced.iter().cloned().map(&tidy).collect();
            let accepted = union(&tidied).map(|u| (u, tidied)).or_else(|| union(&traced).map(|u| (u, traced)));
            let Some((union, own)) = accepted else {
                tracing::debug!(at = ?cut.at, "the parts of a split would meet another surface: not split");
                continue;
            };
            keep = without;
            parts.extend(own);
            cuts.push(cut);
            result = Some(union);
        }
        Some((result?, cuts))
    }

    /// The traced parts (each with its cavities) of the object bounded by
    /// `triangles`, and its cut, or `None` if it does not split.
    fn split_surface_object(
        &self,
        mesh: &SurfaceMesh,
        triangles: &[[usize; 3]],
    ) -> Option<(Vec<SurfaceMesh>, SurfaceCut)> {
        let l = self.dims.iter().copied().max()? as f64;
        let x: Vec<[f64; 3]> = mesh.positions().iter().map(|p| [p[0], p[1], p[2]]).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &v in triangles.iter().flatten() {
            for a in 0..3 {
                lo[a] = lo[a].min(x[v][a]);
                hi[a] = hi[a].max(x[v][a]);
            }
        }
        // the samples around the object's box, one more on each side
        let first = |q: f64, n: usize| (((q * l - 0.5).floor() - 1.0).max(0.0) as usize).min(n);
        let end = |q: f64, n: usize| (((q * l - 0.5).ceil() + 2.0).max(0.0) as usize).min(n);
        let start = [0, 1, 2].map(|a| first(lo[a], self.dims[a]));
        let dims = [0, 1, 2].map(|a| end(hi[a], self.dims[a]).saturating_sub(start[a]));
        if dims.iter().any(|&n| n < 3) {
            return None;
        }
        let grid = SampleGrid { origin: [0, 1, 2].map(|a| (start[a] as f64 + 0.5) / l), spacing: 1.0 / l, dims };
        let (sd, closest) = signed_distance_and_closest(&grid, &x, triangles, 2.0 / l);
        // the split's depths on the distance to the surface itself (sub-sample),
        // the notch test's balls on the voxel distance transform it was measured with
        let exact: Vec<f64> = distance_inside(&grid, &sd, &closest).iter().map(|d| d * l).collect();
        let sd: Vec<f64> = sd.iter().map(|d| d * l).collect();
        let mask: Vec<bool> = sd.iter().map(|&d| d > 0.0).collect();
        let dist = distance_transform(&mask, dims, [1.0; 3]);
        // the maxima on the voxel distance, as the initial shape's
        let (labels, count, at_necks) = self.parts(&mask, [&dist, &exact], dims, split_at_ridges);
        tracing::debug!(count, sizes = ?label_sizes(&labels, count), "neck split of a surface's object");
        if count < 2 || label_sizes(&labels, count).iter().skip(1).any(|&n| n < self.min_size) {
            return None;
        }
        let mut widest: Option<(f64, usize)> = None;
        for a in 1..count as u32 {
            for b in a + 1..=count as u32 {
                let (notch, at) = notched(&labels, &dist, dims, start, self.dims, a, b);
                if !notch && at_necks {
                    tracing::debug!(a, b, "a cut that is not a notch all around: no split");
                    return None;
                }
                if let Some(p) = at.filter(|&p| widest.is_none_or(|(d, _)| dist[p] > d)) {
                    widest = Some((dist[p], p));
                }
            }
        }
        let mut traced = Vec::with_capacity(count);
        for part in 1..=count as u32 {
            // inside the part its distance (at least a twentieth of a sample), in the
            // background its distance (at most a sample), in another part nine
            // samples: a tenth of a sample from the part's samples there
            let level = |i: usize, j: usize, k: usize| {
                let p = grid.index(i, j, k);
                match labels[p] {
                    q if q == part => sd[p].clamp(0.05, 1.0),
                    0 => sd[p].clamp(-1.0, -0.05),
                    _ => -9.0,
                }
            };
            let (v, t) = zero_level_3d([0, dims[0], 0, dims[1], 0, dims[2]], level);
            let positions =
                v.iter().map(|q| Point::<3>::from_fn(|a, _| grid.origin[a] + q[a] * grid.spacing)).collect();
            match SurfaceMesh::new(positions, t) {
                Ok(m) => traced.push(m),
                Err(e) => {
                    tracing::debug!("a traced part of a neck split is invalid: {e}");
                    return None;
                }
            }
        }
        let at = widest.map_or([0.0; 3], |(_, p)| {
            let (i, j, k) = (p % dims[0], (p / dims[0]) % dims[1], p / (dims[0] * dims[1]));
            grid.point(i, j, k)
        });
        Some((traced, SurfaceCut { at, parts: count }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::icosphere;

    const L: f64 = 64.0;

    fn split_by(necks: Necks) -> NeckSplit {
        NeckSplit { dims: [64, 64, 64], necks, min_size: 64, separation: None }
    }

    /// The zero level of `value` (sample units of the 64³ image) traced on a grid
    /// of a quarter of a sample over `[lo, lo + 0.25 · dims)`.
    fn traced(lo: [f64; 3], dims: [usize; 3], value: impl Fn([f64; 3]) -> f64) -> SurfaceMesh {
        let spacing = 0.25 / L;
        let grid = SampleGrid { origin: lo.map(|c| c / L), spacing, dims };
        let (v, t) =
            zero_level_3d([0, dims[0], 0, dims[1], 0, dims[2]], |i, j, k| value(grid.point(i, j, k).map(|c| c * L)));
        let positions = v.iter().map(|q| Point::<3>::from_fn(|a, _| grid.origin[a] + q[a] * spacing)).collect();
        SurfaceMesh::new(positions, t).unwrap()
    }

    /// `r` minus the distance of `p` from `c`.
    fn ball(p: [f64; 3], c: [f64; 3], r: f64) -> f64 {
        r - ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt()
    }

    /// Two balls of radius 8 samples, 14 apart, joined as one surface (the
    /// boundary of their union) on a 64³ grid: the neck split makes two closed
    /// surfaces that do not meet, each near a ball of its own; one ball alone does
    /// not split. Both rules split the pair.
    #[test]
    fn two_overlapping_balls_split_in_two_and_one_ball_does_not() {
        let one = icosphere([0.5, 0.5, 0.5], 8.0 / L, 4).unwrap();
        assert!(split_by(SURFACE_NECKS).split_surfaces(&one, |m| m).is_none());
        let union = traced([10.0, 20.0, 20.0], [177, 97, 97], |p| {
            ball(p, [25.0, 32.0, 32.0], 8.0).max(ball(p, [39.0, 32.0, 32.0], 8.0))
        });
        assert_eq!(union.component_labels().1, 1);
        assert!(split_by(super::super::NECKS).split_surfaces(&union, |m| m).is_some());
        let (parts, cuts) = split_by(SURFACE_NECKS).split_surfaces(&union, |m| m).expect("the union splits");
        assert_eq!(cuts.len(), 1);
        assert_eq!(cuts[0].parts, 2);
        assert!((cuts[0].at[0] * L - 32.0).abs() < 1.5, "{:?}", cuts[0]);
        assert_eq!(parts.component_labels().1, 2);
        let ball_volume = 4.0 / 3.0 * std::f64::consts::PI * (8.0 / L).powi(3);
        for v in parts.component_measures() {
            assert!((v / ball_volume - 0.93).abs() < 0.08, "{} of a ball", v / ball_volume);
        }
    }

    /// A ball of radius 7.6 and one of 4.5, 9.2 apart: their union's neck is a
    /// circle of radius 3.7, 0.8 samples below the small ball's inscribed radius.
    /// The initial shape's rule keeps it whole; the surfaces' rule splits it,
    /// the cut at the neck's plane.
    #[test]
    fn a_shallow_neck_between_unequal_balls_splits_a_surface() {
        let (a, b) = ([26.0, 32.0, 32.0], [35.2, 32.0, 32.0]);
        let union = traced([16.0, 22.0, 22.0], [113, 81, 81], |p| ball(p, a, 7.6).max(ball(p, b, 4.5)));
        assert_eq!(union.component_labels().1, 1);
        assert!(split_by(super::super::NECKS).split_surfaces(&union, |m| m).is_none());
        let (parts, cuts) = split_by(SURFACE_NECKS).split_surfaces(&union, |m| m).expect("the union splits");
        assert_eq!((cuts.len(), cuts[0].parts), (1, 2));
        // the neck's plane: 6.64 from a
        assert!((cuts[0].at[0] * L - 32.64).abs() < 1.5, "{:?}", cuts[0]);
        let mut volumes = parts.component_measures();
        volumes.sort_by(f64::total_cmp);
        let small = 4.0 / 3.0 * std::f64::consts::PI * (4.5 / L).powi(3);
        assert!(volumes[0] > 0.5 * small && volumes[0] < 1.1 * small, "{} of the small ball", volumes[0] / small);
    }

    /// Two balls of radius 8 samples, 7 apart: their union's neck is 0.8 samples
    /// (10 %) below their radius, which the surfaces' neck rule keeps whole. With
    /// `separation` 6 it splits at the maxima of its distance, one part at each
    /// ball, each about half of the union; a prolate ellipsoid (semi-axes 12, 6
    /// and 6 samples) stays whole at its smaller radius (its voxels' distance has
    /// maxima along its axis below that, as for the initial shape). Where the
    /// maxima are closer than `separation` (two balls 14 apart, separation 16) the
    /// neck rule still splits.
    #[test]
    fn balls_without_a_neck_split_at_their_maxima_and_an_ellipsoid_does_not() {
        let peaks = |s: f64| NeckSplit { separation: Some(s), ..split_by(SURFACE_NECKS) };
        let blob = traced([16.0, 20.0, 20.0], [145, 97, 97], |p| {
            ball(p, [28.5, 32.0, 32.0], 8.0).max(ball(p, [35.5, 32.0, 32.0], 8.0))
        });
        assert_eq!(blob.component_labels().1, 1);
        assert!(split_by(SURFACE_NECKS).split_surfaces(&blob, |m| m).is_none());
        let (parts, cuts) = peaks(6.0).split_surfaces(&blob, |m| m).expect("the blob splits at its maxima");
        assert_eq!((cuts.len(), cuts[0].parts), (1, 2));
        assert!((cuts[0].at[0] * L - 32.0).abs() < 1.5, "{:?}", cuts[0]);
        assert_eq!(parts.component_labels().1, 2);
        let whole = blob.component_measures()[0];
        for v in parts.component_measures() {
            assert!((v / whole - 0.47).abs() < 0.06, "{} of the blob", v / whole);
        }
        let c = [32.0, 32.0, 32.0];
        let ellipsoid = traced([18.0, 24.0, 24.0], [113, 65, 65], |p| {
            let axes = [12.0, 6.0, 6.0];
            (1.0 - (0..3).map(|i| ((p[i] - c[i]) / axes[i]).powi(2)).sum::<f64>().sqrt()) * 6.0
        });
        // as the initial shape's rule: an elongated object stays one from a
        // separation of its smaller radius on, and is cut below it
        assert!(peaks(6.0).split_surfaces(&ellipsoid, |m| m).is_none());
        assert!(peaks(4.0).split_surfaces(&ellipsoid, |m| m).is_some());
        let pair = traced([10.0, 20.0, 20.0], [177, 97, 97], |p| {
            ball(p, [25.0, 32.0, 32.0], 8.0).max(ball(p, [39.0, 32.0, 32.0], 8.0))
        });
        let (_, cuts) = peaks(16.0).split_surfaces(&pair, |m| m).expect("the pair splits at its neck");
        assert_eq!(cuts[0].parts, 2);
    }

    /// Two such blobs, one with a small ball inside it across its cut: that
    /// blob's parts would meet the ball, so it stays whole, and the other blob
    /// still splits.
    #[test]
    fn a_split_whose_parts_would_meet_another_surface_leaves_only_that_object_whole() {
        let blob = |y: f64| {
            traced([16.0, y - 12.0, 20.0], [145, 97, 97], |p| {
                ball(p, [28.5, y, 32.0], 8.0).max(ball(p, [35.5, y, 32.0], 8.0))
            })
        };
        let inner = icosphere([32.0 / L, 20.0 / L, 32.0 / L], 2.0 / L, 2).unwrap();
        let all = surface_union(&[blob(20.0), inner, blob(44.0)]).unwrap();
        assert!(first_surface_intersection(all.positions(), all.elements()).is_none());
        let split = NeckSplit { separation: Some(6.0), ..split_by(SURFACE_NECKS) };
        let (parts, cuts) = split.split_surfaces(&all, |m| m).expect("one blob splits");
        assert_eq!(cuts.len(), 1);
        assert!((cuts[0].at[1] * L - 44.0).abs() < 2.0, "{:?}", cuts[0]);
        assert_eq!(parts.component_labels().1, 4);
    }

    /// Single objects with saddles of their own do not split by the surfaces'
    /// rule: a blob of two balls of radius 5 samples, 3.68 apart (its saddle 0.35
    /// samples deep, as those measured inside the single balls of the touching
    /// pairs), and a bean (an ellipsoid with a ball cut 2.5 samples deep out of
    /// one side).
    #[test]
    fn a_blob_with_a_shallow_saddle_and_a_bean_stay_whole() {
        let blob = traced([20.0, 22.0, 22.0], [97, 81, 81], |p| {
            ball(p, [30.16, 32.0, 32.0], 5.0).max(ball(p, [33.84, 32.0, 32.0], 5.0))
        });
        assert_eq!(blob.component_labels().1, 1);
        assert!(split_by(SURFACE_NECKS).split_surfaces(&blob, |m| m).is_none());
        let c = [32.0, 32.0, 32.0];
        let axes = [11.0, 7.0, 6.0];
        let ellipsoid =
            |p: [f64; 3]| (1.0 - (0..3).map(|i| ((p[i] - c[i]) / axes[i]).powi(2)).sum::<f64>().sqrt()) * 6.0;
        let bean = traced([18.0, 22.0, 24.0], [113, 81, 65], |p| {
            ellipsoid(p).min(-ball(p, [32.0, 32.0 + 7.0 + 6.0 - 2.5, 32.0], 6.0))
        });
        assert_eq!(bean.component_labels().1, 1);
        assert!(split_by(SURFACE_NECKS).split_surfaces(&bean, |m| m).is_none());
    }
}
