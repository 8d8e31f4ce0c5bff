//! The bulk domain of 2D shape design (paper §1.2, §4.3): the region `Ω` between the
//! moving curve `Γ` and the fixed outer boundary `Σ`, its triangulation (spade
//! constrained Delaunay with refinement, conforming to the control region `D`) and
//! the P1 state and adjoint solves; the Dirichlet Laplace solve that the stressed
//! film's field shares.

mod dirichlet;
mod domain;
mod laplace;
mod mesh;

pub use dirichlet::DirichletLaplace;
pub use domain::{DesignDomain, Polygon};
pub use laplace::{curve_sensitivity, solve_design_fields, DesignFields};
pub(crate) use mesh::triangulate;
pub use mesh::{triangle_area, BulkMesh, DomainMesh, MeshingOptions};

/// Errors of bulk meshing and solving.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BulkError {
    /// A fixed boundary is malformed; `what` names it (`outer`, `control.inner`, ...).
    #[error("{what}: {message}")]
    Domain { what: String, message: String },
    /// The curve leaves the admissible set (crosses `Σ` or `∂D`, enters `D`).
    #[error("inadmissible curve: {0}")]
    Inadmissible(String),
    #[error("bulk meshing failed: {0}")]
    Meshing(String),
    #[error("bulk solve failed: {0}")]
    Solver(String),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, Point};

    fn circle_polygon(what: &str, r: f64, n: usize) -> Polygon {
        Polygon::from_curve(what, circle([0.0, 0.0], r, n)).unwrap()
    }

    fn ring_domain(n: usize) -> DesignDomain {
        DesignDomain::new(
            circle_polygon("outer", 3.0, 3 * n),
            circle_polygon("control.inner", 2.0, 2 * n),
            circle_polygon("control.outer", 2.5, 5 * n / 2),
        )
        .unwrap()
    }

    /// Max nodal error of `y` against `log(3/|x|)` on the annulus 1 < |x| < 3.
    fn annulus_error(n: usize) -> (f64, BulkMesh, DesignFields) {
        let d = ring_domain(n);
        let opts = MeshingOptions::for_domain(&d, 2.0 * std::f64::consts::PI / n as f64);
        let mesh = BulkMesh::build(&d, &circle([0.0, 0.0], 1.0, n).unwrap(), &opts).unwrap();
        let f = solve_design_fields(&mesh, &|x: Point<2>| (3.0 / x.norm()).ln()).unwrap();
        let err = mesh.mesh.points.iter().zip(&f.y).map(|(x, y)| (y - (3.0 / x.norm()).ln()).abs()).fold(0.0, f64::max);
        (err, mesh, f)
    }

    #[test]
    fn annulus_mesh_is_conforming_and_graded() {
        let (_, mesh, _) = annulus_error(64);
        let (omega, control) = mesh.areas();
        let pi = std::f64::consts::PI;
        // polygonal areas are inscribed: slightly below the exact ones
        assert!((omega - 8.0 * pi).abs() < 0.01 * 8.0 * pi, "|Ω| = {omega}");
        assert!((control - 2.25 * pi).abs() < 0.01 * 2.25 * pi, "|D| = {control}");
        assert!(mesh.min_angle_deg() > 20.0, "min angle {}", mesh.min_angle_deg());
        assert_eq!(mesh.curve_edges.len(), 64);
        assert!(mesh.mesh.dirichlet.iter().filter(|&&b| b).count() >= 192);
    }

    #[test]
    fn state_converges_to_the_exact_annulus_solution() {
        let (e1, _, f1) = annulus_error(32);
        let (e2, _, f2) = annulus_error(64);
        let order = (e1 / e2).log2();
        assert!(e2 < 5e-3, "errors {e1:e} {e2:e}");
        assert!(order > 1.7, "order {order} ({e1:e} → {e2:e})");
        // y = z_g: the misfit and the adjoint vanish up to discretization error
        assert!(f2.misfit < 1e-5 && f2.misfit < f1.misfit, "misfit {} {}", f1.misfit, f2.misfit);
        let pmax = f2.p.iter().fold(0.0f64, |m, p| m.max(p.abs()));
        assert!(pmax < 1e-3, "max |p| {pmax}");
    }

    #[test]
    fn adjoint_of_a_constant_misfit_matches_the_radial_solution() {
        // z_g = y − 1 on D: −Δp = χ_D, p = 0 on |x| = 3, ∂_ν p = 0 on |x| = 1
        let d = ring_domain(96);
        let opts = MeshingOptions::for_domain(&d, 2.0 * std::f64::consts::PI / 96.0);
        let mesh = BulkMesh::build(&d, &circle([0.0, 0.0], 1.0, 96).unwrap(), &opts).unwrap();
        let f = solve_design_fields(&mesh, &|x: Point<2>| (3.0 / x.norm()).ln() - 1.0).unwrap();
        // radial solution: p(r) = c for r ≤ 2; −(r p')'/r = 1 on (2, 2.5); p(3) = 0
        // flux: r p'(r) = −(r² − 4)/2 on [2, 2.5], = −9/8 beyond
        let p_at = |r: f64| -> f64 {
            let outer = 9.0 / 8.0 * (3.0f64 / r.max(2.5)).ln();
            if r >= 2.5 {
                return outer;
            }
            let rr = r.max(2.0);
            outer + (2.5f64 * 2.5 - rr * rr) / 4.0 - 2.0 * (2.5 / rr).ln()
        };
        let err = mesh.mesh.points.iter().zip(&f.p).map(|(x, p)| (p - p_at(x.norm())).abs()).fold(0.0, f64::max);
        assert!(err < 5e-3 * p_at(1.0), "max error {err} vs p(1) = {}", p_at(1.0));
        let misfit_exact = 0.5 * 2.25 * std::f64::consts::PI;
        assert!((f.misfit - misfit_exact).abs() < 5e-3 * misfit_exact, "misfit {}", f.misfit);
    }
}
