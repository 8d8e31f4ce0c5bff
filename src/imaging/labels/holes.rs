//! Which filled holes of a thresholded mask the region model would keep open.
//!
//! The initial shape fills holes that are small against their object (a dark
//! figure on a coin, a nucleolus), since the flow does not open new holes. A hole
//! whose samples fit the background better than their object is a hole of the
//! object (a ring, a cell with a vacuole of background): the Chan–Vese energy
//! `μ|Γ| + λ_in Σ_k ∫_{Ω_k}(I − c_k)² + λ_out ∫_{D∖Ω}(I − c_out)²` is lower with
//! it open by
//! `λ_in Σ_H (I − c_k)² − λ_out Σ_H (I − c_out)² − μ |∂H|`,
//! and it is reopened when that is positive.

use super::{components, neighbours, Dims};

/// The weights of the Chan–Vese energy the holes are judged by (`mu` per unit of
/// length or area in samples).
#[derive(Debug, Clone, Copy)]
pub struct RegionWeights {
    pub mu: f64,
    pub lambda_in: f64,
    pub lambda_out: f64,
}

/// `filled` with the holes reopened that the energy keeps open: the holes are the
/// components of `filled ∖ bare` (`bare`: the same mask with only the holes too
/// small to judge filled), judged on `values` with `c_k` the mean of `values` over
/// the object's samples in `bare` and `c_out` the mean outside `filled`. The
/// length (area) of a hole's boundary is its count of faces between samples
/// times the mean ratio of a smooth boundary's length to its staircase's (π/4 in
/// 2D, 2/3 in 3D).
pub fn reopen_holes(filled: &[bool], bare: &[bool], dims: Dims, values: &[f64], w: RegionWeights) -> Vec<bool> {
    let candidates: Vec<bool> = filled.iter().zip(bare).map(|(&f, &b)| f && !b).collect();
    let (holes, n) = components(&candidates, dims);
    if n == 0 {
        return filled.to_vec();
    }
    let (objects, no) = components(filled, dims);
    // per object: Σ I and the count over its samples in `bare`; outside: the same
    let mut object_sums = vec![(0.0, 0usize); no + 1];
    for ((&o, &b), &v) in objects.iter().zip(bare).zip(values) {
        if o == 0 || b {
            object_sums[o as usize].0 += v;
            object_sums[o as usize].1 += 1;
        }
    }
    let mean = |(s, c): (f64, usize)| if c > 0 { s / c as f64 } else { 0.0 };
    let c_out = mean(object_sums[0]);
    // per hole: its object, Σ I, Σ I², the count and the boundary faces
    let mut sums = vec![(0u32, 0.0, 0.0, 0usize, 0usize); n + 1];
    let mut nb = Vec::with_capacity(6);
    for (p, &h) in holes.iter().enumerate() {
        if h == 0 {
            continue;
        }
        let s = &mut sums[h as usize];
        s.0 = objects[p];
        s.1 += values[p];
        s.2 += values[p] * values[p];
        s.3 += 1;
        neighbours(dims, p, &mut nb);
        s.4 += nb.iter().filter(|&&q| holes[q] != h).count();
    }
    let ratio = if dims[2] > 1 { 2.0 / 3.0 } else { std::f64::consts::FRAC_PI_4 };
    let open: Vec<bool> = sums
        .iter()
        .map(|&(o, s1, s2, count, faces)| {
            let fit = |c: f64| s2 - 2.0 * c * s1 + count as f64 * c * c;
            let c_k = mean(object_sums[o as usize]);
            count > 0 && w.lambda_in * fit(c_k) - w.lambda_out * fit(c_out) > w.mu * ratio * faces as f64
        })
        .collect();
    filled.iter().zip(&holes).map(|(&f, &h)| f && !open[h as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::super::{clean_mask, disc_mask};
    use super::*;

    const W: RegionWeights = RegionWeights { mu: 0.1, lambda_in: 1.0, lambda_out: 1.0 };

    /// A ring whose hole (a tenth of the disc) is background reopens; the same
    /// hole at the object's level stays filled; a hole at a level between,
    /// nearer the object's, stays filled.
    #[test]
    fn a_hole_of_background_reopens_and_a_dark_detail_stays_filled() {
        let (w, h) = (60, 60);
        let outer = disc_mask(w, h, &[(30.0, 30.0, 20.0)]);
        let inner = disc_mask(w, h, &[(30.0, 30.0, 6.0)]);
        let ring: Vec<bool> = outer.iter().zip(&inner).map(|(&o, &i)| o && !i).collect();
        let dims = [w, h, 1];
        let filled = clean_mask(&ring, dims, 16, 0.25);
        let bare = clean_mask(&ring, dims, 16, 0.0);
        assert_eq!(filled, outer, "the fraction rule fills the hole");
        assert_eq!(bare, ring);
        let image = |hole: f64| -> Vec<f64> {
            (0..w * h)
                .map(|p| {
                    if inner[p] {
                        hole
                    } else if outer[p] {
                        0.8
                    } else {
                        0.1
                    }
                })
                .collect()
        };
        assert_eq!(reopen_holes(&filled, &bare, dims, &image(0.1), W), ring);
        assert_eq!(reopen_holes(&filled, &bare, dims, &image(0.8), W), outer);
        assert_eq!(reopen_holes(&filled, &bare, dims, &image(0.5), W), outer);
        // a heavy length weight keeps even a hole of background filled
        let heavy = RegionWeights { mu: 100.0, ..W };
        assert_eq!(reopen_holes(&filled, &bare, dims, &image(0.1), heavy), outer);
    }
}
