//! Image statistics behind the automatic settings of segmentation: percentile
//! normalization, a noise estimate, the smoothing it calls for, and Otsu's
//! threshold. Pure functions over [`Grid`]s.

use super::grid::Grid;

/// Intensity normalization by percentiles: `v ↦ clamp((v − lo)/(hi − lo), 0, 1)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Normalization {
    /// The intensity mapped to 0 (the `low` percentile of the image).
    pub lo: f64,
    /// The intensity mapped to 1 (the `high` percentile).
    pub hi: f64,
}

/// Default percentiles of [`Normalization`]: 0.5 and 99.5. A few saturated or dead
/// pixels then set neither end of the scale, while a handful of bright objects
/// among many dim ones still keep their contrast below 1.
pub const PERCENTILES: (f64, f64) = (0.5, 99.5);

/// The `p`-th percentile (`0 ≤ p ≤ 100`) of `values` by the nearest rank of the
/// sorted copy.
pub fn percentile(values: &[f64], p: f64) -> f64 {
    percentiles(values, &[p])[0]
}

/// Several percentiles of `values` (nearest rank), each by a linear-time selection
/// (the same values a sort would give).
pub fn percentiles(values: &[f64], ps: &[f64]) -> Vec<f64> {
    if values.is_empty() {
        return vec![0.0; ps.len()];
    }
    let mut v = values.to_vec();
    let n = v.len();
    ps.iter()
        .map(|p| {
            let r = (p.clamp(0.0, 100.0) / 100.0 * (n - 1) as f64).round() as usize;
            *v.select_nth_unstable_by(r.min(n - 1), f64::total_cmp).1
        })
        .collect()
}

impl Normalization {
    /// The normalization of `grid` by the percentiles `(low, high)`, widened to
    /// the full range when the two coincide (an image of two levels with most
    /// pixels at one). `None` for a constant image.
    pub fn of(grid: &Grid, (low, high): (f64, f64)) -> Option<Normalization> {
        let p = percentiles(&grid.values, &[low, high, 0.0, 100.0]);
        let (mut lo, mut hi) = (p[0], p[1]);
        if !(hi > lo) {
            (lo, hi) = (p[2], p[3]);
        }
        (hi > lo).then_some(Normalization { lo, hi })
    }

    /// `grid` mapped onto `[0, 1]`.
    pub fn apply(&self, grid: &Grid) -> Grid {
        let s = 1.0 / (self.hi - self.lo);
        Grid { values: grid.values.iter().map(|v| ((v - self.lo) * s).clamp(0.0, 1.0)).collect(), ..grid.clone() }
    }
}

/// The standard deviation of white Gaussian noise in `grid` (Immerkær 1996, "Fast
/// noise variance estimation"): `σ = √(π/2) / (6 (W−2)(H−2)) Σ |I ∗ N|` with the
/// mask `N = [1 −2 1; −2 4 −2; 1 −2 1]`, which annihilates planes and most of an
/// image's structure. Volumes: the mean over their slices. 0 for images below 3×3.
pub fn noise_level(grid: &Grid) -> f64 {
    let [nx, ny, nz] = grid.dims;
    if nx < 3 || ny < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..nz {
        let at = |i: usize, j: usize| grid.values[grid.index(i, j, k)];
        for j in 1..ny - 1 {
            for i in 1..nx - 1 {
                let corners = at(i - 1, j - 1) + at(i + 1, j - 1) + at(i - 1, j + 1) + at(i + 1, j + 1);
                let edges = at(i, j - 1) + at(i - 1, j) + at(i + 1, j) + at(i, j + 1);
                sum += (corners - 2.0 * edges + 4.0 * at(i, j)).abs();
            }
        }
    }
    let count = ((nx - 2) * (ny - 2) * nz) as f64;
    (std::f64::consts::FRAC_PI_2).sqrt() * sum / (6.0 * count)
}

/// Default Gaussian smoothing (pixels) for noise of standard deviation `noise` on
/// a `[0, 1]` scale: enough that the smoothed noise is at most 2 % of the scale
/// (a Gaussian of `σ` pixels divides white noise by `2σ√π` in 2D and by about
/// `(2σ√π)^{3/2}` in 3D), at least 1 pixel, at most 4.
pub fn smoothing_for_noise(noise: f64, dimension: usize) -> f64 {
    let ratio = (noise / 0.02).max(1.0);
    let sigma = if dimension == 2 { ratio } else { ratio.powf(2.0 / 3.0) } / (2.0 * std::f64::consts::PI.sqrt());
    sigma.clamp(1.0, 4.0)
}

/// Standard deviation of white noise of standard deviation `noise` after a
/// Gaussian of `sigma` samples in `dimension` dimensions: divided by `2σ√π` per
/// pair of axes (2D: `2σ√π`; 3D: `(2σ√π)^{3/2}`); unchanged for `σ = 0`.
pub fn smoothed_noise(noise: f64, sigma: f64, dimension: usize) -> f64 {
    if sigma <= 0.0 {
        return noise;
    }
    noise / (2.0 * sigma * std::f64::consts::PI.sqrt()).powf(dimension as f64 / 2.0)
}

/// The most frequent value of `values` in `[0, 1]` (centre of the fullest of 256
/// bins): the background level of an image mostly made of background.
pub fn histogram_mode(values: &[f64]) -> f64 {
    const BINS: usize = 256;
    let mut hist = [0usize; BINS];
    for &v in values {
        hist[((v.clamp(0.0, 1.0) * BINS as f64) as usize).min(BINS - 1)] += 1;
    }
    let best = (0..BINS).max_by_key(|&b| (hist[b], std::cmp::Reverse(b))).unwrap_or(0);
    (best as f64 + 0.5) / BINS as f64
}

/// The spread of the background around its level `mode`, measured on the side
/// away from the objects (`sign` +1 for bright objects: the samples at or below
/// `mode`; −1: at or above): `1.4826 · median |v − mode|` over those samples, the
/// standard deviation for Gaussian fluctuations. On a smoothed image it is the
/// background's variation at the smoothing scale, texture and uneven background
/// included, which a white-noise estimate ([`noise_level`]) does not see; the
/// objects do not enter it. 0 with no such sample.
pub fn background_spread(values: &[f64], mode: f64, sign: f64) -> f64 {
    let mut far: Vec<f64> = values.iter().map(|v| sign * (mode - v)).filter(|d| *d >= 0.0).collect();
    if far.is_empty() {
        return 0.0;
    }
    let mid = far.len() / 2;
    1.4826 * *far.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Otsu's threshold of values in `[0, 1]` (256 bins): the level that maximizes the
/// between-class variance. `None` if all values fall in one bin.
pub fn otsu(values: &[f64]) -> Option<f64> {
    const BINS: usize = 256;
    let mut hist = [0usize; BINS];
    for &v in values {
        hist[((v.clamp(0.0, 1.0) * BINS as f64) as usize).min(BINS - 1)] += 1;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist.iter().enumerate().map(|(b, &c)| b as f64 * c as f64).sum();
    let (mut w0, mut sum0) = (0.0, 0.0);
    let mut best: Option<(f64, usize)> = None;
    for (b, &c) in hist.iter().enumerate().take(BINS - 1) {
        w0 += c as f64;
        sum0 += b as f64 * c as f64;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if best.is_none_or(|(v, _)| between > v) {
            best = Some((between, b));
        }
    }
    best.map(|(_, b)| (b + 1) as f64 / BINS as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::SampleKind;

    /// A seeded uniform generator, enough for noise in tests.
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                // a sum of 12 uniforms − 6: approximately standard normal
                (0..12)
                    .map(|_| {
                        s ^= s << 13;
                        s ^= s >> 7;
                        s ^= s << 17;
                        (s >> 11) as f64 / (1u64 << 53) as f64
                    })
                    .sum::<f64>()
                    - 6.0
            })
            .collect()
    }

    #[test]
    fn noise_level_of_white_noise_on_a_ramp() {
        let (w, h) = (200, 150);
        let z = noise(w * h, 7);
        let values: Vec<f64> = (0..w * h).map(|p| 0.001 * (p % w) as f64 + 0.3 + 0.05 * z[p]).collect();
        let g = Grid::new(2, [w, h, 1], values, SampleKind::F32);
        let s = noise_level(&g);
        assert!((s - 0.05).abs() < 0.003, "{s}");
    }

    #[test]
    fn otsu_splits_two_levels() {
        let values: Vec<f64> = (0..1000).map(|i| if i % 3 == 0 { 0.8 } else { 0.2 }).collect();
        let t = otsu(&values).unwrap();
        assert!(t > 0.2 && t <= 0.8, "{t}");
        assert!(otsu(&[0.5; 10]).is_none());
    }

    #[test]
    fn mode_and_smoothed_noise() {
        let values: Vec<f64> = (0..1000).map(|i| if i % 4 == 0 { 0.9 } else { 0.2 }).collect();
        assert!((histogram_mode(&values) - 0.2).abs() < 1.0 / 256.0);
        let s = smoothed_noise(0.1, 2.0, 2);
        assert!((s - 0.1 / (4.0 * std::f64::consts::PI.sqrt())).abs() < 1e-15);
        assert_eq!(smoothed_noise(0.1, 0.0, 3), 0.1);
    }

    #[test]
    fn background_spread_of_gaussian_noise_ignores_the_objects() {
        // background 0.3 with noise 0.05, and a quarter of the samples bright objects
        let z = noise(40_000, 3);
        let values: Vec<f64> =
            z.iter().enumerate().map(|(i, n)| if i % 4 == 0 { 0.8 + 0.05 * n } else { 0.3 + 0.05 * n }).collect();
        let s = background_spread(&values, 0.3, 1.0);
        assert!((s - 0.05).abs() < 0.003, "{s}");
        // dark objects: the side above the background
        let flipped: Vec<f64> = values.iter().map(|v| 1.0 - v).collect();
        assert!((background_spread(&flipped, 0.7, -1.0) - s).abs() < 1e-12);
        assert_eq!(background_spread(&[0.5, 0.6], 0.4, 1.0), 0.0);
    }

    #[test]
    fn percentiles_ignore_outliers() {
        let mut values: Vec<f64> = (0..1000).map(|i| (i % 100) as f64).collect();
        values[0] = 1e6;
        let g = Grid::new(2, [100, 10, 1], values, SampleKind::F32);
        let n = Normalization::of(&g, PERCENTILES).unwrap();
        assert_eq!((n.lo, n.hi), (0.0, 99.0));
        assert_eq!(n.apply(&g).values[0], 1.0);
    }
}
