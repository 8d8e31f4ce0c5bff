//! The acceptance rules of a trial step, one function per rule, each returning a
//! [`Verdict`]: accept, or retry with a shorter `τ` for a [`Rejection`]. The driver
//! applies them in the order of the module documentation of [`super::driver`]:
//! geometric control, tangling, conservation, intersections, then the energy
//! (backtracking).
//! Below `τ_min`, [`stop_below_tau_min`] decides between `tau_min` and `converged`.

use super::intersections::new_intersection;
use super::report::{Rejection, StopReason};
use crate::geometry::{degenerate_measure, simplex, Mesh, PatchSearch};

/// What a rule says about a trial step of size `τ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Verdict {
    Accept,
    /// Try again with this `τ`.
    Retry {
        tau: f64,
        rejection: Rejection,
    },
}

/// The longest step the geometric control (paper §4.1) allows, from a trial step
/// of length `tau` that moved `old` to `new`: with the displacements `d = τ V⃗`,
/// `ratio = max_T |d(z_a) − d(z_b)|/h_T` stays at most `ε` up to `τ ε / ratio`;
/// `None` without step control (or without any relative motion). The
/// displacements are those of the step as taken, after the problem's constraints:
/// a vertex held against the image's box or another object's territory pushes
/// without moving, and does not shorten the step.
pub(super) fn motion_limit<const D: usize>(old: &Mesh<D>, new: &Mesh<D>, tau: f64, eps: Option<f64>) -> Option<f64> {
    let eps = eps?;
    let ratio = relative_motion(old, new);
    (ratio > 0.0).then(|| tau * eps / ratio)
}

/// Geometric control: a step longer than its [`motion_limit`] (its ratio above
/// `ε`) is retried with `min(0.9 · limit, τ/2)`, that is `τ · min(0.9 ε/ratio, ½)`.
pub(super) fn step_control(tau: f64, limit: Option<f64>) -> Verdict {
    match limit {
        Some(limit) if tau > limit => {
            Verdict::Retry { tau: (0.9 * limit).min(0.5 * tau), rejection: Rejection::StepControl }
        }
        _ => Verdict::Accept,
    }
}

/// Tangling: an element of `new` that degenerated or flipped against `old` halves `τ`.
pub(super) fn tangling<const D: usize>(old: &Mesh<D>, new: &Mesh<D>, tau: f64) -> Verdict {
    match tangled(old, new) {
        Some(e) => {
            trace_tangle(old, new, e, tau);
            Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::Tangled }
        }
        None => Verdict::Accept,
    }
}

/// Intersections (surfaces): a trial surface on which two triangles that share no
/// vertex meet (two components passing through each other, or one through
/// itself), at its end or along a long step ([`new_intersection`]), and did not
/// already meet in `old` halves `τ`. No new intersection is ever accepted; a
/// state that starts with touching parts (a segmentation's objects split at a
/// neck) may keep them. A run whose surfaces come into contact ends at `tau_min`
/// with this rejection as its cause, on the last state before the contact,
/// unless they merge.
pub(super) fn intersection<const D: usize>(
    old: &Mesh<D>,
    new: &Mesh<D>,
    tau: f64,
    search: &mut PatchSearch,
) -> Verdict {
    match new_intersection(old, new, search) {
        Some((a, b)) => {
            tracing::debug!(a, b, tau, "trial surface intersects");
            Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::Intersection }
        }
        None => Verdict::Accept,
    }
}

/// Conservation (`H⁻¹` flows): a relative change of the enclosed measure from `a0`
/// to `a1` above `tolerance` halves `τ`, down to `4 τ_min` (a fresh topological
/// change leaves corners that need a few very short steps; below that the step is
/// taken anyway).
pub(super) fn conservation(a0: f64, a1: f64, tolerance: Option<f64>, tau: f64, tau_min: f64) -> Verdict {
    match tolerance {
        Some(tol) if (a1 - a0).abs() > tol * a0.abs() && tau > 4.0 * tau_min => {
            Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::Conservation }
        }
        _ => Verdict::Accept,
    }
}

/// Backtracking (paper §3.2): a trial energy above the current one halves `τ` when
/// backtracking is on; `+∞` (an inadmissible shape) does so even when it is off.
pub(super) fn energy(current: f64, trial: f64, backtracking: bool, tau: f64) -> Verdict {
    if trial == f64::INFINITY {
        return Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::Inadmissible };
    }
    if backtracking && trial > current {
        return Verdict::Retry { tau: 0.5 * tau, rejection: Rejection::EnergyIncrease };
    }
    Verdict::Accept
}

/// The stop when `τ` fell below `τ_min`: `converged` when the last trials were
/// rejected for raising `J` by no more than `tolerance·|J|` (the state is
/// stationary to the tolerance: rounding and quadrature of `J`, not a failure of
/// the flow), else `tau_min`.
pub(super) fn stop_below_tau_min(
    last: Option<Rejection>,
    smallest_rise: f64,
    tolerance: f64,
    energy: f64,
) -> StopReason {
    let stationary = tolerance > 0.0 && smallest_rise <= tolerance * energy.abs();
    if last == Some(Rejection::EnergyIncrease) && stationary {
        StopReason::Converged
    } else {
        StopReason::TauMin
    }
}

/// Whether an accepted step of length `tau` is judged for convergence (the
/// relative-change test of non-physical flows), and the settled `τ` after it.
/// A step is *natural* when the flow's own limits set its `τ`: it was not cut
/// short by a tangled trial, and it was either not `growing` (doubling back
/// towards `τ_spec` after a short step) or `limited` by the step control or
/// backtracking. A natural step is judged and its `τ` becomes the settled one; a
/// growing step is judged once it is at least half the settled `τ`; a tangled
/// one never: it changes `J` little because it is short.
pub(super) fn judged_step(tau: f64, settled: f64, tangled: bool, growing: bool, limited: bool) -> (bool, f64) {
    if tangled {
        return (false, settled);
    }
    if !growing || limited {
        return (true, tau);
    }
    (tau >= 0.5 * settled, settled)
}

/// Whether the last judged step (the last two of `recent`, the recorded energies
/// after mesh management) changed `J` by at most `tolerance·|J|`: the relative-change
/// test of non-physical flows stops a run only on the second small step in a row.
pub(super) fn last_change_small(recent: &[f64], tolerance: f64) -> bool {
    match recent {
        [.., a, b] => tolerance > 0.0 && (a - b).abs() <= tolerance * a.abs(),
        _ => false,
    }
}

/// The judged steps over which the recorded energy is compared
/// ([`stationary_over_window`]): a multiple of 2 and 3, so that a state that
/// alternates between two or three energies is compared with itself.
pub(super) const WINDOW: usize = 6;

/// Whether the recorded energies (after mesh management) at the ends of the last
/// [`WINDOW`] + 1 judged steps (`recent`, oldest first) end within
/// `tolerance·|J|` of where they began: each step may lower `J` by more than the
/// tolerance while the mesh management after it (tangential regularization,
/// splits and collapses, a contact's held vertices) raises it back by as much,
/// the state staying where it is or cycling through a few.
pub(super) fn stationary_over_window(recent: &[f64], tolerance: f64) -> bool {
    match (recent.first(), recent.last()) {
        (Some(first), Some(last)) if recent.len() == WINDOW + 1 && tolerance > 0.0 => {
            (first - last).abs() <= tolerance * first.abs()
        }
        _ => false,
    }
}

/// `max_T max_{a,b ∈ T} |d(z_a) − d(z_b)| / h_T` on `old`: the relative motion of
/// the vertex displacements `d` from `old` to `new`.
fn relative_motion<const D: usize>(old: &Mesh<D>, new: &Mesh<D>) -> f64 {
    let (x0, x1) = (old.positions(), new.positions());
    let d = |v: usize| x1[v] - x0[v];
    let mut worst: f64 = 0.0;
    for (e, el) in old.elements().iter().enumerate() {
        let h = simplex::diameter(&old.element_points(e));
        for a in 0..D {
            for b in a + 1..D {
                worst = worst.max((d(el[a]) - d(el[b])).norm() / h);
            }
        }
    }
    worst
}

/// First element that degenerated (relative to `old`, or below what validation
/// accepts: [`degenerate_measure`]) or flipped between `old` and `new`.
pub(super) fn tangled<const D: usize>(old: &Mesh<D>, new: &Mesh<D>) -> Option<usize> {
    let tiny = degenerate_measure(new.positions());
    (0..old.num_elements()).find(|&e| {
        let (m0, n0) = old.element_geometry(e);
        let (m1, n1) = new.element_geometry(e);
        !(m1 > 1e-12 * m0) || no_measure(m1, tiny) || n0.dot(&n1) <= 0.0
    })
}

/// A measure `m` at or below `tiny` ([`degenerate_measure`]), or not finite.
fn no_measure(m: f64, tiny: f64) -> bool {
    !(m > tiny) || !m.is_finite()
}

/// The first element of `mesh` of no measure (below [`degenerate_measure`] of its
/// extent, or not finite), if any: a state the flow cannot assemble.
pub(super) fn degenerate<const D: usize>(mesh: &Mesh<D>) -> Option<usize> {
    let tiny = degenerate_measure(mesh.positions());
    (0..mesh.num_elements()).find(|&e| no_measure(mesh.element_geometry(e).0, tiny))
}

/// At debug level, the tangled element `e` of a trial step: its measure before
/// and after, the cosine of its turn and its edge lengths (the diagnosis of a
/// run that ends at `tau_min` on tangling).
fn trace_tangle<const D: usize>(old: &Mesh<D>, new: &Mesh<D>, e: usize, tau: f64) {
    if !tracing::enabled!(tracing::Level::DEBUG) {
        return;
    }
    let ((before, n0), (after, n1)) = (old.element_geometry(e), new.element_geometry(e));
    let x = old.element_points(e);
    let edges: Vec<f64> = (0..D).map(|k| (x[(k + 1) % D] - x[k]).norm()).collect();
    tracing::debug!(element = e, tau, before, after, turn = n0.dot(&n1), ?edges, "tangled");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, Point};

    fn retried(v: Verdict) -> Option<(f64, Rejection)> {
        match v {
            Verdict::Accept => None,
            Verdict::Retry { tau, rejection } => Some((tau, rejection)),
        }
    }

    /// Over a window: steady descent goes on, and so does a slow creep above the
    /// tolerance; a state that stays put, alternates between two or three energies
    /// or comes back to where it was is stationary.
    #[test]
    fn stationary_over_a_window_of_judged_steps() {
        let tol = 1e-6;
        let descent: Vec<f64> = (0..=WINDOW).map(|k| 1.0 - 1e-5 * k as f64).collect();
        assert!(!stationary_over_window(&descent, tol));
        assert!(!stationary_over_window(&descent[..WINDOW], tol), "a window not yet full");
        let creeping: Vec<f64> = (0..=WINDOW).map(|k| 1.0 + 1e-5 * k as f64).collect();
        assert!(!stationary_over_window(&creeping, tol));
        let still: Vec<f64> = (0..=WINDOW).map(|k| 1.0 + 1e-8 * k as f64).collect();
        assert!(stationary_over_window(&still, tol));
        assert!(!stationary_over_window(&still, 0.0), "tolerance 0 disables");
        for period in [2, 3] {
            for phase in 0..period {
                let cycle: Vec<f64> = (0..=WINDOW).map(|k| 1.0 + 1e-4 * ((k + phase) % period) as f64).collect();
                assert!(stationary_over_window(&cycle, tol), "period {period}, phase {phase}");
            }
        }
        let back = [1.0, 0.99, 0.98, 0.99, 0.995, 0.999, 1.0];
        assert!(stationary_over_window(&back, tol));
    }

    /// A small step counts towards convergence only after a small one: the
    /// recorded energies of a run whose steps alternate between a large decrease
    /// and next to none (an overshooting step) never qualify.
    #[test]
    fn a_small_step_stops_only_after_another() {
        let tol = 1e-6;
        assert!(!last_change_small(&[], tol) && !last_change_small(&[1.0], tol), "no step recorded yet");
        assert!(last_change_small(&[1.0, 2.0, 2.0 - 1e-7], tol));
        // the nuclei image's last steps before the rule: −1.4e-7, −4.7e-7, +1.5e-8,
        // −3.6e-7 at J ≈ 6.49e-3, where the tolerance allows 6.5e-9
        let alternating = [6.4926007e-3, 6.4921224e-3, 6.4919870e-3, 6.4915188e-3, 6.4915338e-3, 6.4911742e-3];
        assert!(!last_change_small(&alternating, tol));
        assert!(!last_change_small(&alternating[..5], 1e-6), "a step of +1.5e-8 is above 6.5e-9");
        assert!(last_change_small(&alternating[..5], 1e-5));
        assert!(!last_change_small(&[1.0, 1.0], 0.0), "tolerance 0 disables");
    }

    /// The control compares `τ` times the largest relative motion with `ε`: a
    /// uniform translation moves nothing relative, a stretch does.
    #[test]
    fn step_control_limits_the_relative_motion() {
        let mesh = circle([0.0, 0.0], 1.0, 64).unwrap();
        let shift = vec![Point::<2>::new(1.0, 0.0); 64];
        let moved = |v: &[Point<2>]| mesh.with_positions(mesh.positions().iter().zip(v).map(|(x, v)| x + v).collect());
        // a translation moves nothing relative (up to the rounding of the positions)
        assert!(motion_limit(&mesh, &moved(&shift), 1.0, Some(0.5)).is_none_or(|l| l > 1e12));
        assert_eq!(step_control(10.0, None), Verdict::Accept);
        let stretch: Vec<Point<2>> = mesh.positions().iter().map(|p| p * 2.0).collect();
        // relative motion of a stretch: |2(x_a − x_b)|/|x_a − x_b| = 2, so τ ≤ ε/2
        let limit = motion_limit(&mesh, &moved(&stretch), 1.0, Some(0.5)).unwrap();
        let half = motion_limit(&mesh, &moved(&stretch), 0.5, Some(0.5)).unwrap();
        assert!((half - 0.125).abs() < 1e-12, "the same displacement in half the time: {half}");
        assert!((limit - 0.25).abs() < 1e-12, "{limit}");
        assert_eq!(step_control(0.2, Some(limit)), Verdict::Accept);
        let (tau, why) = retried(step_control(1.0, Some(limit))).unwrap();
        assert_eq!(why, Rejection::StepControl);
        assert!((tau - 0.9 * 0.5 / 2.0).abs() < 1e-12, "{tau}"); // τ · 0.9 ε/ratio
        let (tau, _) = retried(step_control(0.3, Some(limit))).unwrap();
        assert!((tau - 0.15).abs() < 1e-12, "at least halved: {tau}");
        assert_eq!(motion_limit(&mesh, &moved(&stretch), 1.0, None), None);
    }

    /// A circle blown up by a pressure against walls that hold every vertex where
    /// it is (as an image's box or another object's territory holds a
    /// segmentation's vertices): its velocity alone would cut the step to about
    /// 1e-3, but nothing moves, so the step is taken at `flow.tau`.
    #[test]
    fn a_held_vertex_does_not_shorten_the_step() {
        use crate::flow::{Flow, FlowSettings, Problem, ProblemError, ShapeGradient, SurfaceState};
        struct Walled;
        impl Problem<2> for Walled {
            fn name(&self) -> &'static str {
                "walled"
            }
            fn energy(&mut self, mesh: &Mesh<2>) -> Result<f64, ProblemError> {
                Ok(mesh.boundary_measure() - 100.0 * mesh.enclosed_measure())
            }
            fn shape_gradient(&mut self, state: &SurfaceState<'_, 2>) -> Result<ShapeGradient, ProblemError> {
                let n = state.mesh.num_vertices();
                Ok(ShapeGradient { g: vec![1.0; n], f: vec![-100.0; n], aux: Vec::new() })
            }
            fn constrain_step(&self, current: &Mesh<2>, _: Mesh<2>, _: &mut crate::geometry::PatchSearch) -> Mesh<2> {
                current.clone()
            }
        }
        let mesh = circle([0.0, 0.0], 0.25, 64).unwrap();
        let settings = FlowSettings { tau: 1e-2, ..FlowSettings::default() };
        let mut problem = Walled;
        let mut flow = Flow::new(&mut problem, mesh.clone(), settings).unwrap();
        let report = flow.step().unwrap();
        assert!(report.accepted);
        assert_eq!(report.rejected, None, "{report:?}");
        assert_eq!(flow.progress().tau, 1e-2);
        assert_eq!(flow.mesh().positions(), mesh.positions());
        // what the unconstrained velocity V = 100 − κ would have allowed
        let v: Vec<Point<2>> = mesh.positions().iter().map(|p| p * (96.0 / 0.25)).collect();
        let moved = mesh.with_positions(mesh.positions().iter().zip(&v).map(|(x, v)| x + v).collect());
        let limit = motion_limit(&mesh, &moved, 1.0, Some(0.5)).unwrap();
        assert!(limit < 2e-3, "{limit}");
    }

    /// A mirrored curve (every segment flipped) and a collapsed one tangle; a
    /// slightly shrunk one does not.
    #[test]
    fn tangling_catches_flips_and_degenerate_elements() {
        let mesh = circle([0.0, 0.0], 1.0, 32).unwrap();
        let shrunk = mesh.with_positions(mesh.positions().iter().map(|p| p * 0.9).collect());
        assert_eq!(tangling(&mesh, &shrunk, 1.0), Verdict::Accept);
        let mirrored = mesh.with_positions(mesh.positions().iter().map(|p| Point::<2>::new(-p.x, p.y)).collect());
        assert_eq!(retried(tangling(&mesh, &mirrored, 1.0)), Some((0.5, Rejection::Tangled)));
        let collapsed = mesh.with_positions(mesh.positions().iter().map(|p| p * 1e-14).collect());
        assert!(tangled(&mesh, &collapsed).is_some());
    }

    #[test]
    fn conservation_halves_tau_down_to_four_tau_min() {
        assert_eq!(conservation(1.0, 1.0 + 1e-7, Some(1e-6), 1e-3, 1e-10), Verdict::Accept);
        assert_eq!(
            retried(conservation(1.0, 1.0 + 1e-5, Some(1e-6), 1e-3, 1e-10)),
            Some((5e-4, Rejection::Conservation))
        );
        assert_eq!(conservation(1.0, 1.0 + 1e-5, Some(1e-6), 3e-10, 1e-10), Verdict::Accept);
        assert_eq!(conservation(1.0, 2.0, None, 1e-3, 1e-10), Verdict::Accept);
    }

    #[test]
    fn energy_rule_backtracks_rises_and_always_rejects_inadmissible_shapes() {
        assert_eq!(energy(1.0, 0.9, true, 1.0), Verdict::Accept);
        assert_eq!(retried(energy(1.0, 1.1, true, 1.0)), Some((0.5, Rejection::EnergyIncrease)));
        assert_eq!(energy(1.0, 1.1, false, 1.0), Verdict::Accept);
        assert_eq!(retried(energy(1.0, f64::INFINITY, false, 1.0)), Some((0.5, Rejection::Inadmissible)));
        assert!(Rejection::Inadmissible.is_backtrack() && !Rejection::Tangled.is_backtrack());
    }

    /// The 3D nuclei volume's run: a step cut short by tangling (τ 1e-6 → 2e-9) and
    /// the steps doubling back from it are not taken for convergence until τ is
    /// back to half the settled one; a step that step control or backtracking
    /// limited, or a full one, is judged and settles τ.
    #[test]
    fn short_steps_after_tangling_are_not_judged() {
        assert_eq!(judged_step(1e-3, 0.0, false, false, false), (true, 1e-3));
        assert_eq!(judged_step(2e-9, 1e-3, true, true, true), (false, 1e-3));
        assert_eq!(judged_step(4e-9, 1e-3, false, true, false), (false, 1e-3));
        assert_eq!(judged_step(6e-4, 1e-3, false, true, false), (true, 1e-3));
        assert_eq!(judged_step(1e-5, 1e-3, false, true, true), (true, 1e-5));
        assert_eq!(judged_step(0.1, 1e-3, true, false, true), (false, 1e-3));
    }

    /// Below τ_min: stationary to the tolerance only after energy rises no larger
    /// than `tolerance·|J|`; any other last rejection is a `tau_min` stop.
    #[test]
    fn below_tau_min_a_tiny_rise_is_convergence() {
        let e = Some(Rejection::EnergyIncrease);
        assert_eq!(stop_below_tau_min(e, 1e-9, 1e-6, 2.0), StopReason::Converged);
        assert_eq!(stop_below_tau_min(e, 1e-3, 1e-6, 2.0), StopReason::TauMin);
        assert_eq!(stop_below_tau_min(e, 1e-9, 0.0, 2.0), StopReason::TauMin);
        assert_eq!(stop_below_tau_min(Some(Rejection::StepControl), 0.0, 1e-6, 2.0), StopReason::TauMin);
    }
}
