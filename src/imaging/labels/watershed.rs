//! Touching objects split at necks: a persistence watershed of the distance
//! transform, and one sample of background put between labelled objects.

use super::{find, neighbours, Dims};

/// Split the objects of `mask` where they touch: a watershed of the distance
/// transform `d` (descending flood from its maxima) whose basins are merged across
/// a saddle unless both their peaks rise above it by at least
/// `max(depth, relative_depth · lower peak)` (a persistence criterion: two discs
/// joined by a neck stay two objects when the neck is clearly narrower than both).
/// Returns labels `1..=count` (0 outside `mask`) and `count`.
pub fn split_touching(mask: &[bool], d: &[f64], dims: Dims, depth: f64, relative_depth: f64) -> (Vec<u32>, usize) {
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
            if low - d[p] < depth.max(relative_depth * low) {
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

    #[test]
    fn two_touching_discs_are_split_and_one_disc_is_not() {
        let (w, h) = (80, 40);
        let dims = [w, h, 1];
        let m = disc_mask(w, h, &[(25.0, 20.0, 12.0), (46.0, 20.0, 11.0)]);
        let d = distance_transform(&m, dims, [1.0; 3]);
        let (mut labels, n) = split_touching(&m, &d, dims, 2.0, 0.25);
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
        assert_eq!(split_touching(&e, &d, dims, 2.0, 0.25).1, 1);
    }
}
