//! The step with limits on where it may take each vertex ([`StepLimits`]; the
//! image's box of a segmentation), kept in its solve.
//!
//! The lumped step moves vertex `i` by `τ V_i N⃗_i / m_i`. For the L2 and H1
//! products its Schur system `S V = r` is the optimality condition of a quadratic
//! model of the step in `V`; a limit on a vertex's move bounds its `V_i`, and the
//! step becomes a bound-constrained problem, solved here by an active set: the
//! vertices whose move goes past their limit ([`StepLimits::fractions`] below 1)
//! are fixed at the fraction of `V_i` they may make (their rows and columns of `S`
//! replaced by the diagonal, their values moved to the right-hand side), and the
//! others are solved again, until no further vertex goes past its limit
//! ([`ACTIVE_SET_ROUNDS`] at most; the problem's
//! [`super::Problem::constrain_step`] takes what is left).
//!
//! Stopping the vertices of the free step at their limits after the solve
//! instead leaves their neighbours where a step with those vertices moving on
//! put them. Where a volume's surfaces lie flat on the image's box and are pushed
//! out of it (the nuclei volumes: a quarter of their vertices), their runs took
//! 1.5–1.8 times the steps that way (docs/segmentation-real-images.md).

use super::limits::StepLimits;
use super::schur::LumpedSolver;
use super::system::LinearSystem;
use super::FlowError;
use crate::geometry::Point;

/// The most solves of the active set after the free one.
pub const ACTIVE_SET_ROUNDS: usize = 6;

/// The step's `V` with each vertex's move kept within `limits` by an active set
/// (the module's documentation).
pub(super) fn solve_limited<const D: usize>(
    solver: &mut LumpedSolver,
    sys: &LinearSystem<'_, D>,
    limits: &dyn StepLimits<D>,
) -> Result<Vec<f64>, FlowError> {
    let mut v = solver.solve(sys)?;
    let (m, nn, x) = (&sys.matrices.lumped_mass, &sys.matrices.lumped_normal, sys.mesh.positions());
    // each vertex's move per unit V
    let w: Vec<Point<D>> = nn.iter().zip(m).map(|(n, m)| n * (sys.tau / m)).collect();
    let mut fixed: Vec<Option<f64>> = Vec::new();
    for _ in 0..ACTIVE_SET_ROUNDS {
        let to: Vec<Point<D>> = (0..v.len()).map(|i| x[i] + w[i] * v[i]).collect();
        let fractions = limits.fractions(x, &to);
        let mut added = false;
        for (i, &s) in fractions.iter().enumerate() {
            let free = fixed.get(i).is_none_or(|f| f.is_none());
            if free && s < 1.0 {
                if fixed.is_empty() {
                    fixed = vec![None; v.len()];
                }
                fixed[i] = Some(s.max(0.0) * v[i]);
                added = true;
            }
        }
        if !added {
            break;
        }
        v = solver.solve_fixed(sys, &fixed)?;
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flow::limits::Confinement;

    /// A circle pushed out of the box's right face by a balloon force: the
    /// limited step keeps every vertex in the box, stops some on the face, and
    /// solves the step's equations at the vertices left free, which the free step
    /// (clamped) does not.
    #[test]
    fn the_limited_step_solves_the_free_vertices_with_the_others_held() {
        use crate::fem::{csc_mul, Matrices, Pattern};
        use crate::flow::schur::assemble_l2_h1;
        use crate::flow::system::ProductWeights;
        let mesh = crate::geometry::circle([0.7, 0.5], 0.28, 64).unwrap();
        let pattern = Pattern::new(mesh.num_vertices(), mesh.elements());
        let matrices = Matrices::assemble(&mesh, &pattern);
        let ax = matrices.stiffness_times_positions(&mesh, &pattern);
        let n = mesh.num_vertices();
        let (g, f) = (vec![0.05; n], vec![-1.0; n]);
        let sys = LinearSystem {
            mesh: &mesh,
            pattern: &pattern,
            matrices: &matrices,
            ax: &ax,
            g: &g,
            f: &f,
            product: &ProductWeights::L2,
            tau: 0.05,
            bending: 0.0,
            limits: None,
        };
        let unit = Confinement::<2> { lo: Point::<2>::new(0.0, 0.0), hi: Point::<2>::new(1.0, 1.0) };
        let moved = |v: &[f64]| -> Vec<Point<2>> {
            let (m, nn) = (&matrices.lumped_mass, &matrices.lumped_normal);
            (0..n).map(|i| mesh.positions()[i] + nn[i] * (sys.tau * v[i] / m[i])).collect()
        };
        let free = LumpedSolver::new().solve(&sys).unwrap();
        assert!(moved(&free).iter().any(|y| y.x > 1.0 + 1e-3), "the free step leaves the box");
        let limited = solve_limited(&mut LumpedSolver::new(), &sys, &unit).unwrap();
        let to = moved(&limited);
        let on_face: Vec<bool> = to.iter().map(|y| (y.x - 1.0).abs() < 1e-12).collect();
        assert!(to.iter().all(|y| y.x <= 1.0 + 1e-12 && y.x >= 0.0 && y.y >= 0.0 && y.y <= 1.0));
        let held = on_face.iter().filter(|&&b| b).count();
        assert!(held > 2 && held < n / 2, "{held} of {n} on the face");
        let s = assemble_l2_h1(&sys);
        let mut sv = vec![0.0; n];
        csc_mul(pattern.col_ptr(), pattern.row_idx(), &s.values, &limited, &mut sv);
        let scale = s.rhs.iter().fold(0.0f64, |a, r| a.max(r.abs()));
        for i in (0..n).filter(|&i| !on_face[i]) {
            assert!((sv[i] - s.rhs[i]).abs() < 1e-9 * scale, "row {i}: {} against {}", sv[i], s.rhs[i]);
        }
        // the clamped free step does not solve them: its vertices next to the face
        // were moved as if their neighbours went on
        let mut clamped = free.clone();
        for i in 0..n {
            if on_face[i] {
                clamped[i] = limited[i];
            }
        }
        csc_mul(pattern.col_ptr(), pattern.row_idx(), &s.values, &clamped, &mut sv);
        let worst = (0..n).filter(|&i| !on_face[i]).map(|i| (sv[i] - s.rhs[i]).abs()).fold(0.0, f64::max);
        assert!(worst > 1e-3 * scale, "{worst}");
    }
}
