//! The periodic cell of the film: its width `L`, the Dirichlet data `g` on the
//! substrate and the lateral walls, and initial free surfaces.

use crate::geometry::{CurveMesh, Mesh, MeshError, Point};

/// The Dirichlet data `g(x, y) = a + b x + c y` on the bottom and lateral walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundaryData {
    pub a: f64,
    pub b: f64,
    pub c: f64,
}

impl BoundaryData {
    /// `g ≡ a`: no stress, pure surface diffusion.
    pub fn constant(a: f64) -> Self {
        BoundaryData { a, b: 0.0, c: 0.0 }
    }

    /// `g = x`, the paper's misfit (§4.4.2).
    pub fn x() -> Self {
        BoundaryData { a: 0.0, b: 1.0, c: 0.0 }
    }

    pub fn value(&self, p: Point<2>) -> f64 {
        self.a + self.b * p.x + self.c * p.y
    }

    /// `∇g = 0`: the field is constant and `∫_Ω |∇y|² = 0` for every shape.
    pub fn is_constant(&self) -> bool {
        self.b == 0.0 && self.c == 0.0
    }
}

/// The film's cell `0 < x < L` on the substrate `y = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmCell {
    pub length: f64,
    pub boundary: BoundaryData,
}

/// The flat film of height `height` with the perturbation `amplitude·cos(2π m x / L)`,
/// `n` vertices equally spaced in `x` at the midpoints `(i + ½) L / n` (a periodic
/// curve running in `+x`).
pub fn cosine_film(length: f64, height: f64, amplitude: f64, mode: u32, n: usize) -> Result<CurveMesh, MeshError> {
    let k = std::f64::consts::TAU * mode as f64 / length;
    let points: Vec<Point<2>> = (0..n)
        .map(|i| {
            let x = length * (i as f64 + 0.5) / n as f64;
            Point::<2>::new(x, height + amplitude * (k * x).cos())
        })
        .collect();
    polyline_film(length, &points)
}

/// A film surface through `points` (one period, in `+x`; the segment from the last
/// point back to the first one's periodic image closes it).
pub fn polyline_film(length: f64, points: &[Point<2>]) -> Result<CurveMesh, MeshError> {
    let n = points.len();
    Mesh::new_periodic(points.to_vec(), (0..n).map(|i| [i, (i + 1) % n]).collect(), length)
}
