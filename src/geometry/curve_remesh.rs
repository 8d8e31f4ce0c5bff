//! Mesh management for curves (paper §4.1): tangential regularization that keeps the
//! enclosed area exactly, refinement/coarsening driven by `h_S β_S` (`β_S` the
//! turning angle at vertex `S`), and topological changes on intersection. Pure
//! functions from a curve mesh to a curve mesh.

use super::curves::{from_polylines, from_polylines_trusted};
use super::{find_segment_intersections, CurveMesh, MeshError, Point};

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
}

type Loop = Vec<Point<2>>;

fn loops_of(mesh: &CurveMesh) -> Vec<Loop> {
    mesh.cycles().iter().map(|c| c.iter().map(|&v| mesh.positions()[v]).collect()).collect()
}

fn cross(u: Point<2>, v: Point<2>) -> f64 {
    u.x * v.y - u.y * v.x
}

fn loop_area(l: &Loop) -> f64 {
    (0..l.len()).map(|k| 0.5 * cross(l[k], l[(k + 1) % l.len()])).sum()
}

/// Turning angle at every vertex of a loop, measured as the chord `|t₁ − t₂|` of the
/// two adjacent unit tangents (`2 sin(β/2)`: the angle itself for small angles,
/// monotone in it, and free of trigonometric calls).
fn turning_angles(l: &Loop) -> Vec<f64> {
    let n = l.len();
    let unit = |v: Point<2>| {
        let len = v.norm();
        if len > 0.0 {
            v / len
        } else {
            v
        }
    };
    let t: Vec<Point<2>> = (0..n).map(|i| unit(l[(i + 1) % n] - l[i])).collect();
    (0..n).map(|i| (t[i] - t[(i + n - 1) % n]).norm()).collect()
}

/// Desired segment length at every vertex: `ε / κ_S` with `κ_S = β_S / h_S`, clamped
/// to `[h_min, h_max]`.
fn desired_sizes(l: &Loop, s: &CurveRemeshSettings) -> Vec<f64> {
    let n = l.len();
    let beta = turning_angles(l);
    (0..n)
        .map(|i| {
            let h = 0.5 * ((l[i] - l[(i + n - 1) % n]).norm() + (l[(i + 1) % n] - l[i]).norm());
            let kappa = beta[i] / h.max(f64::MIN_POSITIVE);
            (s.epsilon / kappa.max(1e-300)).clamp(s.h_min, s.h_max)
        })
        .collect()
}

/// Tangential regularization: `sweeps` Gauss–Seidel sweeps moving every vertex
/// parallel to the chord of its neighbours towards the point that splits the chord in
/// the ratio of the desired sizes (equal lengths when `sizes` is `None`). The enclosed
/// area is linear in each single vertex with the others fixed and its gradient
/// `½ J (X_{i+1} − X_{i−1})` is normal to that chord, so every move keeps the area
/// exactly (up to round-off).
pub fn regularize_curve(mesh: &CurveMesh, sweeps: usize, sizes: Option<&CurveRemeshSettings>) -> CurveMesh {
    let mut pos = mesh.positions().to_vec();
    for cyc in mesh.cycles() {
        let n = cyc.len();
        let l: Loop = cyc.iter().map(|&v| pos[v]).collect();
        let hd = match sizes {
            Some(s) => desired_sizes(&l, s),
            None => vec![1.0; n],
        };
        for _ in 0..sweeps {
            for k in 0..n {
                let (ip, i, inx) = (cyc[(k + n - 1) % n], cyc[k], cyc[(k + 1) % n]);
                let chord = pos[inx] - pos[ip];
                let len = chord.norm();
                if len <= 0.0 {
                    continue;
                }
                let t = chord / len;
                let (hp, hi, hn) = (hd[(k + n - 1) % n], hd[k], hd[(k + 1) % n]);
                let lambda = (hp + hi) / (hp + 2.0 * hi + hn);
                let target = pos[ip] + chord * lambda;
                let alpha = (target - pos[i]).dot(&t);
                pos[i] += t * alpha;
            }
        }
    }
    mesh.with_positions(pos)
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
        let n = l.len();
        let beta = turning_angles(&l);
        let len: Vec<f64> = (0..n).map(|i| (l[(i + 1) % n] - l[i]).norm()).collect();
        let indicator = |i: usize| beta[i] * len[i].max(len[(i + n - 1) % n]);
        // coarsening: never two neighbours in one pass, keep at least 8 vertices
        let mut keep = vec![true; n];
        let mut removed = 0;
        for i in 0..n {
            if n - removed <= 8 || !keep[(i + n - 1) % n] {
                continue;
            }
            let short = len[i].min(len[(i + n - 1) % n]) < s.h_min;
            let flat = indicator(i) < s.epsilon / 8.0;
            let merged = len[i] + len[(i + n - 1) % n];
            if (short || flat) && merged <= s.h_max && (i + 1 < n || keep[0]) {
                keep[i] = false;
                removed += 1;
            }
        }
        let l2: Loop = (0..n).filter(|&i| keep[i]).map(|i| l[i]).collect();
        changed |= removed > 0;
        // refinement
        let m = l2.len();
        let beta2 = turning_angles(&l2);
        let mut refined = Vec::with_capacity(2 * m);
        for i in 0..m {
            let j = (i + 1) % m;
            let h = (l2[j] - l2[i]).norm();
            refined.push(l2[i]);
            let curved = beta2[i].max(beta2[j]) * h > s.epsilon && h > 2.0 * s.h_min;
            if h > s.h_max || curved {
                let p0 = l2[(i + m - 1) % m];
                let p3 = l2[(j + 1) % m];
                refined.push((l2[i] * 9.0 + l2[j] * 9.0 - p0 - p3) / 16.0);
                changed = true;
            }
        }
        out.push(refined);
    }
    if !changed {
        return Ok(None);
    }
    from_polylines_trusted(out).map(Some)
}

/// Winding number of the point `p` with respect to closed loops (each a list of
/// vertices, the closing segment implied).
pub fn winding_number<L: AsRef<[Point<2>]>>(loops: &[L], p: Point<2>) -> i32 {
    let mut w = 0;
    for l in loops {
        let l = l.as_ref();
        let n = l.len();
        for k in 0..n {
            let (a, b) = (l[k], l[(k + 1) % n]);
            if a.y <= p.y {
                if b.y > p.y && cross(b - a, p - a) > 0.0 {
                    w += 1;
                }
            } else if b.y <= p.y && cross(b - a, p - a) < 0.0 {
                w -= 1;
            }
        }
    }
    w
}

/// Topological changes: where segments of the same or of different components
/// cross, the curves are cut and reconnected (each crossing swaps the successors of
/// the two crossing segments), and of the loops so formed those that bound the
/// region of positive winding number (inside on the left, outside on the right, or
/// the reverse for holes) are kept; the others (doubly covered lenses, inverted
/// slivers) and loops with `|area| < min_area` are dropped. The crossing points
/// themselves are then removed from the kept loops, so that loops which met at a
/// crossing do not touch. Two overlapping circles become one
/// curve; a curve pinched into a figure eight becomes two. Returns `None` if no
/// segments cross.
pub fn resolve_intersections(mesh: &CurveMesh, min_area: f64) -> Result<Option<CurveMesh>, MeshError> {
    let pts = mesh.positions();
    let segs = mesh.elements();
    let hits = find_segment_intersections(pts, segs);
    if hits.is_empty() {
        return Ok(None);
    }
    let original = loops_of(mesh);
    // nodes: the mesh vertices, then two per crossing (one on each segment)
    let nv = pts.len();
    let mut node_pos: Vec<Point<2>> = pts.to_vec();
    let mut on_segment: Vec<Vec<(f64, usize)>> = vec![Vec::new(); segs.len()];
    let mut partner = Vec::new();
    for h in &hits {
        let na = node_pos.len();
        node_pos.push(h.point);
        let nb = node_pos.len();
        node_pos.push(h.point);
        on_segment[h.a].push((h.s, na));
        on_segment[h.b].push((h.t, nb));
        partner.push((na, nb));
    }
    // successor of every node along its original segment chain
    let mut next = vec![usize::MAX; node_pos.len()];
    for (e, seg) in segs.iter().enumerate() {
        let mut chain = on_segment[e].clone();
        chain.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut cur = seg[0];
        for &(_, node) in &chain {
            next[cur] = node;
            cur = node;
        }
        next[cur] = seg[1];
    }
    // reconnect: swap successors at each crossing
    for &(na, nb) in &partner {
        next.swap(na, nb);
    }
    let mut seen = vec![false; node_pos.len()];
    let mut loops: Vec<(Loop, Vec<bool>)> = Vec::new();
    for start in 0..node_pos.len() {
        if seen[start] || (start < nv && next[start] == usize::MAX) {
            continue;
        }
        let mut l = Vec::new();
        let mut is_crossing = Vec::new();
        let mut v = start;
        while !seen[v] {
            seen[v] = true;
            l.push(node_pos[v]);
            is_crossing.push(v >= nv);
            v = next[v];
        }
        if l.len() >= 3 {
            loops.push((l, is_crossing));
        }
    }
    let mut kept = Vec::new();
    for (l, is_crossing) in loops {
        let area = loop_area(&l);
        if area.abs() < min_area || l.len() < 3 {
            continue;
        }
        // probe just left and right of the longest segment's midpoint
        let n = l.len();
        let k =
            (0..n).max_by(|&i, &j| (l[(i + 1) % n] - l[i]).norm().total_cmp(&(l[(j + 1) % n] - l[j]).norm())).unwrap();
        let (a, b) = (l[k], l[(k + 1) % n]);
        let d = b - a;
        let normal_left = Point::<2>::new(-d.y, d.x).normalize();
        let mid = (a + b) * 0.5;
        let eps = 1e-6 * d.norm().max(1e-12);
        let left = winding_number(&original, mid + normal_left * eps) > 0;
        let right = winding_number(&original, mid - normal_left * eps) > 0;
        if left != right {
            let l: Loop = l.into_iter().zip(is_crossing).filter(|(_, c)| !c).map(|(p, _)| p).collect();
            if l.len() >= 3 {
                kept.push(l);
            }
        }
    }
    from_polylines(kept).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, union};

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

    /// Two disjoint circles, then the second moved (positions only, as the flow does).
    fn overlapping(d: f64) -> CurveMesh {
        let a = circle([0.0, 0.0], 1.0, 128).unwrap();
        let b = circle([5.0, 0.0], 1.0, 128).unwrap();
        let m = union(&[a, b]).unwrap();
        let pos = m
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| if i >= 128 { p - Point::<2>::new(5.0 - d, 0.0) } else { *p })
            .collect();
        m.with_positions(pos)
    }

    #[test]
    fn overlapping_circles_merge_and_lens_is_dropped() {
        let m = overlapping(1.2);
        let merged = resolve_intersections(&m, 1e-8).unwrap().unwrap();
        assert_eq!(merged.num_components(), 1);
        let d: f64 = 1.2;
        let lens = 2.0 * (d / 2.0).acos() - 0.5 * d * (4.0 - d * d).sqrt();
        let exact = 2.0 * std::f64::consts::PI - lens;
        assert!((merged.enclosed_measure() - exact).abs() < 0.01 * exact, "{}", merged.enclosed_measure());
        assert!(resolve_intersections(&overlapping(2.5), 1e-8).unwrap().is_none());
    }

    #[test]
    fn figure_eight_splits_into_two_counter_clockwise_loops() {
        // a dumbbell whose neck sides have crossed: (x, y) with |y| ≤ w(x), w < 0 near 0
        let n = 400;
        let pts: Vec<Point<2>> = (0..n)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                let x = 2.0 * t.cos();
                let y = t.sin() * (0.6 * x * x - 0.3);
                Point::<2>::new(x, y)
            })
            .collect();
        // build a valid mesh first (neck open), then move to the crossed state
        let open: Vec<Point<2>> = pts.iter().map(|p| Point::<2>::new(p.x, p.y + p.y.signum() * 0.0)).collect();
        let valid = from_polylines(vec![(0..n)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                Point::<2>::new(2.0 * t.cos(), t.sin() * (0.6 * 4.0 * t.cos() * t.cos() + 0.3))
            })
            .collect()])
        .unwrap();
        let crossed = valid.with_positions(open);
        let out = resolve_intersections(&crossed, 1e-6).unwrap().unwrap();
        assert_eq!(out.num_components(), 2);
        for cyc in out.cycles() {
            let l: Loop = cyc.iter().map(|&v| out.positions()[v]).collect();
            assert!(loop_area(&l) > 0.0, "each lobe counter-clockwise");
        }
        // areas: each lobe ∫ |y| dx over the lobe, by symmetry equal
        let total = out.enclosed_measure();
        let lobes: Vec<f64> =
            out.cycles().iter().map(|c| loop_area(&c.iter().map(|&v| out.positions()[v]).collect())).collect();
        assert!((lobes[0] - lobes[1]).abs() < 1e-3 * total);
    }
}
