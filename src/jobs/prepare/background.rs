//! The background of a segmentation's image: the polarity of its objects, and the
//! quadratic illumination removed before thresholding and fitting.

use crate::imaging::{otsu, percentile, quadratic_background, Grid};
use crate::jobs::spec::Polarity;

/// The quadratic illumination of `smoothed` less its mean over the background (the
/// offset to subtract), fitted to the samples below Otsu's threshold, then twice
/// more to those of them within 2.5 robust standard deviations of the fit (with the
/// threshold of the corrected image); `None` where the fit is not possible.
pub(super) fn flatten(smoothed: &Grid, threshold: f64, polarity: Polarity) -> Option<Vec<f64>> {
    let sign = if polarity == Polarity::Bright { 1.0 } else { -1.0 };
    let mut t = threshold;
    let mut offset: Option<Vec<f64>> = None;
    let mut background: Vec<bool> = Vec::new();
    for _ in 0..3 {
        let current = |p: usize| smoothed.values[p] - offset.as_ref().map_or(0.0, |o| o[p]);
        let below = |p: usize| sign * (current(p) - t) <= 0.0;
        background = if offset.is_none() {
            (0..smoothed.len()).map(below).collect()
        } else {
            // robust refit: the samples of the last background that deviate from the
            // fit by more than 2.5 robust standard deviations towards the objects
            // (the blurred rims of objects, dim objects) are left out
            let used: Vec<f64> = (0..smoothed.len()).filter(|&p| background[p]).map(current).collect();
            let level = used.iter().sum::<f64>() / used.len().max(1) as f64;
            let deviations: Vec<f64> = used.iter().map(|v| (v - level).abs()).collect();
            let spread = 1.4826 * percentile(&deviations, 50.0);
            (0..smoothed.len()).map(|p| below(p) && sign * (current(p) - level) <= 2.5 * spread).collect()
        };
        let Some(b) = quadratic_background(smoothed, &background) else { break };
        let (sum, n) =
            b.iter().zip(&background).filter(|(_, &m)| m).fold((0.0, 0.0), |(s, n), (v, _)| (s + v, n + 1.0));
        let mean = sum / n;
        offset = Some(b.iter().map(|b| b - mean).collect());
        let corrected: Vec<f64> =
            (0..smoothed.len()).map(|p| smoothed.values[p] - offset.as_ref().unwrap()[p]).collect();
        match otsu(&corrected) {
            Some(next) => t = next,
            None => break,
        }
    }
    offset
}

/// `grid` minus `offset` (sample by sample).
pub(super) fn minus(grid: &Grid, offset: &[f64]) -> Grid {
    Grid { values: grid.values.iter().zip(offset).map(|(v, o)| v - o).collect(), ..grid.clone() }
}

/// `Bright` unless most of the image's border lies above the threshold.
pub(super) fn border_polarity(g: &Grid, t: f64) -> Polarity {
    let [nx, ny, nz] = g.dims;
    let (mut above, mut total) = (0usize, 0usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let border = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny || (nz > 1 && (k == 0 || k + 1 == nz));
                if border {
                    total += 1;
                    above += (g.values[g.index(i, j, k)] > t) as usize;
                }
            }
        }
    }
    if 2 * above > total {
        Polarity::Dark
    } else {
        Polarity::Bright
    }
}
