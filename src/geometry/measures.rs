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
        if self.period().is_some() {
            return (0..self.num_elements())
                .map(|e| {
                    let p = self.element_points(e);
                    -0.5 * (p[1][0] - p[0][0]) * (p[0][1] + p[1][1])
                })
                .sum();
        }
        (0..self.num_elements()).map(|e| simplex::enclosed_contribution(&self.element_points(e))).sum()
    }

    /// Measure of Γ itself: perimeter (2D) or surface area (3D), `Σ_T |T|`.
    pub fn boundary_measure(&self) -> f64 {
        (0..self.num_elements()).map(|e| self.element_geometry(e).0).sum()
    }

    /// Unit outward normal `ν_T` of every element (`#E × D`).
    pub fn element_normals(&self) -> Vec<Point<D>> {
        (0..self.num_elements()).map(|e| self.element_geometry(e).1).collect()
    }

    /// Unit vertex normals: the normalized lumped `N⃗_i = ∫_Γ φ_i ν = Σ_{T∋i} |T| ν_T / D`.
    pub fn vertex_normals(&self) -> Vec<Point<D>> {
        let mut n = vec![Point::<D>::zeros(); self.num_vertices()];
        for (e, el) in self.elements().iter().enumerate() {
            let (m, nu) = self.element_geometry(e);
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
