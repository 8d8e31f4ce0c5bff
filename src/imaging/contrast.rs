//! The contrast scale `k` of the edge indicator `H = 1/(1 + |∇I_σ|²/k²)`: what the
//! strong edges give, and the gradient of the noise it must stay above.

/// The contrast scale `k` of the edge indicator that the strong edges give, from
/// the squared gradient magnitudes `g2` (of the image on [0, 100]): a twentieth of
/// their gradient, `max(p99, max/4)/20` of `|∇I_σ|` — the strong edges get
/// `H ≈ 1/400` whatever the image's contrast, and the 99th percentile rather than
/// the maximum lets a few very bright objects not set the scale (the `max/4`
/// floor serves images whose edges are under 1 % of the samples). The automatic
/// `k` of [`EdgeField::with_contrast`] is at least three times the noise's
/// gradient ([`noise_gradient`]), so that noise keeps `H` near 1.
pub fn contrast_scale(g2: &[f64]) -> f64 {
    let mut g: Vec<f64> = g2.iter().map(|v| v.sqrt()).collect();
    let max = g.iter().copied().fold(0.0, f64::max);
    let rank = ((g.len() as f64 - 1.0) * 0.99).round() as usize;
    let p99 = if g.is_empty() { 0.0 } else { *g.select_nth_unstable_by(rank, f64::total_cmp).1 };
    (p99.max(0.25 * max) / 20.0).max(1e-6)
}

/// Standard deviation of one component of the gradient of white noise of standard
/// deviation `noise` after a Gaussian of `sigma` samples in `dimension` dimensions:
/// `noise · (2σ² (4π)^{d/2} σ^d)^{-1/2}` (`∫ (∂_x G_σ)² = ∫ G_σ² / 2σ²`).
pub fn noise_gradient(noise: f64, sigma: f64, dimension: usize) -> f64 {
    let s = sigma.max(0.5);
    let d = dimension as f64;
    noise / (2.0 * s * s * (4.0 * std::f64::consts::PI).powf(d / 2.0) * s.powf(d)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The automatic contrast scale follows the strong edges, not a few brightest
    /// ones: dim objects (most edges of gradient 2, a few of 20) get a smaller `k`
    /// than bright ones, so their edges still bring `H` near 0; a step on the
    /// [0, 100] scale gets `H ≈ 1/400` at its steepest point.
    #[test]
    fn contrast_scale_from_the_strong_edges() {
        let mut g2 = vec![0.0; 10_000];
        for (n, v) in g2.iter_mut().enumerate().take(300) {
            *v = if n < 10 { 400.0 } else { 4.0 };
        }
        let k = contrast_scale(&g2);
        assert!((k - 0.25).abs() < 1e-12, "{k}"); // the max/4 floor: 20/4/20
        for v in g2.iter_mut().take(300) {
            *v = 400.0;
        }
        assert!((contrast_scale(&g2) - 1.0).abs() < 1e-12);
    }

    /// The noise's gradient: `σ_n (2σ² (4π)^{d/2} σ^d)^{-1/2}`, halved when `σ`
    /// grows by `2^{1/2}` in 2D (`σ⁻²`).
    #[test]
    fn noise_gradient_falls_with_the_smoothing() {
        let g = noise_gradient(1.0, 1.5, 2);
        assert!((g - 1.0 / (2.0 * 2.25 * 4.0 * std::f64::consts::PI * 2.25f64).sqrt()).abs() < 1e-15);
        assert!((noise_gradient(1.0, 1.5 * 2f64.sqrt(), 2) - 0.5 * g).abs() < 1e-15);
        assert!(noise_gradient(1.0, 1.5, 3) < g);
    }
}
