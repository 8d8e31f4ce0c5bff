//! The simplex kernels shared by geometry and assembly: measure and unit outward
//! normal of one element with `D` vertices in `R^D` (a segment in the plane, a
//! triangle in space). Pure functions over fixed-size nalgebra types.

use nalgebra::{SVector, Vector3};

/// Measure and unit outward normal of an element.
///
/// * `D = 2`: segment `p0 -> p1`, length `h = |p1 - p0|`, normal `(t_y, -t_x)` with
///   `t = (p1 - p0)/h`: the right-hand normal, outward for counter-clockwise curves.
/// * `D = 3`: triangle `(p0, p1, p2)`, area `|n|/2` with `n = (p1 - p0) × (p2 - p0)`,
///   normal `n/|n|`: outward for triangles counter-clockwise seen from outside.
///
/// A degenerate element has measure 0 and a zero normal.
#[inline]
pub fn measure_and_normal<const D: usize>(p: &[SVector<f64, D>; D]) -> (f64, SVector<f64, D>) {
    match D {
        2 => {
            let e = p[1] - p[0];
            let h = e.norm();
            let mut n = SVector::<f64, D>::zeros();
            if h > 0.0 {
                n[0] = e[1] / h;
                n[1] = -e[0] / h;
            }
            (h, n)
        }
        3 => {
            let c = cross3(p);
            let len = c.norm();
            let mut n = SVector::<f64, D>::zeros();
            if len > 0.0 {
                for k in 0..3 {
                    n[k] = c[k] / len;
                }
            }
            (0.5 * len, n)
        }
        _ => unreachable!("elements exist for D = 2 and D = 3 only"),
    }
}

/// `(p1 - p0) × (p2 - p0)` for a triangle given as `[SVector<f64, 3>; 3]` in generic form.
#[inline]
pub(crate) fn cross3<const D: usize>(p: &[SVector<f64, D>; D]) -> Vector3<f64> {
    let a = Vector3::new(p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]);
    let b = Vector3::new(p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]);
    a.cross(&b)
}

/// Contribution of one element to the enclosed signed measure (area in 2D by the
/// shoelace formula `½ (x0 y1 − x1 y0)`, volume in 3D by `⅙ p0 · (p1 × p2)`).
#[inline]
pub fn enclosed_contribution<const D: usize>(p: &[SVector<f64, D>; D]) -> f64 {
    match D {
        2 => 0.5 * (p[0][0] * p[1][1] - p[1][0] * p[0][1]),
        3 => {
            let a = Vector3::new(p[0][0], p[0][1], p[0][2]);
            let b = Vector3::new(p[1][0], p[1][1], p[1][2]);
            let c = Vector3::new(p[2][0], p[2][1], p[2][2]);
            a.dot(&b.cross(&c)) / 6.0
        }
        _ => unreachable!(),
    }
}

/// Diameter of an element: its length (2D) or its longest edge (3D).
#[inline]
pub fn diameter<const D: usize>(p: &[SVector<f64, D>; D]) -> f64 {
    let mut d: f64 = 0.0;
    for a in 0..D {
        for b in a + 1..D {
            d = d.max((p[a] - p[b]).norm());
        }
    }
    d
}
