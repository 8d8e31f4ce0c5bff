//! One pass of curve management over a whole mesh, short of topology: each loop
//! adapted and regularized on its own ([`manage_curve`]), or held in part or whole
//! ([`manage_curve_holding`], [`Hold`]: the loops a pass would make cross another
//! object's). The loops keep their order, that of the mesh's components.

use super::curve_loop::{desired_sizes, metrics, regularize_loop, size_bounds, Loop};
use super::curve_remesh::{adapt_loop, lifted_loop, rebuild};
use super::{CurveMesh, CurveRemeshSettings, MeshError, Point};

/// One pass of curve management short of topology: refinement/coarsening (if
/// `adapt`), then `sweeps` regularization sweeps towards the desired sizes (if
/// `adapt`, else equal lengths), with the lengths and turning angles of each loop
/// computed once. Returns the new mesh, `None` if nothing was to be done, and
/// whether the connectivity changed.
pub fn manage_curve(
    mesh: &CurveMesh,
    s: &CurveRemeshSettings,
    adapt: bool,
    sweeps: usize,
) -> Result<(Option<CurveMesh>, bool), MeshError> {
    manage_curve_holding(mesh, s, adapt, sweeps, &[])
}

/// How much of a pass [`manage_curve_holding`] makes on one loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Hold {
    /// The whole pass.
    #[default]
    Free,
    /// Only its segments shorter than a quarter of `h_min` collapsed (with
    /// `adapt`): a segment shrinking beside a contact would otherwise hold every
    /// step to a fraction of its length, and the collapse moves the loop by less
    /// than an eighth of `h_min`.
    Collapse,
    /// Only its segments shorter than `h_min/64` collapsed: a loop whose
    /// [`Hold::Collapse`] still crosses a neighbour it touches.
    CollapseTiny,
    /// Nothing.
    Whole,
}

/// [`manage_curve`] with loop `c` managed as `hold[c]` says (free beyond the
/// slice). Loops are numbered as the mesh's components
/// ([`Mesh::component_labels`](super::Mesh::component_labels): by their first
/// vertex), and the result keeps that order.
pub fn manage_curve_holding(
    mesh: &CurveMesh,
    s: &CurveRemeshSettings,
    adapt: bool,
    sweeps: usize,
    hold: &[Hold],
) -> Result<(Option<CurveMesh>, bool), MeshError> {
    if !adapt && sweeps == 0 {
        return Ok((None, false));
    }
    let x = mesh.positions();
    // meshes built from polylines store each loop as a run of vertices: no cycle
    // search, no gather, no scatter
    let runs = if mesh.period().is_none() { contiguous_loops(mesh) } else { None };
    let cycles = if runs.is_none() { mesh.cycles() } else { Vec::new() };
    let count = runs.as_ref().map_or(cycles.len(), Vec::len);
    let mut loops = Vec::with_capacity(count);
    let mut changed = false;
    for c in 0..count {
        let mut l = match &runs {
            Some(r) => Loop { p: x[r[c].clone()].to_vec(), shift: Point::<2>::zeros() },
            None => lifted_loop(mesh, &cycles[c]),
        };
        match hold.get(c).copied().unwrap_or_default() {
            Hold::Free => {}
            hold @ (Hold::Collapse | Hold::CollapseTiny) => {
                let min = if hold == Hold::Collapse { 0.25 } else { 1.0 / 64.0 } * s.h_min;
                if let Some(short) = adapt.then(|| l.collapse_short(min)).flatten() {
                    changed = true;
                    l = short;
                }
                loops.push(l);
                continue;
            }
            Hold::Whole => {
                loops.push(l);
                continue;
            }
        }
        let (mut len, mut beta) = metrics(&l);
        if adapt {
            if let Some(new) = adapt_loop(&l, &len, &beta, s) {
                changed = true;
                l = new;
                (len, beta) = metrics(&l);
            }
        }
        if sweeps > 0 {
            let hd = if adapt { desired_sizes(&len, &beta, s) } else { vec![1.0; l.len()] };
            regularize_loop(&mut l, &hd, sweeps, adapt.then(|| size_bounds(s)));
        }
        loops.push(l);
    }
    if changed {
        return rebuild(mesh, loops.into_iter().map(|l| l.p).collect(), false).map(|m| (Some(m), true));
    }
    // same connectivity: back to the mesh's own representatives
    if let Some(runs) = runs {
        let pos = if loops.len() == 1 { loops.pop().unwrap().p } else { loops.into_iter().flat_map(|l| l.p).collect() };
        debug_assert!(runs.last().is_some_and(|r| r.end == pos.len()));
        return Ok((Some(mesh.with_positions(pos)), false));
    }
    let mut pos = x.to_vec();
    for (cyc, l) in cycles.iter().zip(&loops) {
        if mesh.period().is_none() {
            for (&v, p) in cyc.iter().zip(&l.p) {
                pos[v] = *p;
            }
        } else {
            for (&v, p) in cyc.iter().zip(&l.p) {
                pos[v] = mesh.lift(*p, &x[v]);
            }
        }
    }
    Ok((Some(mesh.with_positions(pos)), false))
}

/// The loops of a closed curve mesh as vertex ranges, if every element `e` is
/// `[e, e + 1]` except the last of each loop, which closes it (the layout of meshes
/// built from polylines); `None` otherwise.
fn contiguous_loops(mesh: &CurveMesh) -> Option<Vec<std::ops::Range<usize>>> {
    let elements = mesh.elements();
    if elements.len() != mesh.num_vertices() || elements.is_empty() {
        return None;
    }
    let mut runs = Vec::new();
    let mut start = 0;
    for (e, &[a, b]) in elements.iter().enumerate() {
        if a != e {
            return None;
        }
        if b == start {
            runs.push(start..e + 1);
            start = e + 1;
        } else if b != e + 1 {
            return None;
        }
    }
    (start == elements.len()).then_some(runs)
}
