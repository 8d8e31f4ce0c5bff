//! Touching objects split at the necks of the contours a flow converged to.
//!
//! The automatic initial shape splits touching objects where the thresholded,
//! smoothed image narrows ([`split_touching`]); the smoothing fills shallow
//! notches, so two objects whose neck only the flow brings out (it fits the
//! unsmoothed image) start as one. After the flow converges, each object of the
//! contours is drawn on the image's grid and split by the same rule, where the
//! cut is a notch at both of its ends ([`PINCH`]); an object that splits is traced
//! again, one closed curve per part along the boundary of its samples, and the
//! flow goes on from there. The parts then stay separate objects (the curves'
//! contact rule), as the initial shape's do. With `problem.min_separation` an
//! object is first split at the maxima of its distance transform, as the initial
//! shape's objects are ([`NeckSplit::separation`]), and at necks only where
//! those give one part.

use crate::geometry::{curves_from_loops, segment_cycles, CurveMesh, Point};
use crate::imaging::contours::{polygon_loop, zero_level};
use crate::imaging::labels::{distance_transform, label_sizes, split_at_peaks, split_touching, Dims, Necks};
use crate::imaging::{rasterize_curve_window, Grid};

mod notch;
mod surfaces;

pub use surfaces::SURFACE_NECKS;

/// The necks that split touching objects in the initial shape
/// ([`split_at_ridges`](crate::imaging::labels::split_at_ridges)) and the
/// contours after convergence: at least 1.5 samples and 18 % of the smaller
/// side's inscribed radius below it (two equal discs whose centres are at least
/// 1.15 radii apart), between sides whose inscribed radii differ by at most 2.5
/// times. Measured: the 20 splits of the
/// nuclei image, all between two annotated nuclei, have depths of 21–66 % and
/// ratios up to 1.8; the false cuts of a horse's silhouette are at depths of 6 %
/// (its head) and 16 % (its body), and at ratios of 2.8 (its tail) and 6.6–7.6
/// (its hooves).
pub const NECKS: Necks = Necks { depth: 1.5, relative_depth: 0.18, size_ratio: 2.5 };

/// How the contours (2D) or surfaces (3D) of a segmentation are split after the
/// flow converged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeckSplit {
    /// The image's samples along `x`, `y` and `z` (1 for a 2D image).
    pub dims: [usize; 3],
    /// The necks that split an object (those of the initial shape).
    pub necks: Necks,
    /// A part of fewer samples than this keeps its object whole.
    pub min_size: usize,
    /// `problem.min_separation` (samples): objects are split at the maxima of
    /// their distance to the boundary at least this far apart ([`split_at_peaks`],
    /// the initial shape's rule with it), whatever their necks; `None`: at necks.
    pub separation: Option<f64>,
}

/// A split at necks: labels `1..=count` of a mask by its distance ([`split_touching`],
/// [`split_at_ridges`](crate::imaging::labels::split_at_ridges)).
type NeckRule = fn(&[bool], &[f64], Dims, &Necks) -> (Vec<u32>, usize);

impl NeckSplit {
    /// The split on `grid`'s samples: at the maxima `separation` apart where it is
    /// given, else contours by [`NECKS`] and surfaces by [`SURFACE_NECKS`]
    /// (measured on the exact distance to the surface).
    pub fn for_grid(grid: &Grid, min_size: usize, separation: Option<f64>) -> Self {
        let necks = if grid.dimension == 3 { SURFACE_NECKS } else { NECKS };
        NeckSplit { dims: grid.dims, necks, min_size, separation }
    }

    /// The parts of `mask`, and whether they were cut at necks (which must then be
    /// notches): at the maxima of `peaks_d` [`NeckSplit::separation`] apart where
    /// that gives two or more, else by `at_necks` on `necks_d` with
    /// [`NeckSplit::necks`] (two objects whose maxima are closer can still meet at
    /// a neck).
    fn parts(
        &self,
        mask: &[bool],
        [peaks_d, necks_d]: [&[f64]; 2],
        dims: Dims,
        at_necks: NeckRule,
    ) -> (Vec<u32>, usize, bool) {
        if let Some(s) = self.separation {
            let (labels, count) = split_at_peaks(mask, peaks_d, dims, s, self.min_size);
            if count > 1 {
                return (labels, count, false);
            }
        }
        let (labels, count) = at_necks(mask, necks_d, dims, &self.necks);
        (labels, count, true)
    }

    /// `mesh` with every object that has a neck by [`NeckSplit::necks`] replaced by
    /// one traced curve per part (its holes as inner curves), or `None` where no
    /// object splits. The other objects' curves are kept as they are.
    pub fn split(&self, mesh: &CurveMesh) -> Option<CurveMesh> {
        if mesh.period().is_some() {
            return None;
        }
        let objects = mesh.objects();
        let cycles = segment_cycles(mesh.num_vertices(), mesh.elements().iter().map(|e| (e[0], e[1])));
        let component_of = |cycle: &[usize]| objects.vertex_component[cycle[0]];
        let mut loops: Vec<Vec<Point<2>>> = Vec::with_capacity(cycles.len());
        let mut any = false;
        for root in objects.roots() {
            let own: Vec<&Vec<usize>> = cycles.iter().filter(|c| objects.owner[component_of(c)] == root).collect();
            match self.split_object(mesh, &own) {
                Some(parts) => {
                    loops.extend(parts);
                    any = true;
                }
                None => loops.extend(own.iter().map(|c| c.iter().map(|&v| mesh.positions()[v]).collect())),
            }
        }
        if !any {
            return None;
        }
        // holes with no object around them are kept as they are
        for c in &cycles {
            let k = component_of(c);
            if objects.owner[k] == k && objects.measures[k] <= 0.0 {
                loops.push(c.iter().map(|&v| mesh.positions()[v]).collect());
            }
        }
        curves_from_loops(loops).ok()
    }

    /// The traced parts of the object bounded by `cycles`, or `None` if it does not
    /// split (or a part would be below `min_size`).
    fn split_object(&self, mesh: &CurveMesh, cycles: &[&Vec<usize>]) -> Option<Vec<Vec<Point<2>>>> {
        let [nx, ny, _] = self.dims;
        let l = nx.max(ny) as f64;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &v in cycles.iter().flat_map(|c| c.iter()) {
            let x = mesh.positions()[v];
            for a in 0..2 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
        // the samples around the object's box, one more on each side
        let first = |x: f64| ((x * l - 0.5).floor() - 1.0).max(0.0) as usize;
        let end = |x: f64, n: usize| (((x * l - 0.5).ceil() + 2.0).max(0.0) as usize).min(n);
        let window = [first(lo[0]).min(nx), end(hi[0], nx), first(lo[1]).min(ny), end(hi[1], ny)];
        let (w, h) = (window[1].saturating_sub(window[0]), window[3].saturating_sub(window[2]));
        if w < 3 || h < 3 {
            return None;
        }
        let segments: Vec<[usize; 2]> =
            cycles.iter().flat_map(|c| (0..c.len()).map(move |i| [c[i], c[(i + 1) % c.len()]])).collect();
        let mask = rasterize_curve_window(mesh.positions(), &segments, l, window);
        let dims = [w, h, 1];
        let dist = distance_transform(&mask, dims, [1.0; 3]);
        let (labels, count, at_necks) = self.parts(&mask, [&dist, &dist], dims, split_touching);
        if count < 2 {
            return None;
        }
        if label_sizes(&labels, count).iter().skip(1).any(|&n| n < self.min_size) {
            return None;
        }
        for a in 1..count as u32 {
            for b in a + 1..=count as u32 {
                if at_necks && !pinched(&labels, &dist, window, [nx, ny], a, b) {
                    return None;
                }
            }
        }
        let unit = |q: f64, offset: usize| (q + offset as f64 + 0.5) / l;
        let mut parts = Vec::new();
        for part in 1..=count as u32 {
            // between two parts the curve passes a quarter of a sample from the
            // part's sample (half of one between the parts' curves, no sample
            // centre in it); elsewhere half-way to the background's
            let level = |i: usize, j: usize| match labels[i + w * j] {
                l if l == part => 1.0,
                0 => -1.0,
                _ => -3.0,
            };
            let to_point = |q: [f64; 2]| Point::<2>::new(unit(q[0], window[0]), unit(q[1], window[2]));
            parts
                .extend(zero_level([0, w, 0, h], level).into_iter().filter_map(|poly| polygon_loop(poly, l, to_point)));
        }
        Some(parts)
    }
}

/// Least fraction of a disc around each end of a cut that lies inside the
/// object: a neck between two touching objects is a notch on both sides (the
/// object fills more than half of a disc around each end), where a cut below a
/// deep inlet into one object (a dark crack) ends at a straight or convex stretch
/// of its boundary (half of the disc or less). The disc is centred on the cut's
/// last sample, half a sample inside the boundary, which adds `1/(πr)` to the
/// fraction of a straight boundary; that is taken off.
const PINCH: f64 = 0.55;

/// Whether the cut between parts `a` and `b` of `labels` (the samples of
/// `window` in an image of `dims` samples, with the object's distance transform
/// `dist`) is a notch at both of its ends (see [`PINCH`]); `true` where the parts
/// do not touch. An end within that disc's radius of the image's edge counts as a
/// notch.
fn pinched(labels: &[u32], dist: &[f64], window: [usize; 4], dims: [usize; 2], a: u32, b: u32) -> bool {
    let (w, h) = (window[1] - window[0], window[3] - window[2]);
    let at = |p: usize| ((p % w) as f64, (p / w) as f64);
    let touches_b = |p: usize| {
        let (i, j) = (p % w, p / w);
        (i > 0 && labels[p - 1] == b)
            || (i + 1 < w && labels[p + 1] == b)
            || (j > 0 && labels[p - w] == b)
            || (j + 1 < h && labels[p + w] == b)
    };
    let cut: Vec<usize> = (0..w * h).filter(|&p| labels[p] == a && touches_b(p)).collect();
    let Some(&saddle) = cut.iter().max_by(|&&p, &&q| dist[p].total_cmp(&dist[q])) else {
        return true;
    };
    let farthest = |from: usize| {
        let (x, y) = at(from);
        *cut.iter()
            .max_by(|&&p, &&q| {
                let (d1, d2) = (at(p), at(q));
                ((d1.0 - x).powi(2) + (d1.1 - y).powi(2)).total_cmp(&((d2.0 - x).powi(2) + (d2.1 - y).powi(2)))
            })
            .expect("a cut has samples")
    };
    let first = farthest(saddle);
    let second = farthest(first);
    let r = dist[saddle].max(2.0);
    [first, second].iter().all(|&e| {
        let (x, y) = at(e);
        let (mut inside, mut all) = (0usize, 0usize);
        let reach = r.ceil() as i64;
        for dj in -reach..=reach {
            for di in -reach..=reach {
                if ((di * di + dj * dj) as f64) > r * r {
                    continue;
                }
                let (i, j) = (x as i64 + di, y as i64 + dj);
                let (gi, gj) = (i + window[0] as i64, j + window[2] as i64);
                if gi < 0 || gj < 0 || gi >= dims[0] as i64 || gj >= dims[1] as i64 {
                    // a cut that ends at the image's edge: the object goes on
                    // beyond it, and the edge is that side of the neck
                    return true;
                }
                all += 1;
                // beyond the window (a sample around the object's box) is background
                if i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h && labels[i as usize + w * j as usize] != 0
                {
                    inside += 1;
                }
            }
        }
        inside as f64 / all as f64 - 1.0 / (std::f64::consts::PI * r) >= PINCH
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::polygon;

    /// A closed curve `r(θ)` around `(cx, cy)` (pixels) on a 100² image, in the
    /// unit box.
    fn polar(cx: f64, cy: f64, r: impl Fn(f64) -> f64) -> CurveMesh {
        let pts: Vec<Point<2>> = (0..400)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 400.0;
                Point::<2>::new((cx + r(t) * t.cos()) / 100.0, (cy + r(t) * t.sin()) / 100.0)
            })
            .collect();
        polygon(&pts, None).unwrap()
    }

    #[test]
    fn a_peanut_splits_in_two_and_an_ellipse_does_not() {
        let split = NeckSplit { dims: [100, 100, 1], necks: NECKS, min_size: 16, separation: None };
        // lobes of inscribed radius about 12 px joined by a waist of half-width 5
        let peanut = polar(50.0, 50.0, |t| 30.0 * (0.58 + 0.42 * (2.0 * t).cos()).max(0.17));
        let parts = split.split(&peanut).expect("the peanut splits");
        let objects = parts.objects();
        assert_eq!(objects.roots().count(), 2);
        // the parts keep the peanut's area, less half a sample along the cut
        let area: f64 = objects.measures.iter().sum::<f64>() * 1e4;
        let whole = peanut.objects().measures[0] * 1e4;
        assert!((whole - area).abs() < 0.05 * whole, "{area} of {whole}");
        let ellipse = polar(50.0, 50.0, |t| 30.0 / (t.cos().powi(2) + 4.0 * t.sin().powi(2)).sqrt());
        assert!(split.split(&ellipse).is_none());
    }

    /// Left and right halves of a 40 × 20 block cut by a slit from its top edge
    /// down to a quarter of its height: the cut below the slit ends at the straight
    /// bottom edge, no neck; two blocks joined by a narrow bridge are pinched.
    #[test]
    fn a_cut_below_a_slit_is_not_a_neck() {
        let (w, h) = (44, 24);
        let block = |i: usize, j: usize| (2..42).contains(&i) && (2..22).contains(&j);
        let labels: Vec<u32> = (0..w * h)
            .map(|p| {
                let (i, j) = (p % w, p / w);
                match (block(i, j), i) {
                    (false, _) => 0,
                    (true, 21 | 22) if j >= 7 => 0,
                    (true, i) if i <= 21 => 1,
                    _ => 2,
                }
            })
            .collect();
        let mask: Vec<bool> = labels.iter().map(|&l| l != 0).collect();
        let dist = distance_transform(&mask, [w, h, 1], [1.0; 3]);
        let window = [20, 20 + w, 30, 30 + h];
        assert!(!pinched(&labels, &dist, window, [100, 100], 1, 2));
        // blocks 18 samples wide joined by a bridge 5 samples across and 4 long
        let bridge: Vec<u32> = (0..w * h)
            .map(|p| {
                let (i, j) = (p % w, p / w);
                match (block(i, j), i) {
                    (false, _) => 0,
                    (true, 20..=23) if !(10..15).contains(&j) => 0,
                    (true, i) if i <= 21 => 1,
                    _ => 2,
                }
            })
            .collect();
        let mask: Vec<bool> = bridge.iter().map(|&l| l != 0).collect();
        let dist = distance_transform(&mask, [w, h, 1], [1.0; 3]);
        assert!(pinched(&bridge, &dist, window, [100, 100], 1, 2));
    }
}
