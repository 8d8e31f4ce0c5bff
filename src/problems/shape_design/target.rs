//! The target `z_g` of shape design: the state the domain's solution should match
//! on the control region `D`.

use crate::geometry::Point;

/// The target `z_g` on `D`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    Constant(f64),
    /// `log(R / |x − c|)`: the state of the annulus with `Γ` the unit circle around `c`
    /// and `Σ` the circle of radius `R` (paper §4.3.2).
    LogRadial {
        center: Point<2>,
        radius: f64,
    },
    /// `a + b cos(kθ)` in polar coordinates around `c` (paper §4.3.3, Figure 7).
    Polar {
        center: Point<2>,
        a: f64,
        b: f64,
        k: f64,
    },
}

impl Target {
    pub fn value(&self, x: Point<2>) -> f64 {
        match *self {
            Target::Constant(c) => c,
            Target::LogRadial { center, radius } => (radius / (x - center).norm()).ln(),
            Target::Polar { center, a, b, k } => {
                let d = x - center;
                a + b * (k * d.y.atan2(d.x)).cos()
            }
        }
    }
}
