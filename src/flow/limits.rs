//! Limits on where a step may take each vertex (segmentation: the image's box),
//! which the step's solve keeps ([`super::active_set`]).

use crate::geometry::{Mesh, Point};

/// Where a step may take each vertex of the shape it starts from.
pub trait StepLimits<const D: usize>: Send + Sync {
    /// For each vertex `i` whose step would take it from `from[i]` to `to[i]`, the
    /// largest fraction `s ∈ [0, 1]` of that move it may make (1: all of it).
    fn fractions(&self, from: &[Point<D>], to: &[Point<D>]) -> Vec<f64>;
}

/// The box `[lo, hi]` (per axis) the shape stays in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Confinement<const D: usize> {
    pub lo: Point<D>,
    pub hi: Point<D>,
}

impl<const D: usize> Confinement<D> {
    /// `mesh` with every vertex moved to its nearest point of the box.
    pub fn clamp(&self, mut mesh: Mesh<D>) -> Mesh<D> {
        let outside = mesh.positions().iter().any(|x| (0..D).any(|a| x[a] < self.lo[a] || x[a] > self.hi[a]));
        if outside {
            let clamped = mesh
                .positions()
                .iter()
                .map(|x| Point::<D>::from_fn(|a, _| x[a].clamp(self.lo[a], self.hi[a])))
                .collect();
            mesh.set_positions(clamped);
        }
        mesh
    }

    /// The largest fraction of the move `x → y` that stays in the box (0 for a
    /// vertex on or past a face moving further out).
    pub fn fraction(&self, x: &Point<D>, y: &Point<D>) -> f64 {
        let mut s = 1.0f64;
        for a in 0..D {
            let d = y[a] - x[a];
            if y[a] > self.hi[a] && d > 0.0 {
                s = s.min((self.hi[a] - x[a]).max(0.0) / d);
            } else if y[a] < self.lo[a] && d < 0.0 {
                s = s.min((self.lo[a] - x[a]).min(0.0) / d);
            }
        }
        s
    }
}

impl<const D: usize> StepLimits<D> for Confinement<D> {
    fn fractions(&self, from: &[Point<D>], to: &[Point<D>]) -> Vec<f64> {
        from.iter().zip(to).map(|(x, y)| self.fraction(x, y)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_box_stops_a_move_at_its_face() {
        let c = Confinement::<2> { lo: Point::<2>::new(0.0, 0.0), hi: Point::<2>::new(1.0, 2.0) };
        let x = Point::<2>::new(0.75, 0.5);
        // out through x = 1 at a quarter of the way, before y = -0.5 at three quarters
        assert_eq!(c.fraction(&x, &Point::<2>::new(1.75, -0.5)), 0.25);
        assert_eq!(c.fraction(&x, &Point::<2>::new(0.25, -0.5)), 0.5);
        assert_eq!(c.fraction(&x, &Point::<2>::new(0.25, 1.5)), 1.0);
        // on a face, moving out of it: no room that way, but along it
        let on = Point::<2>::new(1.0, 1.0);
        assert_eq!(c.fraction(&on, &Point::<2>::new(1.5, 1.0)), 0.0);
        assert_eq!(c.fraction(&on, &Point::<2>::new(0.5, 1.5)), 1.0);
    }

    #[test]
    fn clamp_moves_only_what_is_outside() {
        let c = Confinement::<2> { lo: Point::<2>::new(0.0, 0.0), hi: Point::<2>::new(1.0, 1.0) };
        let m = crate::geometry::circle([0.5, 0.5], 0.6, 16).unwrap();
        let clamped = c.clamp(m.clone());
        for (x, y) in m.positions().iter().zip(clamped.positions()) {
            assert!(y.x >= 0.0 && y.x <= 1.0 && y.y >= 0.0 && y.y <= 1.0);
            if x.x >= 0.0 && x.x <= 1.0 && x.y >= 0.0 && x.y <= 1.0 {
                assert_eq!(x, y);
            }
        }
    }
}
