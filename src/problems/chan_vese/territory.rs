//! The contact rule of surfaces: every object keeps to its territory.

use crate::geometry::{Mesh, Point};
use crate::imaging::EdgeField;
use std::sync::Arc;

/// The territory of every object of the initial shape on the image's grid (the
/// samples nearer to it than to any other, [`crate::imaging::labels::territories`]):
/// a vertex whose step would enter the territory of another object stays where
/// it is, so that touching objects meet at the border of their territories
/// instead of running into each other (surfaces have no crossing test as curves
/// do).
#[derive(Debug, Clone, PartialEq)]
pub struct Territories {
    /// Object label per sample (`x` fastest), as the image's grid.
    labels: Arc<Vec<u32>>,
}

impl Territories {
    /// `labels` on the grid of the image (`dims` samples).
    pub fn new(labels: Vec<u32>) -> Territories {
        Territories { labels: Arc::new(labels) }
    }

    /// The territory at `x` (unit-box coordinates; outside the grid, the nearest
    /// sample's).
    fn at<const D: usize>(&self, grid: &EdgeField, x: &Point<D>) -> u32 {
        let (dims, l) = (grid.dims(), grid.scale());
        let index = |a: usize| ((x[a] * l).floor().max(0.0) as usize).min(dims[a] - 1);
        let mut p = index(0) + dims[0] * index(1);
        if D == 3 {
            p += dims[0] * dims[1] * index(2);
        }
        self.labels[p]
    }

    /// `candidate` with every vertex that would enter the territory of another
    /// object than its component's held at its position in `current` (the same
    /// connectivity). A component's object is the territory most of its vertices
    /// of `current` lie in. A vertex already in another territory (put there by
    /// the mesh management, which follows the shape rather than the territories)
    /// may move back through it, against its normal, but is held if it would
    /// advance: held wherever it went, it stayed there for good (a volume's run
    /// held about 690 such vertices at every `τ` down to 1e-6).
    pub(super) fn hold<const D: usize>(&self, grid: &EdgeField, current: &Mesh<D>, candidate: Mesh<D>) -> Mesh<D> {
        let (component, count) = current.component_labels();
        let here: Vec<u32> = current.positions().iter().map(|x| self.at(grid, x)).collect();
        let mut pairs: Vec<(usize, u32)> = component.iter().copied().zip(here.iter().copied()).collect();
        pairs.sort_unstable();
        // the most frequent territory of each component (pairs sorted by both)
        let mut own = vec![0u32; count];
        let mut best = vec![0usize; count];
        let mut k = 0;
        while k < pairs.len() {
            let run = pairs[k..].iter().take_while(|q| **q == pairs[k]).count();
            let (c, t) = pairs[k];
            if run > best[c] {
                (best[c], own[c]) = (run, t);
            }
            k += run;
        }
        let mut x = candidate.positions().to_vec();
        let mut held = false;
        let mut normals: Option<Vec<Point<D>>> = None;
        for (v, p) in x.iter_mut().enumerate() {
            let mine = own[component[v]];
            let foreign = |t: u32| t != 0 && mine != 0 && t != mine;
            if !foreign(self.at(grid, p)) {
                continue;
            }
            let from = current.positions()[v];
            // a vertex already in another territory (left there by the mesh
            // management) may retreat through it, but not advance
            let hold = !foreign(self.at(grid, &from))
                || (*p - from).dot(&normals.get_or_insert_with(|| current.vertex_normals())[v]) > 0.0;
            if hold {
                *p = from;
                held = true;
            }
        }
        if !held {
            return candidate;
        }
        let mut candidate = candidate;
        candidate.set_positions(x);
        candidate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::icosphere;

    /// Two balls on a 20×10×10 grid split at x = 10: a step that moves every
    /// vertex of the left ball by 0.2 to the right holds those that would cross
    /// into the right ball's territory, and moves the others.
    #[test]
    fn a_step_into_another_territory_is_held() {
        let dims = [20, 10, 10];
        let grid = EdgeField::from_coefficients(3, dims, vec![0.0; 2000]);
        let l = grid.scale();
        let labels: Vec<u32> = (0..2000).map(|p| if p % 20 < 10 { 1 } else { 2 }).collect();
        let territories = Territories::new(labels);
        // the left ball: centre (5, 5, 5) samples, radius 3
        let ball = icosphere([5.0 / l, 5.0 / l, 5.0 / l], 3.0 / l, 2).unwrap();
        let moved: Vec<Point<3>> = ball.positions().iter().map(|x| x + Point::<3>::new(0.2, 0.0, 0.0)).collect();
        let candidate = territories.hold(&grid, &ball, ball.with_positions(moved.clone()));
        let mut held = 0;
        for (k, x) in candidate.positions().iter().enumerate() {
            if moved[k][0] * l >= 10.0 {
                assert_eq!(*x, ball.positions()[k]);
                held += 1;
            } else {
                assert_eq!(*x, moved[k]);
            }
        }
        assert!(held > 0 && held < ball.num_vertices(), "{held}");
    }

    /// A ball of radius 3 at x = 8 on the same grid reaches a sample past the
    /// border at x = 10: its vertices there may retreat through the other
    /// territory (the ball shrinking) but not advance into it (the ball growing).
    #[test]
    fn a_vertex_in_another_territory_may_only_retreat() {
        let dims = [20, 10, 10];
        let grid = EdgeField::from_coefficients(3, dims, vec![0.0; 2000]);
        let l = grid.scale();
        let territories = Territories::new((0..2000).map(|p| if p % 20 < 10 { 1 } else { 2 }).collect());
        let centre = Point::<3>::new(8.0 / l, 5.0 / l, 5.0 / l);
        let ball = icosphere([centre[0], centre[1], centre[2]], 3.0 / l, 2).unwrap();
        let scaled = |k: f64| ball.with_positions(ball.positions().iter().map(|x| centre + (x - centre) * k).collect());
        let inside = |x: &Point<3>| x[0] * l >= 10.0;
        let across = ball.positions().iter().filter(|x| inside(x)).count();
        assert!(across > 0);
        // shrinking: every vertex moves, also those that stay across the border
        let shrunk = scaled(0.95);
        assert!(shrunk.positions().iter().filter(|x| inside(x)).count() > 0);
        assert_eq!(territories.hold(&grid, &ball, shrunk.clone()).positions(), shrunk.positions());
        // growing: the vertices across the border, and those that would cross it,
        // stay; the others move
        let grown = scaled(1.05);
        let held = territories.hold(&grid, &ball, grown.clone());
        for k in 0..ball.num_vertices() {
            let stays = inside(&grown.positions()[k]);
            let expected = if stays { ball.positions()[k] } else { grown.positions()[k] };
            assert_eq!(held.positions()[k], expected, "vertex {k}");
        }
    }
}
