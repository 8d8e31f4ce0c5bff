//! Touching objects split at necks: a persistence watershed of the distance
//! transform, and one sample of background put between labelled objects.

use super::{find, neighbours, Dims};

/// When two basins of the distance transform stay apart ([`split_touching`]): both
/// peaks rise above their saddle by at least `max(depth, relative_depth · lower
/// peak)`, and the higher peak is at most `size_ratio` times the lower one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Necks {
    /// Least depth of the neck below the lower peak (samples).
    pub depth: f64,
    /// Least depth as a fraction of the lower peak.
    pub relative_depth: f64,
    /// Largest ratio of the peaks (the inscribed radii of the two sides).
    pub size_ratio: f64,
}

impl Necks {
    /// Whether basins with peaks `high ≥ low` meeting at `saddle` stay apart.
    fn apart(&self, high: f64, low: f64, saddle: f64) -> bool {
        low - saddle >= self.depth.max(self.relative_depth * low) && high <= self.size_ratio * low
    }
}

/// Split the objects of `mask` where they touch: a watershed of the distance
/// transform `d` (descending flood from its maxima) whose basins are merged across
/// a saddle unless [`Necks::apart`] keeps them apart (a persistence criterion: two
/// discs of comparable size joined by a neck stay two objects when the neck is
/// clearly narrower than both; a narrow part of one object much smaller than the
/// rest, a leg or a tail, is no object of its own).
/// Returns labels `1..=count` (0 outside `mask`) and `count`.
pub fn split_touching(mask: &[bool], d: &[f64], dims: Dims, necks: &Necks) -> (Vec<u32>, usize) {
    let mut order: Vec<usize> = (0..mask.len()).filter(|&p| mask[p]).collect();
    order.sort_unstable_by(|&a, &b| d[b].total_cmp(&d[a]).then(a.cmp(&b)));
    const NONE: u32 = u32::MAX;
    let mut basin = vec![NONE; mask.len()];
    let mut parent: Vec<u32> = Vec::new();
    let mut peak: Vec<f64> = Vec::new();
    let mut nb = Vec::with_capacity(6);
    let mut roots: Vec<u32> = Vec::with_capacity(6);
    for &p in &order {
        neighbours(dims, p, &mut nb);
        roots.clear();
        for &q in &nb {
            if basin[q] != NONE {
                let r = find(&mut parent, basin[q]);
                if !roots.contains(&r) {
                    roots.push(r);
                }
            }
        }
        if roots.is_empty() {
            parent.push(parent.len() as u32);
            peak.push(d[p]);
            basin[p] = (parent.len() - 1) as u32;
            continue;
        }
        // highest peak first; merge every basin that does not stand out of this saddle
        roots.sort_unstable_by(|&a, &b| peak[b as usize].total_cmp(&peak[a as usize]));
        let main = roots[0];
        for &r in &roots[1..] {
            let low = peak[r as usize];
            if !necks.apart(peak[main as usize], low, d[p]) {
                parent[r as usize] = main;
            }
        }
        basin[p] = main;
    }
    // compact labels
    let mut id = vec![0u32; parent.len()];
    let mut count = 0u32;
    let mut labels = vec![0u32; mask.len()];
    for &p in &order {
        let r = find(&mut parent, basin[p]) as usize;
        if id[r] == 0 {
            count += 1;
            id[r] = count;
        }
        labels[p] = id[r];
    }
    (labels, count as usize)
}

/// [`split_touching`] with its parts flooded again from their cores
/// ([`flood_from_cores`]): the cut along the ridge of each neck.
pub fn split_at_ridges(mask: &[bool], d: &[f64], dims: Dims, necks: &Necks) -> (Vec<u32>, usize) {
    let (labels, count) = split_touching(mask, d, dims, necks);
    let labels = if count > 1 { flood_from_cores(mask, d, dims, &labels, count) } else { labels };
    (labels, count)
}

/// The parts of [`split_touching`] flooded again from their cores: each part
/// keeps its samples whose distance is above the highest saddle at which it meets
/// another part, and the rest of `mask` is flooded from there in order of
/// decreasing distance, every sample taking the part of the neighbour it is
/// reached from (a marker-controlled watershed). The union-find flood assigns a
/// sample between two parts to the one of the higher peak, which lets the larger
/// side creep around the outer layers of a smaller one; this puts the cut along
/// the ridge of the neck.
pub fn flood_from_cores(mask: &[bool], d: &[f64], dims: Dims, labels: &[u32], count: usize) -> Vec<u32> {
    let mut nb = Vec::with_capacity(6);
    // the highest saddle of every part: the largest distance of its samples next to another part
    let mut saddle = vec![f64::NEG_INFINITY; count + 1];
    for p in 0..labels.len() {
        let l = labels[p];
        if l == 0 {
            continue;
        }
        neighbours(dims, p, &mut nb);
        if nb.iter().any(|&q| labels[q] != 0 && labels[q] != l) {
            saddle[l as usize] = saddle[l as usize].max(d[p]);
        }
    }
    let cores: Vec<u32> = (0..labels.len())
        .map(|p| if labels[p] != 0 && d[p] > saddle[labels[p] as usize] { labels[p] } else { 0 })
        .collect();
    flood_from_markers(mask, d, dims, cores)
}

/// The samples of `mask` flooded from the labelled samples of `out` (the
/// markers) in order of decreasing distance `d`, every sample taking the label of
/// the neighbour it is reached from (a marker-controlled watershed of `-d`). A
/// component of `mask` with no marker stays 0.
pub(super) fn flood_from_markers(mask: &[bool], d: &[f64], dims: Dims, mut out: Vec<u32>) -> Vec<u32> {
    let mut nb = Vec::with_capacity(6);
    // a max-heap of (distance, sample) on the flood's front
    let mut front = std::collections::BinaryHeap::new();
    let key = |p: usize| (ordered(d[p]), std::cmp::Reverse(p));
    for p in 0..out.len() {
        if out[p] != 0 {
            neighbours(dims, p, &mut nb);
            if nb.iter().any(|&q| mask[q] && out[q] == 0) {
                front.push((key(p), p));
            }
        }
    }
    while let Some((_, p)) = front.pop() {
        neighbours(dims, p, &mut nb);
        for &q in &nb {
            if mask[q] && out[q] == 0 {
                out[q] = out[p];
                front.push((key(q), q));
            }
        }
    }
    out
}

/// A total order of distances (no NaN among them) for the heap.
fn ordered(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | 1 << 63
    }
}

/// Background samples between touching objects: every sample adjacent to a sample
/// of a smaller label loses its label, so that the objects of `labels` are
/// separated by at least one sample. Returns the samples cleared.
pub fn separate(labels: &mut [u32], dims: Dims) -> Vec<usize> {
    let mut cleared = Vec::new();
    let mut nb = Vec::with_capacity(6);
    for p in 0..labels.len() {
        let l = labels[p];
        if l == 0 {
            continue;
        }
        neighbours(dims, p, &mut nb);
        if nb.iter().any(|&q| labels[q] != 0 && labels[q] < l) {
            cleared.push(p);
        }
    }
    for &p in &cleared {
        labels[p] = 0;
    }
    cleared
}

#[cfg(test)]
mod tests {
    use super::super::{components, disc_mask, distance_transform};
    use super::*;

    const NECKS: Necks = Necks { depth: 2.0, relative_depth: 0.25, size_ratio: 2.5 };

    #[test]
    fn two_touching_discs_are_split_and_one_disc_is_not() {
        let (w, h) = (80, 40);
        let dims = [w, h, 1];
        let m = disc_mask(w, h, &[(25.0, 20.0, 12.0), (46.0, 20.0, 11.0)]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        let (mut labels, n) = split_touching(&m, &d, dims, &NECKS);
        assert_eq!(n, 2);
        assert_eq!(components(&m, dims).1, 1);
        let cleared = separate(&mut labels, dims);
        assert!(!cleared.is_empty());
        let sep: Vec<bool> = labels.iter().map(|&l| l != 0).collect();
        assert_eq!(components(&sep, dims).1, 2);
        // an ellipse of aspect 2 stays one object
        let e: Vec<bool> = (0..w * h)
            .map(|p| {
                let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                ((x - 40.0) / 24.0).powi(2) + ((y - 20.0) / 12.0).powi(2) < 1.0
            })
            .collect();
        let d = distance_transform(&e, dims, [1.0; 3]);
        assert_eq!(split_touching(&e, &d, dims, &NECKS).1, 1);
    }

    /// Discs of radii 12 and 7 overlapping by 2: the cut runs along the neck,
    /// all but a few samples labelled with the disc whose boundary is farther.
    #[test]
    fn the_cut_between_unequal_discs_runs_along_their_neck() {
        let (w, h) = (80, 40);
        let dims = [w, h, 1];
        let (a, b) = ((25.0, 20.0, 12.0), (42.0, 20.0, 7.0));
        let m = disc_mask(w, h, &[a, b]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        let (labels, n) = split_touching(&m, &d, dims, &Necks { depth: 1.0, relative_depth: 0.1, size_ratio: 2.5 });
        assert_eq!(n, 2);
        let depth = |c: (f64, f64, f64), p: usize| {
            let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
            c.2 - (x - c.0).hypot(y - c.1)
        };
        let small = labels[42 + w * 20];
        let (mut wrong, mut all) = (0, 0);
        for p in (0..w * h).filter(|&p| m[p]) {
            all += 1;
            wrong += usize::from((labels[p] == small) != (depth(b, p) > depth(a, p)));
        }
        assert!(wrong * 50 < all, "{wrong} of {all} samples on the wrong side");
        // flooded again from the parts' cores, fewer still
        let again = flood_from_cores(&m, &d, dims, &labels, n);
        let small = again[42 + w * 20];
        let wrong_after = (0..w * h).filter(|&p| m[p] && (again[p] == small) != (depth(b, p) > depth(a, p))).count();
        assert!(wrong_after <= wrong, "{wrong_after} {wrong}");
    }

    /// A small side is a part of the larger one (a leg), whatever its neck; two
    /// sides joined by a wide neck are one object.
    #[test]
    fn a_small_side_and_a_wide_neck_stay_one_object() {
        let (w, h) = (80, 40);
        let dims = [w, h, 1];
        // inscribed radii 16 and about 5.5 with a neck of half-width about 2
        let m = disc_mask(w, h, &[(28.0, 20.0, 16.0), (50.0, 20.0, 6.0)]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        assert_eq!(components(&m, dims).1, 1);
        let loose = Necks { depth: 1.0, relative_depth: 0.0, size_ratio: 100.0 };
        assert_eq!(split_touching(&m, &d, dims, &loose).1, 2);
        assert_eq!(split_touching(&m, &d, dims, &Necks { size_ratio: 2.5, ..loose }).1, 1);
        // equal discs whose centres are 1.1 radii apart: a neck of about 0.85 radii
        let m = disc_mask(w, h, &[(31.5, 20.0, 12.0), (44.5, 20.0, 12.0)]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        assert_eq!(split_touching(&m, &d, dims, &loose).1, 2);
        assert_eq!(split_touching(&m, &d, dims, &Necks { relative_depth: 0.18, ..loose }).1, 1);
    }
}
