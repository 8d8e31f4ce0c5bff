//! One run of the Chan–Vese functional: the problem, and the objects and moments
//! of the last mesh they were computed for. The flow evaluates the energy of the
//! step it accepts (or of the mesh management's result) and then linearizes on
//! that same mesh, so the shape gradient reuses the region integrals instead of
//! computing them again.

use super::{ChanVese, Moments};
use crate::geometry::Mesh;
use std::sync::Arc;

/// The objects of a mesh ([`ChanVese`]'s `objects`): the component of every
/// vertex, the object of every component and every object's moments.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Objects {
    pub vertex_component: Vec<usize>,
    pub object_of: Vec<usize>,
    pub moments: Vec<Moments>,
}

/// A mesh's coordinates and connectivity, flattened (either dimension), to
/// recognize the same mesh again.
#[derive(Debug, Clone, PartialEq)]
struct Key {
    positions: Vec<f64>,
    elements: Vec<usize>,
}

impl Key {
    fn matches<const D: usize>(&self, mesh: &Mesh<D>) -> bool {
        self.positions.len() == D * mesh.num_vertices()
            && self.elements.len() == D * mesh.num_elements()
            && mesh.positions().iter().flat_map(|x| x.iter()).eq(self.positions.iter())
            && mesh.elements().iter().flatten().eq(self.elements.iter())
    }

    fn of<const D: usize>(mesh: &Mesh<D>) -> Key {
        Key {
            positions: mesh.positions().iter().flat_map(|x| x.iter().copied()).collect(),
            elements: mesh.elements().iter().flatten().copied().collect(),
        }
    }
}

/// [`ChanVese`] as a flow runs it (see the module documentation).
#[derive(Debug, Clone)]
pub struct ChanVeseRun {
    pub(super) cv: ChanVese,
    last: Option<(Key, Arc<Objects>)>,
}

impl ChanVese {
    /// A run of this problem, with nothing computed yet.
    pub fn start(&self) -> ChanVeseRun {
        ChanVeseRun { cv: self.clone(), last: None }
    }
}

impl ChanVeseRun {
    /// The problem this run evaluates.
    pub fn problem(&self) -> &ChanVese {
        &self.cv
    }

    /// The objects of `mesh`, computed unless `mesh` is the one of the last call
    /// (the same coordinates and connectivity, exactly).
    pub(super) fn objects<const D: usize>(&mut self, mesh: &Mesh<D>) -> Arc<Objects> {
        if let Some((key, objects)) = &self.last {
            if key.matches(mesh) {
                return objects.clone();
            }
        }
        let objects = Arc::new(self.cv.objects(mesh));
        self.last = Some((Key::of(mesh), objects.clone()));
        objects
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::circle;

    /// The cached objects are those of the mesh asked for: a moved vertex is a new
    /// mesh.
    #[test]
    fn a_mesh_is_recognized_exactly() {
        let n = 32;
        let values: Vec<f64> = (0..n * n).map(|p| if (p % n) < n / 2 { 1.0 } else { 0.0 }).collect();
        let mut run = ChanVese::new(2, [n, n, 1], &values, 1e-3, (1.0, 1.0)).start();
        let a = circle([0.5, 0.5], 0.3, 64).unwrap();
        let first = run.objects(&a);
        assert!(Arc::ptr_eq(&first, &run.objects(&a)));
        let mut x = a.positions().to_vec();
        x[3][0] += 1e-9;
        let b = a.with_positions(x);
        let moved = run.objects(&b);
        assert!(!Arc::ptr_eq(&first, &moved));
        assert_eq!(*moved, run.problem().objects(&b));
        assert_eq!(*first, run.problem().objects(&a));
    }
}
