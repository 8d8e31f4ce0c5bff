//! P1 finite elements for the state and adjoint equations of shape design
//! (paper eqs. 7 and 42) on a [`BulkMesh`]:
//!
//! ```text
//! state:   −Δy = 0 in Ω,   y = 0 on Σ,   ∂_ν y = 1 on Γ
//! adjoint: −Δp = χ_D (y − z_g) in Ω,   p = 0 on Σ,   ∂_ν p = 0 on Γ
//! ```
//!
//! Both are solves with one [`DirichletLaplace`] (`K_ij = ∫_Ω ∇φ_i·∇φ_j`, Dirichlet
//! on `Σ`): one factorization, two solves. The data misfit `½∫_D (y − z_g)²` and the adjoint load
//! `∫_D (y − z_g) φ_i` use the degree-5 seven-point rule on every triangle of `D`
//! (the mesh conforms to `∂D`, so only the geometry of `∂D` is approximated).

use super::dirichlet::DirichletLaplace;
use super::mesh::{triangle_area, BulkMesh};
use super::BulkError;
use crate::geometry::Point;

/// Barycentric coordinates and weights (summing to 1) of the seven-point rule.
const RULE7: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_770;
    const B1: f64 = 0.470_142_064_105_115;
    const A2: f64 = 0.797_426_985_353_087;
    const B2: f64 = 0.101_286_507_323_456;
    const W1: f64 = 0.132_394_152_788_506;
    const W2: f64 = 0.125_939_180_544_827;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

/// The fields of one shape-design evaluation, at the vertices of the bulk mesh.
#[derive(Debug, Clone)]
pub struct DesignFields {
    pub y: Vec<f64>,
    pub p: Vec<f64>,
    /// `½ ∫_D (y − z_g)²`.
    pub misfit: f64,
}

/// Solves the state and adjoint problems for the target `z_g`.
pub fn solve_design_fields(bulk: &BulkMesh, target: &dyn Fn(Point<2>) -> f64) -> Result<DesignFields, BulkError> {
    let mesh = &bulk.mesh;
    let n = mesh.points.len();
    let laplace = DirichletLaplace::new(mesh, "bulk")?;

    // state: Neumann load ∫_Γ φ_i
    let mut load = vec![0.0; n];
    for &[a, b] in &bulk.curve_edges {
        let len = (mesh.points[b] - mesh.points[a]).norm();
        load[a] += 0.5 * len;
        load[b] += 0.5 * len;
    }
    let y = laplace.solve(load, None);
    check_finite("state", &y)?;

    // misfit and adjoint load on D
    let mut p = vec![0.0; n];
    let mut misfit = 0.0;
    for (t, _) in mesh.triangles.iter().zip(&bulk.in_control).filter(|(_, &c)| c) {
        let area = triangle_area(&mesh.points, t);
        let x = t.map(|i| mesh.points[i]);
        for (l, w) in RULE7 {
            let point = x[0] * l[0] + x[1] * l[1] + x[2] * l[2];
            let r = l[0] * y[t[0]] + l[1] * y[t[1]] + l[2] * y[t[2]] - target(point);
            misfit += 0.5 * w * area * r * r;
            for a in 0..3 {
                p[t[a]] += w * area * r * l[a];
            }
        }
    }
    let p = laplace.solve(p, None);
    check_finite("adjoint", &p)?;
    if !misfit.is_finite() {
        return Err(BulkError::Solver("the misfit ½∫_D (y − z_g)² is not finite (check the target)".into()));
    }
    Ok(DesignFields { y, p, misfit })
}

fn check_finite(what: &str, v: &[f64]) -> Result<(), BulkError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(BulkError::Solver(format!("the {what} solution is not finite at bulk vertex {i}"))),
        None => Ok(()),
    }
}

/// `∇φ_a` of the P1 basis functions on a counter-clockwise triangle of area `area`.
fn basis_gradients(p: &[Point<2>; 3], area: f64) -> [Point<2>; 3] {
    std::array::from_fn(|a| {
        let e = p[(a + 2) % 3] - p[(a + 1) % 3]; // edge opposite a, counter-clockwise
        Point::<2>::new(-e.y, e.x) / (2.0 * area)
    })
}

/// The exact gradient of the discrete functional `J_h = ½∫_D (y_h − z_g)² + γ|Γ_h|`
/// with respect to the positions of the curve's vertices (the first
/// `mesh.curve_vertices` bulk vertices), all other bulk vertices fixed, as in
/// [`BulkMesh::with_curve_positions`]; `y_h` and the adjoint `p_h` are those of
/// `fields`.
///
/// With the Lagrangian `L = J_h + ℓ(p) − a(y, p)`, `a(y, p) = ∫_Ω ∇y·∇p`,
/// `ℓ(p) = ∫_Γ p`, and the state and adjoint equations satisfied, `dJ_h = ∂_X L` at
/// fixed nodal values. Moving vertex `c` by `δ` moves the points of its triangles by
/// `φ_c δ`, and on a triangle `T` (where `∇y`, `∇p` are constant)
///
/// ```text
/// ∂_c ∫_T ∇y·∇p = |T| [(∇y·∇p) ∇φ_c − (∇φ_c·∇y) ∇p − (∇φ_c·∇p) ∇y],
/// ```
///
/// while `∂_c ∫_e p = t_e (p_c + p_d)/2` and `∂_c |e| = t_e` on a curve edge
/// `e = (c, d)` with `t_e = (X_c − X_d)/|e|`. `D` does not touch `Γ`, so the misfit
/// has no explicit dependence.
pub fn curve_sensitivity(bulk: &BulkMesh, fields: &DesignFields, gamma: f64) -> Vec<Point<2>> {
    let mesh = &bulk.mesh;
    let nc = mesh.curve_vertices;
    let mut grad = vec![Point::<2>::zeros(); nc];
    for t in mesh.triangles.iter().filter(|t| t.iter().any(|&v| v < nc)) {
        let p = t.map(|i| mesh.points[i]);
        let area = triangle_area(&mesh.points, t);
        let g = basis_gradients(&p, area);
        let gy: Point<2> = (0..3).map(|a| g[a] * fields.y[t[a]]).sum();
        let gp: Point<2> = (0..3).map(|a| g[a] * fields.p[t[a]]).sum();
        for a in (0..3).filter(|&a| t[a] < nc) {
            grad[t[a]] -= (g[a] * gy.dot(&gp) - gp * g[a].dot(&gy) - gy * g[a].dot(&gp)) * area;
        }
    }
    for &[a, b] in &bulk.curve_edges {
        let d = mesh.points[a] - mesh.points[b];
        let t = d / d.norm();
        let w = 0.5 * (fields.p[a] + fields.p[b]) + gamma;
        grad[a] += t * w;
        grad[b] -= t * w;
    }
    grad
}
