//! The uniform cubic B-spline `B` (support `[-2, 2]`, C², partition of unity) and
//! its antiderivative `I_B(s) = ∫_{-∞}^s B`.
//!
//! For `u = i₀ + t`, `t ∈ [0, 1)`, the four splines centred at `i₀-1 … i₀+2` take the
//! values `w(t)` below, their derivatives `dw`, second derivatives `ddw`, and the
//! antiderivatives `iw(t) = I_B(u - i)`.

/// `1/6`, multiplied by rather than divided by (a division by a constant is not
/// turned into a multiplication, which rounds differently, and costs a division).
const SIXTH: f64 = 1.0 / 6.0;

/// `B(t+1), B(t), B(t-1), B(t-2)`.
#[inline]
pub fn w(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s * SIXTH,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) * SIXTH,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) * SIXTH,
        t * t * t * SIXTH,
    ]
}

/// Derivatives of [`w`].
#[inline]
pub fn dw(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [-s * s / 2.0, (3.0 * t * t - 4.0 * t) / 2.0, (-3.0 * t * t + 2.0 * t + 1.0) / 2.0, t * t / 2.0]
}

/// Second derivatives of [`w`].
#[inline]
pub fn ddw(t: f64) -> [f64; 4] {
    [1.0 - t, 3.0 * t - 2.0, 1.0 - 3.0 * t, t]
}

/// `I_B` on `[-1, 0]`: `1/24 + (4s − 2s³ − ¾s⁴ + 11/4)/6`.
#[inline]
fn ib_left(s: f64) -> f64 {
    1.0 / 24.0 + (4.0 * s - 2.0 * s * s * s - 0.75 * s * s * s * s + 2.75) * SIXTH
}

/// `I_B(t+1), I_B(t), I_B(t-1), I_B(t-2)`.
#[inline]
pub fn iw(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [1.0 - s * s * s * s * (1.0 / 24.0), 1.0 - ib_left(-t), ib_left(t - 1.0), t * t * t * t * (1.0 / 24.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_consistent_derivatives() {
        for k in 0..=10 {
            let t = k as f64 / 10.0 * 0.999;
            assert!((w(t).iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!(dw(t).iter().sum::<f64>().abs() < 1e-14);
            let h = 1e-6;
            for q in 0..4 {
                let fd = (w(t + h)[q] - w(t - h)[q]) / (2.0 * h);
                assert!((fd - dw(t)[q]).abs() < 1e-8);
                let fd2 = (dw(t + h)[q] - dw(t - h)[q]) / (2.0 * h);
                assert!((fd2 - ddw(t)[q]).abs() < 1e-7);
                let fdi = (iw(t + h)[q] - iw(t - h)[q]) / (2.0 * h);
                assert!((fdi - w(t)[q]).abs() < 1e-8, "q={q} t={t}");
            }
        }
        // continuity of I_B across knots: iw(1⁻)[q] == iw(0)[q-1]
        let (a, b) = (iw(1.0 - 1e-12), iw(0.0));
        for q in 1..4 {
            assert!((a[q] - b[q - 1]).abs() < 1e-10);
        }
        assert!((b[0] - 23.0 / 24.0).abs() < 1e-14 && (b[1] - 0.5).abs() < 1e-14 && (b[2] - 1.0 / 24.0).abs() < 1e-14);
    }
}
