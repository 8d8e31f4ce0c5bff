//! Global assembly on a fixed [`Pattern`]: only values are refilled each step.

use super::element::{element_data, mass_entry};
use super::Pattern;
use crate::geometry::{Mesh, Point};
use nalgebra::SMatrix;

/// A weight function on Γ for `A_α`, `M_β`, `M_g`: constant, per element, or per
/// vertex (P1; its element average is used inside an element).
#[derive(Debug, Clone, PartialEq)]
pub enum Weight {
    Constant(f64),
    Element(Vec<f64>),
    Vertex(Vec<f64>),
}

impl Weight {
    /// Value on element `e` with vertices `el`.
    #[inline]
    pub fn on_element<const D: usize>(&self, e: usize, el: &[usize; D]) -> f64 {
        match self {
            Weight::Constant(c) => *c,
            Weight::Element(w) => w[e],
            Weight::Vertex(w) => el.iter().map(|&v| w[v]).sum::<f64>() / D as f64,
        }
    }

    /// Lumped nodal values `w_i = (∫_Γ w φ_i) / (∫_Γ φ_i)`.
    pub fn at_vertices<const D: usize>(&self, mesh: &Mesh<D>, m: &Matrices<D>) -> Vec<f64> {
        match self {
            Weight::Constant(c) => vec![*c; mesh.num_vertices()],
            Weight::Vertex(w) => w.clone(),
            Weight::Element(w) => {
                let mut out = vec![0.0; mesh.num_vertices()];
                for (e, el) in mesh.elements().iter().enumerate() {
                    for &v in el {
                        out[v] += w[e] * m.measure[e] / D as f64;
                    }
                }
                out.iter_mut().zip(&m.lumped_mass).for_each(|(o, mi)| *o /= mi);
                out
            }
        }
    }

    /// Check the length against the mesh and that every value is finite.
    pub fn check<const D: usize>(&self, mesh: &Mesh<D>) -> Result<(), String> {
        let (vals, need, what): (&[f64], usize, &str) = match self {
            Weight::Constant(c) => (std::slice::from_ref(c), 1, "constant"),
            Weight::Element(w) => (w, mesh.num_elements(), "elements"),
            Weight::Vertex(w) => (w, mesh.num_vertices(), "vertices"),
        };
        if vals.len() != need {
            return Err(format!("weight has {} values for {} {}", vals.len(), need, what));
        }
        if let Some(i) = vals.iter().position(|v| !v.is_finite()) {
            return Err(format!("weight value {i} is not finite"));
        }
        Ok(())
    }
}

/// The P1 matrices of one mesh state, values on a shared [`Pattern`].
#[derive(Debug, Clone)]
pub struct Matrices<const D: usize> {
    /// `|T|` per element.
    pub measure: Vec<f64>,
    /// `ν_T` per element.
    pub normal: Vec<Point<D>>,
    /// Local stiffness per element.
    pub local_stiffness: Vec<SMatrix<f64, D, D>>,
    /// Lumped mass `m_i = ∫_Γ φ_i`.
    pub lumped_mass: Vec<f64>,
    /// Lumped normal `N⃗_i = ∫_Γ φ_i ν` (area-weighted vertex normal, not unit).
    pub lumped_normal: Vec<Point<D>>,
    /// Lumped mass of the scalar rows, `m̂_i = |N⃗_i|² / m_i` (see `flow::LumpedSolver`).
    pub scalar_mass: Vec<f64>,
    /// Stiffness `A` (values on the pattern).
    pub stiffness: Vec<f64>,
    /// Consistent mass `M` (values on the pattern); empty unless assembled with
    /// [`Matrices::assemble_into`]`(.., true)`.
    pub mass: Vec<f64>,
}

impl<const D: usize> Matrices<D> {
    /// Assemble `A`, `M`, lumped `m` and `N⃗` for `mesh` on `pattern`.
    pub fn assemble(mesh: &Mesh<D>, pattern: &Pattern<D>) -> Self {
        let mut out = Matrices {
            measure: Vec::new(),
            normal: Vec::new(),
            local_stiffness: Vec::new(),
            lumped_mass: Vec::new(),
            lumped_normal: Vec::new(),
            scalar_mass: Vec::new(),
            stiffness: Vec::new(),
            mass: Vec::new(),
        };
        out.assemble_into(mesh, pattern, true);
        out
    }

    /// Refill `self` for `mesh` on `pattern`, reusing the allocations; the
    /// consistent mass only if `consistent_mass` (the lumped path does not need it).
    pub fn assemble_into(&mut self, mesh: &Mesh<D>, pattern: &Pattern<D>, consistent_mass: bool) {
        let nv = mesh.num_vertices();
        let reset = |v: &mut Vec<f64>, n: usize| {
            v.clear();
            v.resize(n, 0.0);
        };
        self.measure.clear();
        self.normal.clear();
        self.local_stiffness.clear();
        reset(&mut self.lumped_mass, nv);
        reset(&mut self.stiffness, pattern.nnz());
        reset(&mut self.mass, if consistent_mass { pattern.nnz() } else { 0 });
        self.lumped_normal.clear();
        self.lumped_normal.resize(nv, Point::<D>::zeros());
        let off = 1.0 / (D * (D + 1)) as f64;
        for (e, el) in mesh.elements().iter().enumerate() {
            let d = element_data(&mesh.element_points(e));
            let slots = &pattern.slots()[e];
            let share = d.measure / D as f64;
            let weighted_normal = d.normal * share;
            for a in 0..D {
                self.lumped_mass[el[a]] += share;
                self.lumped_normal[el[a]] += weighted_normal;
                for b in 0..D {
                    self.stiffness[slots[a][b]] += d.stiffness[(a, b)];
                }
                if consistent_mass {
                    for b in 0..D {
                        self.mass[slots[a][b]] += if a == b { 2.0 * off * d.measure } else { off * d.measure };
                    }
                }
            }
            self.measure.push(d.measure);
            self.normal.push(d.normal);
            self.local_stiffness.push(d.stiffness);
        }
        self.scalar_mass.clear();
        self.scalar_mass.extend(self.lumped_normal.iter().zip(&self.lumped_mass).map(|(n, m)| n.norm_squared() / m));
    }

    /// `A_α = Σ_T α_T K_T` on the pattern.
    pub fn weighted_stiffness(&self, mesh: &Mesh<D>, pattern: &Pattern<D>, alpha: &Weight) -> Vec<f64> {
        let mut v = vec![0.0; pattern.nnz()];
        for (e, el) in mesh.elements().iter().enumerate() {
            let w = alpha.on_element(e, el);
            pattern.add_local(&mut v, e, |a, b| w * self.local_stiffness[e][(a, b)]);
        }
        v
    }

    /// Consistent weighted mass `∫_Γ w φ_i φ_j` (element-average weight) on the pattern.
    pub fn weighted_mass(&self, mesh: &Mesh<D>, pattern: &Pattern<D>, w: &Weight) -> Vec<f64> {
        let mut v = vec![0.0; pattern.nnz()];
        for (e, el) in mesh.elements().iter().enumerate() {
            let we = w.on_element(e, el) * self.measure[e];
            pattern.add_local(&mut v, e, |a, b| mass_entry::<D>(we, a, b));
        }
        v
    }

    /// Consistent `N⃗_ij = ∫_Γ φ_i φ_j ν`, one value array per component of `ν`.
    pub fn consistent_normal(&self, mesh: &Mesh<D>, pattern: &Pattern<D>) -> [Vec<f64>; D] {
        let mut out: [Vec<f64>; D] = std::array::from_fn(|_| vec![0.0; pattern.nnz()]);
        for (e, _) in mesh.elements().iter().enumerate() {
            let slots = &pattern.slots()[e];
            for a in 0..D {
                for b in 0..D {
                    let m = mass_entry::<D>(self.measure[e], a, b);
                    for c in 0..D {
                        out[c][slots[a][b]] += m * self.normal[e][c];
                    }
                }
            }
        }
        out
    }

    /// `A⃗ X`: the stiffness matrix applied to the vertex positions, `#V × D`
    /// (`(A X)_i ≈ m_i κ_i ν_i`, Dziuk's `−Δ_Γ X = κ ν`).
    /// On periodic curves the positions are lifted per element (the period drops out).
    pub fn stiffness_times_positions(&self, mesh: &Mesh<D>, pattern: &Pattern<D>) -> Vec<Point<D>> {
        let mut out = vec![Point::<D>::zeros(); mesh.num_vertices()];
        if mesh.period().is_some() {
            for (e, el) in mesh.elements().iter().enumerate() {
                let p = mesh.element_points(e);
                for a in 0..D {
                    for b in 0..D {
                        out[el[a]] += p[b] * self.local_stiffness[e][(a, b)];
                    }
                }
            }
            return out;
        }
        let x = mesh.positions();
        for j in 0..pattern.size() {
            for k in pattern.col_ptr()[j]..pattern.col_ptr()[j + 1] {
                out[pattern.row_idx()[k]] += x[j] * self.stiffness[k];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere};

    #[test]
    fn constants_in_kernel_and_mass_totals() {
        let s = icosphere([0.0; 3], 1.0, 2).unwrap();
        let p = Pattern::new(s.num_vertices(), s.elements());
        let m = Matrices::assemble(&s, &p);
        let ones = vec![1.0; s.num_vertices()];
        let mut y = vec![0.0; s.num_vertices()];
        p.mul(&m.stiffness, &ones, &mut y);
        assert!(y.iter().all(|v| v.abs() < 1e-12));
        let total: f64 = m.mass.iter().sum();
        assert!((total - s.boundary_measure()).abs() < 1e-12);
        assert!((m.lumped_mass.iter().sum::<f64>() - total).abs() < 1e-12);
        // symmetric pattern and values
        for j in 0..p.size() {
            for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                let i = p.row_idx()[k];
                let r = &p.row_idx()[p.col_ptr()[i]..p.col_ptr()[i + 1]];
                let kk = p.col_ptr()[i] + r.binary_search(&j).unwrap();
                assert!((m.stiffness[k] - m.stiffness[kk]).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn regular_polygon_discrete_curvature_is_exact() {
        let c = circle([0.0, 0.0], 2.0, 50).unwrap();
        let p = Pattern::new(c.num_vertices(), c.elements());
        let m = Matrices::assemble(&c, &p);
        let ax = m.stiffness_times_positions(&c, &p);
        for i in 0..c.num_vertices() {
            let kappa = m.lumped_normal[i].dot(&ax[i]) / (m.lumped_mass[i] * m.lumped_mass[i]);
            // lumped normal of a regular polygon has length m_i cos(θ/2)
            let half = std::f64::consts::PI / 50.0;
            assert!((kappa - 0.5 * half.cos()).abs() < 1e-12, "{kappa}");
        }
    }
}
