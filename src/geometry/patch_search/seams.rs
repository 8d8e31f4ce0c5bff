//! Seams: two disk patches whose boundary loops share exactly one arc. When both
//! are proved embedded over the same coordinate plane with the same orientation,
//! their union is too if the rest of the two loops (`P`, `Q` below) meet only at
//! the arc's ends: the union is a disk (two disks glued along one arc) whose
//! triangles all project with one strict orientation and whose boundary `P ∪ Q`
//! projects to a simple loop, so the degree argument of the patches applies to it
//! and no pair of the two patches needs a test.

use super::super::{bounding_box, boxes_meet, Point, Rect};
use super::certify::{flat, folds_back, loop_projects_simple, segments_meet};
use robust::{orient2d, Coord};

/// A seam of patches `a < b`: the part of `a`'s loop off the shared arc is `P`,
/// the `p_edges` edges from loop position `p_from` on (from the arc's end back
/// to its start), and that of `b`'s loop is `Q`, `q_edges` edges from `q_from`
/// (from the arc's start to its end): `P` then `Q` is the union's boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Seam {
    pub a: u32,
    pub b: u32,
    pub p_from: u32,
    pub p_edges: u32,
    pub q_from: u32,
    pub q_edges: u32,
}

impl Seam {
    /// Whether the union of the seam's patches is proved embedded at `x`, the
    /// patches having loops `loops` and triangles `triangles(q)`, and `planes`
    /// those over which each patch was: over their common plane, or when they
    /// differ, over the plane of one if the other's triangles project onto it
    /// with the same strict orientation.
    pub fn sealed<'a>(
        &self,
        x: &[Point<3>],
        loops: &[Option<&Vec<usize>>],
        triangles: impl Fn(usize) -> &'a [[usize; 3]],
        planes: &[Option<(usize, bool)>],
    ) -> bool {
        let (a, b) = (self.a as usize, self.b as usize);
        let (Some(la), Some(lb)) = (loops[a], loops[b]) else { return false };
        let (Some(pa), Some(pb)) = (planes[a], planes[b]) else { return false };
        let arcs = |k: usize| {
            let at = |v: usize| flat(k, &x[v]);
            (arc(la, self.p_from, self.p_edges, at), arc(lb, self.q_from, self.q_edges, at))
        };
        if pa == pb {
            let (p, q) = arcs(pa.0);
            return arcs_apart(&p, &q);
        }
        // the union's loop, P then Q without its ends
        let mut lp = arc(la, self.p_from, self.p_edges, |v| v);
        lp.extend(arc(lb, self.q_from, self.q_edges, |v| v).iter().skip(1).take(self.q_edges as usize - 1));
        [(pa, b), (pb, a)].into_iter().any(|((k, ccw), other)| {
            let at = |v: usize| flat(k, &x[v]);
            let sign = if ccw { 1.0 } else { -1.0 };
            triangles(other).iter().all(|&[u, v, w]| orient2d(at(u), at(v), at(w)) * sign > 0.0)
                && loop_projects_simple(x, &lp, k, ccw)
        })
    }
}

/// The seams of the patches with boundary loops `loops` (`None`: not a disk),
/// sorted by their pair; `across(u, v)` is the patch of the triangle using the
/// directed edge `v → u` (across a boundary edge `u → v`).
pub(super) fn seams(loops: &[Option<&Vec<usize>>], across: impl Fn(usize, usize) -> u32) -> Vec<Seam> {
    let mut found = Vec::new();
    let mut other = Vec::new();
    for (a, lp) in loops.iter().enumerate() {
        let Some(lp) = lp else { continue };
        let n = lp.len();
        other.clear();
        other.extend((0..n).map(|i| across(lp[i], lp[(i + 1) % n])));
        let mut starts: Vec<(u32, usize)> =
            (0..n).filter(|&i| other[i] != other[(i + n - 1) % n]).map(|i| (other[i], i)).collect();
        starts.sort_unstable();
        for (r, &(b, s)) in starts.iter().enumerate() {
            // one run of edges to b only, and b a disk patch after a
            let once = (r == 0 || starts[r - 1].0 != b) && starts.get(r + 1).is_none_or(|next| next.0 != b);
            let Some(lq) = loops.get(b as usize).copied().flatten() else { continue };
            if !once || b as usize <= a {
                continue;
            }
            let m = (s..s + n).take_while(|&i| other[i % n] == b).count();
            let nb = lq.len();
            // the arc runs backwards along b's loop: lq[t + i] = lp[s + m - i]
            let Some(t) = lq.iter().position(|&v| v == lp[(s + m) % n]) else { continue };
            if m >= n || m >= nb || (0..=m).any(|i| lq[(t + i) % nb] != lp[(s + m - i) % n]) {
                continue;
            }
            found.push(Seam {
                a: a as u32,
                b,
                p_from: ((s + m) % n) as u32,
                p_edges: (n - m) as u32,
                q_from: ((t + m) % nb) as u32,
                q_edges: (nb - m) as u32,
            });
        }
    }
    found.sort_unstable();
    found
}

/// The points of `lp` from position `from` on, `edges + 1` of them (cyclically).
pub(super) fn arc<T: Copy>(lp: &[usize], from: u32, edges: u32, at: impl Fn(usize) -> T) -> Vec<T> {
    let n = lp.len();
    (0..=edges as usize).map(|i| at(lp[(from as usize + i) % n])).collect()
}

/// Whether the open polylines `p` and `q`, `p` ending where `q` starts and `q`
/// ending where `p` starts, form a simple loop, each being simple: no edge of
/// one meets an edge of the other but at the two junctions, where consecutive
/// edges meet at their common corner only (decided exactly).
pub(super) fn arcs_apart(p: &[Coord<f64>], q: &[Coord<f64>]) -> bool {
    let (np, nq) = (p.len().saturating_sub(1), q.len().saturating_sub(1));
    if np == 0 || nq == 0 || np + nq < 3 {
        return false;
    }
    let box_of = |pts: &[Coord<f64>]| bounding_box(pts.iter().map(|c| [c.x, c.y]));
    let (pbox, qbox) = (box_of(p), box_of(q));
    // the edges of each inside the other's box
    let near = |pts: &[Coord<f64>], other: &Rect| -> Vec<(usize, Rect)> {
        (0..pts.len() - 1).map(|i| (i, box_of(&pts[i..i + 2]))).filter(|(_, b)| boxes_meet(b, other)).collect()
    };
    let (near_p, near_q) = (near(p, &qbox), near(q, &pbox));
    for &(i, bi) in &near_p {
        for &(j, bj) in &near_q {
            if !boxes_meet(&bi, &bj) {
                continue;
            }
            let hit = if i + 1 == np && j == 0 {
                folds_back(p[i], p[i + 1], q[1])
            } else if j + 1 == nq && i == 0 {
                folds_back(q[j], q[j + 1], p[1])
            } else {
                segments_meet(p[i], p[i + 1], q[j], q[j + 1])
            };
            if hit {
                return false;
            }
        }
    }
    true
}
