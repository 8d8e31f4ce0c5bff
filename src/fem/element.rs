//! Element kernels: pure functions over fixed-size nalgebra types.
//!
//! On an element `T` with `D` vertices (segment in 2D, triangle in 3D) and P1 basis
//! functions `φ_a`:
//!
//! * stiffness `K_ab = ∫_T ∇_Γφ_a·∇_Γφ_b`: segment of length `h`:
//!   `K = [[1, −1], [−1, 1]] / h`; triangle: `K_ab = (e_a · e_b) / (4|T|)` with `e_a`
//!   the edge opposite vertex `a`, `e_a = p_{a+2} − p_{a+1}` (the cotangent formula);
//! * mass `M_ab = ∫_T φ_a φ_b = |T| (1 + δ_ab) / (D (D + 1))`;
//! * lumped mass `∫_T φ_a = |T| / D`.

use crate::geometry::simplex;
use nalgebra::{SMatrix, SVector};

/// Geometry and stiffness of one element.
#[derive(Debug, Clone, Copy)]
pub struct ElementData<const D: usize> {
    /// `|T|`: length or area.
    pub measure: f64,
    /// Unit outward normal `ν_T`.
    pub normal: SVector<f64, D>,
    /// `K_ab = ∫_T ∇_Γφ_a·∇_Γφ_b` (`D × D`).
    pub stiffness: SMatrix<f64, D, D>,
}

/// Measure, normal and stiffness of the element with vertices `p`.
#[inline]
pub fn element_data<const D: usize>(p: &[SVector<f64, D>; D]) -> ElementData<D> {
    let (measure, normal) = simplex::measure_and_normal(p);
    let mut stiffness = SMatrix::<f64, D, D>::zeros();
    match D {
        2 => {
            let inv = 1.0 / measure;
            stiffness[(0, 0)] = inv;
            stiffness[(1, 1)] = inv;
            stiffness[(0, 1)] = -inv;
            stiffness[(1, 0)] = -inv;
        }
        3 => {
            let k = cotangent_stiffness(&[p[0], p[1], p[2]], measure);
            for a in 0..3 {
                for b in 0..3 {
                    stiffness[(a, b)] = k[(a, b)];
                }
            }
        }
        _ => unreachable!(),
    }
    ElementData { measure, normal, stiffness }
}

/// P1 stiffness `K_ab = (e_a · e_b) / (4|T|)` of a triangle with vertices `p` (in the
/// plane or in space) and area `|T| = area`, `e_a = p_{a+2} − p_{a+1}` the edge
/// opposite vertex `a` (the cotangent formula).
#[inline]
pub fn cotangent_stiffness<const N: usize>(p: &[SVector<f64, N>; 3], area: f64) -> SMatrix<f64, 3, 3> {
    let e: [SVector<f64, N>; 3] = std::array::from_fn(|a| p[(a + 2) % 3] - p[(a + 1) % 3]);
    let inv = 1.0 / (4.0 * area);
    SMatrix::<f64, 3, 3>::from_fn(|a, b| e[a].dot(&e[b]) * inv)
}

/// Entry `M_ab` of the consistent element mass matrix.
#[inline]
pub fn mass_entry<const D: usize>(measure: f64, a: usize, b: usize) -> f64 {
    let diag = if a == b { 2.0 } else { 1.0 };
    measure * diag / (D * (D + 1)) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn triangle_stiffness_matches_gradients() {
        let p = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
        let d = element_data(&p);
        assert!((d.measure - 1.0).abs() < 1e-15);
        // gradients: φ0 = 1 - x/2 - y, φ1 = x/2, φ2 = y
        let g = [Vector3::new(-0.5, -1.0, 0.0), Vector3::new(0.5, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
        for a in 0..3 {
            for b in 0..3 {
                assert!((d.stiffness[(a, b)] - g[a].dot(&g[b]) * d.measure).abs() < 1e-14);
            }
        }
        assert!((d.normal - Vector3::z()).norm() < 1e-15);
        let total: f64 =
            (0..3).flat_map(|a| (0..3).map(move |b| (a, b))).map(|(a, b)| mass_entry::<3>(1.0, a, b)).sum();
        assert!((total - 1.0).abs() < 1e-15);
    }
}
