//! Measures of a mesh: enclosed area/volume, perimeter/surface area, element and
//! vertex normals, and quality figures.

use super::{simplex, Mesh, Point};

/// Quality figures of a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshQuality {
    /// Shortest edge length.
    pub min_edge: f64,
    /// Longest edge length.
    pub max_edge: f64,
    /// Smallest interior angle of any triangle in degrees (180 for curves).
    pub min_angle_deg: f64,
    /// Largest interior angle of any triangle in degrees (0 for curves).
    pub max_angle_deg: f64,
}

impl<const D: usize> Mesh<D> {
    /// Signed enclosed measure: area `½ Σ (x_a y_b − x_b y_a)` (2D) or volume
    /// `⅙ Σ p_a · (p_b × p_c)` (3D). Positive for outward orientation.
    ///
    /// Periodic curves: `−Σ (x_b − x_a)(y_a + y_b)/2 = −∮ y dx` over the lifted
    /// segments, which is invariant under shifts by the period; for a component
    /// winding in `+x` it is minus the area between it and `y = 0`, so the sum is the
    /// area of the closed components minus that under the winding ones (its
    /// variation under a normal motion is `∫_Γ V`, as for closed curves).
    pub fn enclosed_measure(&self) -> f64 {
        (0..self.num_elements()).map(|e| self.element_enclosed_contribution(e)).sum()
    }

    /// The share of element `e` in [`Mesh::enclosed_measure`].
    pub(super) fn element_enclosed_contribution(&self, e: usize) -> f64 {
        let p = self.element_points(e);
        if self.period().is_some() {
            -0.5 * (p[1][0] - p[0][0]) * (p[0][1] + p[1][1])
        } else {
            simplex::enclosed_contribution(&p)
        }
    }

    /// [`Mesh::enclosed_measure`] of every component of [`Mesh::component_labels`].
    pub fn component_measures(&self) -> Vec<f64> {
        let (labels, count) = self.component_labels();
        let mut m = vec![0.0; count];
        for (e, el) in self.elements().iter().enumerate() {
            m[labels[el[0]]] += self.element_enclosed_contribution(e);
        }
        m
    }

    /// Every component offset along its unit vertex normals by the uniform distance
    /// that gives it the enclosed measure `targets[c]` (components as in
    /// [`Mesh::component_labels`], which must match `targets`).
    ///
    /// The first variation of the enclosed measure is `Σ_i N⃗_i·δX⃗_i` with the lumped
    /// `N⃗_i = ∫_Γ φ_i ν`, so the offset `δ_c = (A*_c − A_c)/Σ_{i∈c} |N⃗_i|` restores it
    /// up to `O(δ_c² |Γ_c| max|κ|)`. Area-conserving flows use it to remove the `O(τ²)`
    /// error of a step, which would otherwise add up over many steps.
    pub fn with_component_measures(&self, targets: &[f64]) -> Self {
        let (labels, count) = self.component_labels();
        assert_eq!(count, targets.len(), "one target per component");
        let mut lumped = vec![Point::<D>::zeros(); self.num_vertices()];
        let mut current = vec![0.0; count];
        for (e, el) in self.elements().iter().enumerate() {
            let (m, nu) = self.element_geometry(e);
            for &v in el {
                lumped[v] += nu * (m / D as f64);
            }
            current[labels[el[0]]] += self.element_enclosed_contribution(e);
        }
        let mut weight = vec![0.0; count];
        for (v, n) in lumped.iter().enumerate() {
            weight[labels[v]] += n.norm();
        }
        let delta: Vec<f64> = (0..count)
            .map(|c| {
                let d = (targets[c] - current[c]) / weight[c];
                if d.is_finite() {
                    d
                } else {
                    0.0
                }
            })
            .collect();
        let positions = self
            .positions()
            .iter()
            .zip(&lumped)
            .enumerate()
            .map(|(v, (x, n))| {
                let l = n.norm();
                if l > 0.0 {
                    x + n * (delta[labels[v]] / l)
                } else {
                    *x
                }
            })
            .collect();
        self.with_positions(positions)
    }

    /// Measure of Γ itself: perimeter (2D) or surface area (3D), `Σ_T |T|`.
    pub fn boundary_measure(&self) -> f64 {
        (0..self.num_elements()).map(|e| self.element_geometry(e).0).sum()
    }

    /// Unit outward normal `ν_T` of every element (`#E × D`).
    pub fn element_normals(&self) -> Vec<Point<D>> {
        (0..self.num_elements()).map(|e| self.element_geometry(e).1).collect()
    }

    /// Unit vertex normals: the normalized lumped `N⃗_i = ∫_Γ φ_i ν = Σ_{T∋i} |T| ν_T / D`
    /// ([`vertex_normals`]).
    pub fn vertex_normals(&self) -> Vec<Point<D>> {
        // element_geometry: periodic segments run to the nearest image of their end
        vertex_normals_by(self.num_vertices(), self.elements(), |e| self.element_geometry(e))
    }

    /// Centroid of the vertices.
    pub fn vertex_centroid(&self) -> Point<D> {
        let s: Point<D> = self.positions().iter().sum();
        s / self.num_vertices() as f64
    }

    /// Edge lengths and angles: see [`MeshQuality`].
    pub fn quality(&self) -> MeshQuality {
        let mut q = MeshQuality { min_edge: f64::INFINITY, max_edge: 0.0, min_angle_deg: 180.0, max_angle_deg: 0.0 };
        for e in 0..self.num_elements() {
            let p = self.element_points(e);
            for a in 0..D {
                let b = (a + 1) % D;
                let l = (p[b] - p[a]).norm();
                q.min_edge = q.min_edge.min(l);
                q.max_edge = q.max_edge.max(l);
                if D == 3 {
                    let c = (a + 2) % D;
                    let u = p[b] - p[a];
                    let w = p[c] - p[a];
                    let cos = (u.dot(&w) / (u.norm() * w.norm())).clamp(-1.0, 1.0);
                    let ang = cos.acos().to_degrees();
                    q.min_angle_deg = q.min_angle_deg.min(ang);
                    q.max_angle_deg = q.max_angle_deg.max(ang);
                }
            }
        }
        q
    }
}

/// Unit vertex normals of the elements `elements` over `positions`: each vertex's
/// `Σ_{T∋i} |T| ν_T` (the lumped `∫_Γ φ_i ν` up to the factor `1/D`: area-weighted
/// on surfaces, length-weighted on curves), normalized; zero where it vanishes.
/// The one computation of vertex normals (meshes, remeshing, glTF).
pub fn vertex_normals<const D: usize>(positions: &[Point<D>], elements: &[[usize; D]]) -> Vec<Point<D>> {
    vertex_normals_by(positions.len(), elements, |e| simplex::measure_and_normal(&elements[e].map(|v| positions[v])))
}

/// [`vertex_normals`] with each element's measure and unit normal given by
/// `geometry(e)`.
fn vertex_normals_by<const D: usize>(
    vertices: usize,
    elements: &[[usize; D]],
    geometry: impl Fn(usize) -> (f64, Point<D>),
) -> Vec<Point<D>> {
    let mut n = vec![Point::<D>::zeros(); vertices];
    for (e, el) in elements.iter().enumerate() {
        let (m, nu) = geometry(e);
        for &v in el {
            n[v] += nu * m;
        }
    }
    for v in &mut n {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::super::{circle, icosphere, union};
    use crate::geometry::Point;
    use crate::problems::cosine_film;

    /// Each component is scaled differently; the offsets restore every measure up to
    /// the second order of the offset (relative changes of 2e-4 → below 1e-7).
    #[test]
    fn component_measures_are_restored_one_by_one() {
        let two = union(&[circle([0.0, 0.0], 1.0, 64).unwrap(), circle([3.0, 0.0], 0.5, 32).unwrap()]).unwrap();
        let targets = two.component_measures();
        assert!((targets.iter().sum::<f64>() - two.enclosed_measure()).abs() < 1e-14);
        let moved = two.with_positions(
            two.positions()
                .iter()
                .map(|p| {
                    if p.x < 2.0 {
                        p * 1.0001
                    } else {
                        Point::<2>::new(3.0, 0.0) + (p - Point::<2>::new(3.0, 0.0)) * 0.9998
                    }
                })
                .collect(),
        );
        let restored = moved.with_component_measures(&targets);
        for (a, b) in restored.component_measures().iter().zip(&targets) {
            assert!((a / b - 1.0).abs() < 1e-7, "{a} vs {b}");
        }
        // a periodic film surface (area under it) and a sphere (volume)
        let film = cosine_film(1.0, 0.5, 0.05, 1, 64).unwrap();
        let target = film.component_measures();
        let lifted = film.with_positions(film.positions().iter().map(|p| p + Point::<2>::new(0.0, 1e-4)).collect());
        let back = lifted.with_component_measures(&target).component_measures();
        assert!((back[0] / target[0] - 1.0).abs() < 1e-9, "{back:?} vs {target:?}");
        let ball = icosphere([0.0; 3], 1.0, 3).unwrap();
        let v = ball.component_measures();
        let grown = ball.with_positions(ball.positions().iter().map(|p| p * 1.0002).collect());
        let back = grown.with_component_measures(&v).component_measures();
        assert!((back[0] / v[0] - 1.0).abs() < 1e-6, "{back:?} vs {v:?}");
    }
}
