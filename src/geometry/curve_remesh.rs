//! Mesh management for curves (paper §4.1): tangential regularization that keeps the
//! enclosed area exactly, and refinement/coarsening driven by `h_S β_S` (`β_S` the
//! turning angle at vertex `S`); topological changes are in `curve_topology`. Pure
//! functions from a curve mesh to a curve mesh.

use super::curve_loop::{desired_sizes, metrics, regularize_loop, size_bounds, Loop};
use super::curves::{from_polylines, from_polylines_trusted};
use super::{CurveMesh, Mesh, MeshError, Point};

/// Parameters of curve mesh management.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveRemeshSettings {
    /// Refine where `h_S β_S > epsilon`, coarsen where `h_S β_S < epsilon / 8`.
    pub epsilon: f64,
    /// Segment lengths are kept within `[h_min, h_max]` where the curvature allows.
    pub h_min: f64,
    pub h_max: f64,
    /// Components with `|area|` below this are dropped after a topological change.
    pub min_area: f64,
    /// Area-conserving flows (`H^{-1}`): after refinement/coarsening each component
    /// is offset along its normals to keep its area (see `keep_area`).
    pub keep_area: bool,
    /// After a topological change, drop clockwise closed loops: pockets of the
    /// exterior that a curve closed around are filled (shape design, where such a
    /// pocket of `Ω` would be cut off from `Σ`).
    pub fill_pockets: bool,
    /// Different components never merge: the loops that a management pass would
    /// make cross another component only have their tiny segments collapsed in
    /// that pass, or are left as they are ([`Hold`](super::Hold)), and the others are managed
    /// (segmentation: touching objects stay the objects they are).
    pub keep_apart: bool,
}

fn loops_of(mesh: &CurveMesh) -> Vec<Loop> {
    mesh.cycles().iter().map(|c| lifted_loop(mesh, c)).collect()
}

/// A curve mesh from polylines, periodic like `like`.
pub(super) fn rebuild(like: &CurveMesh, parts: Vec<Vec<Point<2>>>, validate: bool) -> Result<CurveMesh, MeshError> {
    match like.period() {
        None if validate => from_polylines(parts),
        None => from_polylines_trusted(parts),
        Some(l) => {
            if parts.iter().all(|p| p.is_empty()) {
                return Err(MeshError::Empty);
            }
            let mut positions = Vec::new();
            let mut elements = Vec::new();
            for part in parts {
                let (base, n) = (positions.len(), part.len());
                positions.extend(part.into_iter().map(|mut q| {
                    q.x = q.x.rem_euclid(l);
                    q
                }));
                elements.extend((0..n).map(|k| [base + k, base + (k + 1) % n]));
            }
            if validate {
                Mesh::new_periodic(positions, elements, l)
            } else {
                Ok(Mesh::periodic_trusted(positions, elements, l))
            }
        }
    }
}

/// Tangential regularization: `sweeps` Gauss–Seidel sweeps moving every vertex
/// parallel to the chord of its neighbours towards the point that splits the chord in
/// the ratio of the desired sizes (equal lengths when `sizes` is `None`). The enclosed
/// area is linear in each single vertex with the others fixed and its gradient
/// `½ J (X_{i+1} − X_{i−1})` is normal to that chord, so every move keeps the area
/// exactly (up to round-off).
pub fn regularize_curve(mesh: &CurveMesh, sweeps: usize, sizes: Option<&CurveRemeshSettings>) -> CurveMesh {
    let mut pos = mesh.positions().to_vec();
    for cyc in &mesh.cycles() {
        let mut l = lifted_loop(mesh, cyc);
        let start = l.p.clone();
        let hd = match sizes {
            Some(s) => {
                let (len, beta) = metrics(&l);
                desired_sizes(&len, &beta, s)
            }
            None => vec![1.0; l.len()],
        };
        regularize_loop(&mut l, &hd, sweeps, sizes.map(size_bounds));
        // back to the mesh's own representatives (lifting shifted some by periods)
        for ((&v, p), p0) in cyc.iter().zip(&l.p).zip(&start) {
            pos[v] += p - p0;
        }
    }
    mesh.with_positions(pos)
}

/// The cycle `cyc` of `mesh` as a loop lifted vertex by vertex.
pub(super) fn lifted_loop(mesh: &CurveMesh, cyc: &[usize]) -> Loop {
    let x = mesh.positions();
    let mut p: Vec<Point<2>> = Vec::with_capacity(cyc.len());
    if mesh.period().is_none() {
        p.extend(cyc.iter().map(|&v| x[v]));
        return Loop { p, shift: Point::<2>::zeros() };
    }
    for &v in cyc {
        let q = match p.last() {
            Some(prev) => mesh.lift(x[v], prev),
            None => x[v],
        };
        p.push(q);
    }
    let shift = mesh.lift(p[0], p.last().unwrap()) - p[0];
    Loop { p, shift }
}

/// Flat vertices are removed only where the merged segment stays below this times
/// `h_max`, the largest size the regularization aims at.
const MERGED_MAX: f64 = 0.8;

/// Refinement and coarsening. A segment is split (at the four-point subdivision
/// point, which lies on a smooth curve through the neighbours) when it is longer
/// than `h_max`, or when `h β > ε` at one of its ends and both halves stay above
/// `h_min`; a vertex is removed when a neighbouring segment is shorter than `h_min`
/// and the merged segment stays below `h_max`, or when `h β < ε/8` and the merged
/// segment stays below `0.8 h_max` (the margin of `desired_sizes`). Returns `None`
/// if nothing changed.
pub fn adapt_curve(mesh: &CurveMesh, s: &CurveRemeshSettings) -> Result<Option<CurveMesh>, MeshError> {
    let mut changed = false;
    let mut out = Vec::new();
    for l in loops_of(mesh) {
        let (len, beta) = metrics(&l);
        match adapt_loop(&l, &len, &beta, s) {
            Some(new) => {
                changed = true;
                out.push(new.p);
            }
            None => out.push(l.p),
        }
    }
    if !changed {
        return Ok(None);
    }
    rebuild(mesh, out, false).map(Some)
}

/// [`adapt_curve`] on one loop, given its segment lengths and turning angles.
pub(super) fn adapt_loop(l: &Loop, len: &[f64], beta: &[f64], s: &CurveRemeshSettings) -> Option<Loop> {
    let n = l.len();
    if !may_adapt(len, beta, s) {
        return None;
    }
    let before = |i: usize| if i == 0 { n - 1 } else { i - 1 };
    // coarsening: never two neighbours in one pass, keep at least 8 vertices
    let mut keep = vec![true; n];
    let (mut removed, mut short_removed) = (0, 0);
    for i in 0..n {
        if n - removed <= 8 || !keep[before(i)] {
            continue;
        }
        let (lp, li) = (len[before(i)], len[i]);
        let short = li.min(lp) < s.h_min;
        let flat = beta[i] * li.max(lp) < s.epsilon / 8.0;
        // a flat vertex goes only if the merged segment keeps the sizes' margin
        // below h_max, or a little stretching splits it again at the next step
        let room = if short { s.h_max } else { MERGED_MAX * s.h_max };
        if (short || flat) && li + lp <= room && (i + 1 < n || keep[0]) {
            keep[i] = false;
            removed += 1;
            short_removed += usize::from(short);
        }
    }
    // flat vertices cost but do no harm: they are removed in batches, once they are
    // 1/32 of the loop, so that a slowly flattening curve is not re-meshed (new
    // connectivity, new sparsity pattern) at every step
    if short_removed == 0 && removed < n.div_ceil(32) {
        keep.fill(true);
        removed = 0;
    }
    let coarse;
    let (l2, len2, beta2) = if removed > 0 {
        let l2 = Loop { p: (0..n).filter(|&i| keep[i]).map(|i| l.p[i]).collect(), shift: l.shift };
        let (len2, beta2) = metrics(&l2);
        coarse = (l2, len2, beta2);
        (&coarse.0, &coarse.1[..], &coarse.2[..])
    } else {
        (l, len, beta)
    };
    // refinement
    let m = l2.len();
    let splits = |i: usize| {
        let h = len2[i];
        let curved = beta2[i].max(beta2[if i + 1 == m { 0 } else { i + 1 }]) * h > s.epsilon && h > 2.0 * s.h_min;
        h > s.h_max || curved
    };
    let first_split = (0..m).find(|&i| splits(i));
    if removed == 0 && first_split.is_none() {
        return None;
    }
    let mut refined = Vec::with_capacity(m + m / 4);
    refined.extend_from_slice(&l2.p[..first_split.unwrap_or(m)]);
    for i in first_split.unwrap_or(m)..m {
        refined.push(l2.p[i]);
        if splits(i) {
            let k = i as isize;
            refined.push((l2.at(k) * 9.0 + l2.at(k + 1) * 9.0 - l2.at(k - 1) - l2.at(k + 2)) / 16.0);
        }
    }
    let out = Loop { p: refined, shift: l2.shift };
    Some(if s.keep_area { Loop { p: keep_area(out, signed_area(l)), shift: l.shift } } else { out })
}

/// Whether [`adapt_loop`] may change the loop, in one branch-free pass (the common
/// answer is no): some segment is shorter than `h_min`, or one of them would be
/// split, or at least the batch of flat vertices that could go is there.
fn may_adapt(len: &[f64], beta: &[f64], s: &CurveRemeshSettings) -> bool {
    let n = len.len();
    if n < 2 {
        return false;
    }
    // per vertex: (a short neighbouring segment or a split, a flat vertex) as 0/1,
    // counted without branches (plain comparisons: no NaN here)
    let (h_min, h_max, eps, room) = (s.h_min, s.h_max, s.epsilon, MERGED_MAX * s.h_max);
    let vertex = |lp: f64, li: f64, bi: f64, bn: f64| {
        let (lmin, lmax) = if li < lp { (li, lp) } else { (lp, li) };
        let bmax = if bi < bn { bn } else { bi };
        let work = (lmin < h_min) | (li > h_max) | ((bmax * li > eps) & (li > 2.0 * h_min));
        (u64::from(work), u64::from((bi * lmax < eps / 8.0) & (li + lp <= room)))
    };
    let (w0, f0) = vertex(len[n - 1], len[0], beta[0], beta[1]);
    let (w1, f1) = vertex(len[n - 2], len[n - 1], beta[n - 1], beta[0]);
    let (mut work, mut flat) = (w0 + w1, f0 + f1);
    for (((&lp, &li), &bi), &bn) in len[..n - 2].iter().zip(&len[1..n - 1]).zip(&beta[1..n - 1]).zip(&beta[2..]) {
        let (w, f) = vertex(lp, li, bi, bn);
        work += w;
        flat += f;
    }
    work > 0 || flat as usize >= n.div_ceil(32)
}

/// `−∮ y dx` of a loop: the shoelace area for closed loops, and for loops winding
/// around the period minus the area between them and `y = 0`; invariant under
/// shifts by the period, linear in a uniform normal offset with slope the length.
fn signed_area(l: &Loop) -> f64 {
    (0..l.len() as isize).map(|k| -0.5 * (l.at(k + 1).x - l.at(k).x) * (l.at(k).y + l.at(k + 1).y)).sum()
}

/// The loop offset along its vertex normals (away from the interior) by the
/// uniform distance that restores `signed_area = target`: coarsening cuts chords
/// off convex arcs and the four-point insertions bulge out, a bias that would
/// accumulate over many passes (one offset, exact to first order in the offset).
fn keep_area(mut l: Loop, target: f64) -> Vec<Point<2>> {
    let n = l.len() as isize;
    let length: f64 = (0..n).map(|k| (l.at(k + 1) - l.at(k)).norm()).sum();
    let delta = (target - signed_area(&l)) / length.max(f64::MIN_POSITIVE);
    if delta != 0.0 && delta.is_finite() {
        let normals: Vec<Point<2>> = (0..n)
            .map(|k| {
                let t = (l.at(k + 1) - l.at(k - 1)).normalize();
                Point::<2>::new(t.y, -t.x)
            })
            .collect();
        for (p, nrm) in l.p.iter_mut().zip(normals) {
            *p += nrm * delta;
        }
    }
    l.p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regularization_keeps_area_and_equalizes() {
        // a circle sampled densely on one side
        let n = 60;
        let pts: Vec<Point<2>> = (0..n)
            .map(|k| {
                let u = k as f64 / n as f64;
                let th = 2.0 * std::f64::consts::PI * (u + 0.12 * (2.0 * std::f64::consts::PI * u).sin());
                Point::<2>::new(th.cos(), th.sin())
            })
            .collect();
        let m = from_polylines(vec![pts]).unwrap();
        let q0 = m.quality();
        let r = regularize_curve(&m, 300, None);
        let q1 = r.quality();
        assert!((r.enclosed_measure() - m.enclosed_measure()).abs() < 1e-13);
        assert!(q1.max_edge / q1.min_edge < 1.2 && q0.max_edge / q0.min_edge > 3.0, "{q0:?} {q1:?}");
        let r5 = regularize_curve(&m, 30, None).quality();
        assert!(r5.max_edge / r5.min_edge < 0.5 * q0.max_edge / q0.min_edge, "{r5:?}");
    }
}
