//! Mesh management for curves (paper §4.1): tangential regularization that keeps the
//! enclosed area exactly, and refinement/coarsening driven by `h_S β_S` (`β_S` the
//! turning angle at vertex `S`); topological changes are in `curve_topology`. Pure
//! functions from a curve mesh to a curve mesh.

use super::curves::{from_polylines, from_polylines_trusted};
use super::intersect::cross;
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
}

/// One component as a polyline: its points and the shift of the closing segment
/// (from the last point to `first + shift`; nonzero for a component winding around
/// a periodic mesh).
#[derive(Debug, Clone)]
pub(super) struct Loop {
    pub(super) p: Vec<Point<2>>,
    pub(super) shift: Point<2>,
}

impl Loop {
    pub(super) fn len(&self) -> usize {
        self.p.len()
    }

    /// Point `k` for `−n ≤ k < 2n`, continued across the closing segment.
    #[inline]
    pub(super) fn at(&self, k: isize) -> Point<2> {
        let n = self.p.len() as isize;
        if k < 0 {
            self.p[(k + n) as usize] - self.shift
        } else if k >= n {
            self.p[(k - n) as usize] + self.shift
        } else {
            self.p[k as usize]
        }
    }
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

pub(super) fn loop_area(l: &[Point<2>]) -> f64 {
    (0..l.len()).map(|k| 0.5 * cross(l[k], l[(k + 1) % l.len()])).sum()
}

/// Segment lengths and turning angles of a loop in one pass: `len[i] = |X_{i+1} − X_i|`
/// (the last one the closing segment) and, at every vertex, the turning angle as the
/// chord `|t_i − t_{i−1}|` of the two adjacent unit tangents (`2 sin(β/2)`: the angle
/// itself for small angles, monotone in it, and free of trigonometric calls).
fn metrics(l: &Loop) -> (Vec<f64>, Vec<f64>) {
    let n = l.len();
    let (mut len, mut beta) = (Vec::with_capacity(n), Vec::with_capacity(n));
    if n == 0 {
        return (len, beta);
    }
    let unit = |d: Point<2>, h: f64| if h > 0.0 { d * h.recip() } else { d };
    let closing = l.p[0] + l.shift - l.p[n - 1];
    let h_closing = closing.norm();
    let t_closing = unit(closing, h_closing);
    let mut before = t_closing;
    for w in l.p.windows(2) {
        let d = w[1] - w[0];
        let h = d.norm();
        let t = unit(d, h);
        len.push(h);
        beta.push((t - before).norm());
        before = t;
    }
    len.push(h_closing);
    beta.push((t_closing - before).norm());
    (len, beta)
}

/// Desired segment length at every vertex: `ε / κ_S` (`κ_S = β_S / h_S`) clamped to
/// `[h_min, h_max]` gives the shape (in curved parts mostly `h_min`, larger where the
/// curve is nearly straight); the sizes are that shape times the scale `c` for which
/// they add up to the loop's length, clamped to `[1.25 h_min, 0.8 h_max]`. The
/// regularization only sees ratios of neighbouring sizes; scaled so, it aims at
/// lengths the loop can have, and does not push segments past `h_max` (below
/// `h_min`), where adaptivity would split (merge) them again at the next step — a
/// 10k-vertex curve was re-meshed at 30 of 40 steps before.
fn desired_sizes(len: &[f64], beta: &[f64], s: &CurveRemeshSettings) -> Vec<f64> {
    let n = len.len();
    let total: f64 = len.iter().sum();
    // the shape of the sizes: ε/κ_S, clamped
    let shape: Vec<f64> = (0..n)
        .map(|i| {
            let h = 0.5 * (len[if i == 0 { n - 1 } else { i - 1 }] + len[i]);
            let kappa = beta[i] / h.max(f64::MIN_POSITIVE);
            (s.epsilon / kappa.max(1e-300)).clamp(s.h_min, s.h_max)
        })
        .collect();
    // a margin inside [h_min, h_max], so that motion does not trip adaptivity
    let (lo, hi) = (1.25 * s.h_min, 0.8 * s.h_max);
    if n as f64 * hi <= total {
        return vec![hi; n];
    }
    if n as f64 * lo >= total {
        return vec![lo; n];
    }
    // Newton on the piecewise linear, nondecreasing Σ clamp(c shape) − total
    let finite: f64 = shape.iter().filter(|r| r.is_finite()).sum();
    let mut c = if finite > 0.0 { total / finite } else { 1.0 };
    for _ in 0..30 {
        let (mut sum, mut slope) = (0.0, 0.0);
        for &r in &shape {
            let h = c * r;
            if h <= lo {
                sum += lo;
            } else if h >= hi {
                sum += hi;
            } else {
                sum += h;
                slope += r;
            }
        }
        let f = sum - total;
        if f.abs() <= 1e-9 * total || slope == 0.0 {
            break;
        }
        c = (c - f / slope).max(0.5 * c);
    }
    shape.iter().map(|&r| (c * r).clamp(lo, hi)).collect()
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
        regularize_loop(&mut l, &hd, sweeps);
        // back to the mesh's own representatives (lifting shifted some by periods)
        for ((&v, p), p0) in cyc.iter().zip(&l.p).zip(&start) {
            pos[v] += p - p0;
        }
    }
    mesh.with_positions(pos)
}

/// The sweeps of [`regularize_curve`] on one loop with desired sizes `hd`, even
/// vertices first, then odd ones: vertex `k` moves along the chord
/// `c = X_{k+1} − X_{k−1}` to `X_{k−1} + λ_k c`,
/// `λ_k = (h_{k−1} + h_k)/(h_{k−1} + 2h_k + h_{k+1})`, i.e. by
/// `((X_{k−1} + λ_k c − X_k)·c / |c|²) c`.
fn regularize_loop(l: &mut Loop, hd: &[f64], sweeps: usize) {
    let n = l.len();
    if n < 3 || sweeps == 0 {
        return;
    }
    let shift = l.shift;
    let p = &mut l.p;
    let mut relax = |k: usize| {
        let (prev, hp) = if k == 0 { (p[n - 1] - shift, hd[n - 1]) } else { (p[k - 1], hd[k - 1]) };
        let (next, hn) = if k + 1 == n { (p[0] + shift, hd[0]) } else { (p[k + 1], hd[k + 1]) };
        let lambda = (hp + hd[k]) / (hp + 2.0 * hd[k] + hn);
        let chord = next - prev;
        let cc = chord.dot(&chord);
        if cc > 0.0 {
            let alpha = (prev + chord * lambda - p[k]).dot(&chord) / cc;
            p[k] += chord * alpha;
        }
    };
    // red–black order: the moves of one colour do not depend on each other (nor
    // interact in the area), so they pipeline; with n odd the last vertex, a
    // neighbour of vertex 0, goes alone
    let odd_tail = n % 2 == 1;
    for _ in 0..sweeps {
        for k in (0..n - usize::from(odd_tail)).step_by(2) {
            relax(k);
        }
        for k in (1..n).step_by(2) {
            relax(k);
        }
        if odd_tail {
            relax(n - 1);
        }
    }
}

/// The cycle `cyc` of `mesh` as a loop lifted vertex by vertex.
fn lifted_loop(mesh: &CurveMesh, cyc: &[usize]) -> Loop {
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

/// Refinement and coarsening. A segment is split (at the four-point subdivision
/// point, which lies on a smooth curve through the neighbours) when it is longer
/// than `h_max`, or when `h β > ε` at one of its ends and both halves stay above
/// `h_min`; a vertex is removed when `h β < ε/8` (or a neighbouring segment is
/// shorter than `h_min`) and the merged segment stays below `h_max`. Returns `None`
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
fn adapt_loop(l: &Loop, len: &[f64], beta: &[f64], s: &CurveRemeshSettings) -> Option<Loop> {
    let n = l.len();
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
        if (short || flat) && li + lp <= s.h_max && (i + 1 < n || keep[0]) {
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
            regularize_loop(&mut l, &hd, sweeps);
        }
        loops.push(l);
    }
    if changed {
        return rebuild(mesh, loops.into_iter().map(|l| l.p).collect(), false).map(|m| (Some(m), true));
    }
    // same connectivity: back to the mesh's own representatives
    if let Some(runs) = runs {
        let mut pos = Vec::with_capacity(x.len());
        for l in loops {
            pos.extend_from_slice(&l.p);
        }
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
