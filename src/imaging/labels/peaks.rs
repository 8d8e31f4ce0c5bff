//! Touching objects split at the maxima of the distance transform: one object
//! per maximum that stands at least a given distance from every higher one of
//! its component, whatever the depth of the neck between them (the marker
//! watershed of scikit-image's `peak_local_max(min_distance=…)` followed by
//! `watershed`, or MorphoLibJ's distance-transform watershed).

use super::watershed::flood_from_markers;
use super::{components, label_sizes, Dims};
use std::collections::HashMap;

/// Split the objects of `mask` at the maxima of its distance transform `d`: a
/// sample is a marker if no sample within `separation` (samples, along each axis)
/// is farther from the background, and no higher (or equal, earlier) marker of
/// its component lies within `separation` of it; the mask is then flooded from
/// the markers in order of decreasing distance ([`flood_from_markers`]). Parts of
/// fewer than `min_size` samples give their samples to their neighbours (a
/// component keeps at least one part). Returns labels `1..=count` (0 outside
/// `mask`) and `count`.
pub fn split_at_peaks(mask: &[bool], d: &[f64], dims: Dims, separation: f64, min_size: usize) -> (Vec<u32>, usize) {
    let (component, _) = components(mask, dims);
    let reach = separation.floor().max(0.0) as usize;
    let highest = max_filter(d, dims, reach);
    let mut candidates: Vec<usize> = (0..mask.len()).filter(|&p| mask[p] && d[p] > 0.0 && d[p] >= highest[p]).collect();
    candidates.sort_unstable_by(|&a, &b| d[b].total_cmp(&d[a]).then(a.cmp(&b)));
    let at = |p: usize| [p % dims[0], (p / dims[0]) % dims[1], p / (dims[0] * dims[1])].map(|c| c as f64);
    let cell = separation.max(1.0);
    let cell_of = |x: [f64; 3]| x.map(|c| (c / cell).floor() as i64);
    let mut accepted: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut markers: Vec<usize> = Vec::new();
    for &p in &candidates {
        let x = at(p);
        let c = cell_of(x);
        let near =
            (-1..=1).flat_map(|i| (-1..=1).flat_map(move |j| (-1..=1).map(move |k| [c[0] + i, c[1] + j, c[2] + k])));
        let crowded = near.filter_map(|key| accepted.get(&key)).flatten().any(|&q| {
            let y = at(q);
            component[q] == component[p] && (0..3).map(|a| (x[a] - y[a]).powi(2)).sum::<f64>() < separation * separation
        });
        if !crowded {
            accepted.entry(c).or_default().push(p);
            markers.push(p);
        }
    }
    // parts below the least size hand their samples to their neighbours, all of a
    // component's at once but its largest; the others only grow, so that this
    // ends in a few rounds
    let mut keep = vec![true; markers.len()];
    loop {
        let (labels, count) = flood(mask, d, dims, &markers, &keep);
        let sizes = label_sizes(&labels, count);
        let mut largest: HashMap<u32, (usize, usize)> = HashMap::new();
        for (i, &m) in markers.iter().enumerate().filter(|&(i, _)| keep[i]) {
            let size = sizes[labels[m] as usize];
            let best = largest.entry(component[m]).or_insert((i, size));
            if size > best.1 {
                *best = (i, size);
            }
        }
        let mut dropped = false;
        for (i, &m) in markers.iter().enumerate() {
            if keep[i] && sizes[labels[m] as usize] < min_size && largest[&component[m]].0 != i {
                keep[i] = false;
                dropped = true;
            }
        }
        if !dropped {
            return (labels, count);
        }
    }
}

/// The flood of `mask` from the kept `markers`, labelled `1..=count` in their order.
fn flood(mask: &[bool], d: &[f64], dims: Dims, markers: &[usize], keep: &[bool]) -> (Vec<u32>, usize) {
    let mut out = vec![0u32; mask.len()];
    let mut count = 0;
    for (&m, _) in markers.iter().zip(keep).filter(|(_, &k)| k) {
        count += 1;
        out[m] = count;
    }
    (flood_from_markers(mask, d, dims, out), count as usize)
}

/// The largest value of `d` within `reach` samples along each axis (a cube), by
/// one pass per axis, each a sliding maximum over a queue of decreasing values
/// (linear in the samples whatever `reach`).
fn max_filter(d: &[f64], dims: Dims, reach: usize) -> Vec<f64> {
    let mut out = d.to_vec();
    let (mut line, mut queue) = (Vec::new(), std::collections::VecDeque::new());
    for (axis, stride) in [(0, 1), (1, dims[0]), (2, dims[0] * dims[1])] {
        let n = dims[axis];
        if n < 2 || reach == 0 {
            continue;
        }
        for start in (0..d.len()).filter(|&p| (p / stride) % n == 0) {
            line.clear();
            line.extend((0..n).map(|i| out[start + i * stride]));
            queue.clear();
            // the window of sample i is [i - reach, i + reach]; j enters it at i = j - reach
            for j in 0..n + reach {
                if j < n {
                    while queue.back().is_some_and(|&b: &usize| line[b] <= line[j]) {
                        queue.pop_back();
                    }
                    queue.push_back(j);
                }
                let Some(i) = j.checked_sub(reach) else { continue };
                while queue.front().is_some_and(|&f| f + reach < i) {
                    queue.pop_front();
                }
                out[start + i * stride] = line[*queue.front().expect("the window holds sample i")];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::{distance_transform, split_touching, Necks};
    use super::*;

    /// The tests' grid: 32³ samples.
    const N: usize = 32;
    const DIMS: Dims = [N, N, N];

    /// The samples of the grid whose centres are `inside`, and their distance
    /// transform.
    fn solid(inside: impl Fn([f64; 3]) -> bool) -> (Vec<bool>, Vec<f64>) {
        let m: Vec<bool> =
            (0..N * N * N).map(|p| inside([p % N, (p / N) % N, p / (N * N)].map(|c| c as f64 + 0.5))).collect();
        let d = distance_transform(&m, DIMS, [1.0; 3]);
        (m, d)
    }

    /// The union of balls `(x, y, z, r)` on the grid, and its distance transform.
    fn balls(balls: &[(f64, f64, f64, f64)]) -> (Vec<bool>, Vec<f64>) {
        solid(|x| balls.iter().any(|b| (x[0] - b.0).powi(2) + (x[1] - b.1).powi(2) + (x[2] - b.2).powi(2) < b.3 * b.3))
    }

    /// Two balls of radius 7 whose centres are 7 apart: a neck only 13 % below
    /// their inscribed radius, which the initial shape's neck rule keeps whole; two
    /// parts at a separation of 6, cut at the plane between them; a ball alone and
    /// a prolate ellipsoid stay one.
    #[test]
    fn overlapping_balls_split_at_their_maxima_and_one_ball_does_not() {
        let (n, dims) = (N, DIMS);
        let (m, d) = balls(&[(12.5, 16.0, 16.0, 7.0), (19.5, 16.0, 16.0, 7.0)]);
        let (labels, count) = split_at_peaks(&m, &d, dims, 6.0, 64);
        // the initial shape's rule (`jobs::necks::NECKS`) keeps them whole
        let necks = Necks { depth: 1.5, relative_depth: 0.18, size_ratio: 2.5 };
        assert_eq!(split_touching(&m, &d, dims, &necks).1, 1);
        assert_eq!(count, 2);
        let sample = |x: usize, y: usize, z: usize| labels[x + n * (y + n * z)];
        assert_ne!(sample(11, 16, 16), sample(20, 16, 16));
        // every sample off the middle plane is on the side of its centre
        let wrong = (0..n * n * n)
            .filter(|&p| m[p] && (p % n) as f64 + 0.5 != 16.0)
            .filter(|&p| (labels[p] == sample(11, 16, 16)) != ((p % n) as f64 + 0.5 < 16.0))
            .count();
        assert!(wrong * 100 < m.iter().filter(|&&v| v).count(), "{wrong}");
        // farther apart than the separation asks: one object
        assert_eq!(split_at_peaks(&m, &d, dims, 8.0, 64).1, 1);
        let (one, d) = balls(&[(16.0, 16.0, 16.0, 9.0)]);
        assert_eq!(split_at_peaks(&one, &d, dims, 6.0, 64).1, 1);
        let (ellipsoid, d) = solid(|x| {
            ((x[0] - 16.0) / 13.0).powi(2) + ((x[1] - 16.0) / 6.0).powi(2) + ((x[2] - 16.0) / 6.0).powi(2) < 1.0
        });
        // of aspect 2.2: one object at a separation of its smaller radius, two
        // below it (maxima of the voxels' distance along its axis)
        assert_eq!(split_at_peaks(&ellipsoid, &d, dims, 6.0, 64).1, 1);
        assert_eq!(split_at_peaks(&ellipsoid, &d, dims, 4.0, 64).1, 2);
    }

    /// The sliding maximum is the cube's maximum, near the edges too.
    #[test]
    fn the_max_filter_is_the_maximum_over_the_cube() {
        let dims = [7, 5, 4];
        let d: Vec<f64> = (0..140).map(|p| ((p * 37 + 11) % 23) as f64).collect();
        for reach in [1, 2, 9] {
            let got = max_filter(&d, dims, reach);
            for p in 0..d.len() {
                let c = [p % 7, (p / 7) % 5, p / 35];
                let want = (0..d.len())
                    .filter(|&q| {
                        let e = [q % 7, (q / 7) % 5, q / 35];
                        (0..3).all(|a| c[a].abs_diff(e[a]) <= reach)
                    })
                    .map(|q| d[q])
                    .fold(f64::NEG_INFINITY, f64::max);
                assert_eq!(got[p], want, "sample {p}, reach {reach}");
            }
        }
    }

    /// Balls closer than the separation but not touching are each an object:
    /// markers suppress each other only within their own component; a part below
    /// the least size goes to its neighbour.
    #[test]
    fn every_component_keeps_an_object_and_small_parts_go() {
        let (m, d) = balls(&[(9.0, 16.0, 16.0, 5.0), (20.0, 16.0, 16.0, 5.0)]);
        assert_eq!(components(&m, DIMS).1, 2);
        assert_eq!(split_at_peaks(&m, &d, DIMS, 20.0, 8).1, 2);
        // a small bump on a ball: its own maximum, a part below the least size
        let (bump, d) = balls(&[(14.0, 16.0, 16.0, 8.0), (23.0, 16.0, 16.0, 2.5)]);
        let (labels, count) = split_at_peaks(&bump, &d, DIMS, 3.0, 200);
        assert_eq!(count, 1);
        assert!(labels.iter().zip(&bump).all(|(&l, &b)| (l == 1) == b));
    }
}
