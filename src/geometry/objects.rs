//! The objects of a shape: its components, each component of negative enclosed
//! measure (a hole of a curve, a cavity of a surface) belonging to the smallest
//! positive component around it. Curves decide "around" by the winding number of a
//! vertex of the hole; surfaces by bounding boxes (a cavity's box lies in its
//! owner's).

use super::{winding_number, Mesh, Point};

/// Components of a mesh grouped into objects.
#[derive(Debug, Clone, PartialEq)]
pub struct Objects {
    /// Component of every vertex (as [`Mesh::component_labels`]).
    pub vertex_component: Vec<usize>,
    /// Signed enclosed measure of every component.
    pub measures: Vec<f64>,
    /// The component that owns each component: itself if positive, the positive
    /// one around it for a hole, itself for a hole with nothing around it.
    pub owner: Vec<usize>,
}

impl Objects {
    /// The components that are objects of their own (positive measure).
    pub fn roots(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.owner.len()).filter(|&c| self.owner[c] == c && self.measures[c] > 0.0)
    }
}

impl<const D: usize> Mesh<D> {
    /// The objects of the shape (see the module documentation).
    pub fn objects(&self) -> Objects {
        let (vertex_component, count) = self.component_labels();
        let mut measures = vec![0.0; count];
        for (e, el) in self.elements().iter().enumerate() {
            measures[vertex_component[el[0]]] += self.element_enclosed_contribution(e);
        }
        let mut owner: Vec<usize> = (0..count).collect();
        if measures.iter().all(|&m| m >= 0.0) {
            return Objects { vertex_component, measures, owner };
        }
        let mut bbox = vec![[Point::<D>::repeat(f64::INFINITY), Point::<D>::repeat(f64::NEG_INFINITY)]; count];
        for (x, &c) in self.positions().iter().zip(&vertex_component) {
            bbox[c] = [bbox[c][0].inf(x), bbox[c][1].sup(x)];
        }
        let within =
            |h: usize, o: usize| (0..D).all(|a| bbox[o][0][a] <= bbox[h][0][a] && bbox[h][1][a] <= bbox[o][1][a]);
        let loops: Vec<Vec<Point<2>>> = if D == 2 {
            let mut loops = vec![Vec::new(); count];
            for cycle in self.cycles_of_elements() {
                let c = vertex_component[cycle[0]];
                loops[c] =
                    cycle.iter().map(|&v| Point::<2>::new(self.positions()[v][0], self.positions()[v][1])).collect();
            }
            loops
        } else {
            Vec::new()
        };
        for h in (0..count).filter(|&h| measures[h] < 0.0) {
            let around = (0..count)
                .filter(|&o| measures[o] > 0.0 && within(h, o))
                .filter(|&o| D != 2 || winding_number(&[&loops[o]], loops[h][0]) != 0)
                .min_by(|&a, &b| measures[a].total_cmp(&measures[b]));
            owner[h] = around.unwrap_or(h);
        }
        Objects { vertex_component, measures, owner }
    }

    /// Vertex cycles of a curve mesh (`D = 2`) following its segments.
    fn cycles_of_elements(&self) -> Vec<Vec<usize>> {
        super::segment_cycles(self.num_vertices(), self.elements().iter().map(|e| (e[0], e[D - 1])))
    }
}

#[cfg(test)]
mod tests {
    use crate::geometry::{circle, icosphere, union, Mesh, Point};

    #[test]
    fn a_ring_and_a_disc() {
        let outer = circle([0.0, 0.0], 2.0, 64).unwrap();
        let hole = circle([0.0, 0.0], 1.0, 32).unwrap();
        let hole = hole.with_positions(hole.positions().iter().map(|p| Point::<2>::new(p.x, -p.y)).collect());
        let disc = circle([5.0, 0.0], 1.0, 32).unwrap();
        let m = union(&[outer, hole, disc]).unwrap();
        let o = m.objects();
        assert_eq!(o.roots().count(), 2);
        let hole_c = (0..3).find(|&c| o.measures[c] < 0.0).unwrap();
        let ring_c = (0..3).max_by(|&a, &b| o.measures[a].total_cmp(&o.measures[b])).unwrap();
        assert_eq!(o.owner[hole_c], ring_c);
    }

    #[test]
    fn a_cavity() {
        let outer = icosphere([0.0, 0.0, 0.0], 2.0, 2).unwrap();
        let inner = icosphere([0.0, 0.0, 0.0], 1.0, 1).unwrap();
        let flipped: Vec<[usize; 3]> = inner.elements().iter().map(|t| [t[0], t[2], t[1]]).collect();
        let n = outer.num_vertices();
        let mut positions = outer.positions().to_vec();
        positions.extend(inner.positions());
        let mut elements = outer.elements().to_vec();
        elements.extend(flipped.iter().map(|t| t.map(|v| v + n)));
        let m = Mesh::<3>::from_trusted_parts(positions, elements);
        let o = m.objects();
        assert_eq!(o.roots().count(), 1);
        assert!(o.measures.iter().any(|&v| v < 0.0));
        assert!(o.owner.iter().all(|&c| c == o.owner[0]));
    }
}
