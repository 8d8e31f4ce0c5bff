//! Topological changes of curves (paper §4.1): where segments cross, the curves are
//! cut and reconnected, and the loops that bound the region of positive winding
//! number are kept.

use super::curve_loop::{loop_area, Loop};
use super::curve_remesh::rebuild;
use super::mesh::lift_near;
use super::winding::WindingProbe;
use super::MeshError;
use super::{CurveMesh, Point};

/// Topological changes: where segments of the same or of different components
/// cross, the curves are cut and reconnected (each crossing swaps the successors of
/// the two crossing segments), and of the loops so formed those that bound the
/// region of positive winding number (inside on the left, outside on the right, or
/// the reverse for holes) are kept; the others (doubly covered lenses, inverted
/// slivers) and closed loops with `|area| < min_area` are dropped. The crossing
/// points themselves are then removed from the kept loops, so that loops which met
/// at a crossing do not touch; where that shortcut would cross another segment (a
/// fold pressed against a neighbouring curve), a crossing point whose other loop
/// was dropped stays instead: the kept loop then runs along parts of the two
/// crossed segments, which crossed nothing else. Two overlapping circles become
/// one curve; a curve pinched into a figure eight becomes two; on the cylinder, a
/// winding curve that touches itself or its periodic image encloses a closed
/// component. With `fill_pockets`, clockwise closed loops (a pocket of the exterior
/// that a curve closed around) are dropped too, so the pocket joins the interior.
/// Returns `None` if no segments cross.
pub fn resolve_intersections(
    mesh: &CurveMesh,
    min_area: f64,
    fill_pockets: bool,
) -> Result<Option<CurveMesh>, MeshError> {
    resolve_crossings(mesh, &mesh.crossings(), min_area, fill_pockets)
}

/// [`resolve_intersections`] given the crossings of `mesh` (as
/// [`CurveMesh::crossings`] finds them, or a [`super::CrossingWatch`]).
pub fn resolve_crossings(
    mesh: &CurveMesh,
    hits: &[super::SegmentHit],
    min_area: f64,
    fill_pockets: bool,
) -> Result<Option<CurveMesh>, MeshError> {
    let pts = mesh.positions();
    let segs = mesh.elements();
    if hits.is_empty() {
        return Ok(None);
    }
    // nodes: the mesh vertices, then two per crossing (one on each segment, each in
    // the frame of its segment's first vertex)
    let nv = pts.len();
    let mut node_pos: Vec<Point<2>> = pts.to_vec();
    let mut on_segment: Vec<Vec<(f64, usize)>> = vec![Vec::new(); segs.len()];
    let mut partner = Vec::new();
    let along = |e: usize, s: f64| {
        let [a, b] = mesh.element_points(e);
        a + (b - a) * s
    };
    for h in hits {
        let na = node_pos.len();
        node_pos.push(along(h.a, h.s));
        let nb = node_pos.len();
        node_pos.push(along(h.b, h.t));
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
    let lift = |p: Point<2>, near: &Point<2>| lift_near(mesh.period(), p, near);
    let mut seen = vec![false; node_pos.len()];
    // each loop with the node behind each of its points
    let mut loops: Vec<(Loop, Vec<usize>)> = Vec::new();
    for start in 0..node_pos.len() {
        if seen[start] || (start < nv && next[start] == usize::MAX) {
            continue;
        }
        let mut l: Vec<Point<2>> = Vec::new();
        let mut node = Vec::new();
        let mut v = start;
        while !seen[v] {
            seen[v] = true;
            let p = match l.last() {
                Some(prev) => lift(node_pos[v], prev),
                None => node_pos[v],
            };
            l.push(p);
            node.push(v);
            v = next[v];
        }
        if l.len() >= 3 {
            let shift = lift(l[0], l.last().unwrap()) - l[0];
            loops.push((Loop { p: l, shift }, node));
        }
    }
    let probe = WindingProbe::of(mesh);
    let mut kept: Vec<(Vec<Point<2>>, Vec<usize>)> = Vec::new();
    for (l, node) in loops {
        let n = l.len();
        if l.shift.norm() == 0.0 && loop_area(&l.p).abs() < min_area {
            continue;
        }
        // probe just left and right of the longest segment's midpoint
        let seg_len = |i: usize| (l.at(i as isize + 1) - l.at(i as isize)).norm();
        let k = (0..n).max_by(|&i, &j| seg_len(i).total_cmp(&seg_len(j))).unwrap();
        let (a, b) = (l.at(k as isize), l.at(k as isize + 1));
        let d = b - a;
        let normal_left = Point::<2>::new(-d.y, d.x).normalize();
        let mid = (a + b) * 0.5;
        let eps = 1e-6 * d.norm().max(1e-12);
        let left = probe.at(mid + normal_left * eps) > 0;
        let right = probe.at(mid - normal_left * eps) > 0;
        // on the cylinder, a clockwise closed loop would be an island of the
        // interior's complement (a floating piece of film): dropped like a sliver;
        // in the plane, one is a pocket of the exterior, filled on request
        let island = (mesh.period().is_some() || fill_pockets) && l.shift.norm() == 0.0 && loop_area(&l.p) < 0.0;
        if left != right && !island {
            kept.push((l.p, node));
        }
    }
    // the partner of every crossing node, and whether it lies on a kept loop
    let mut on_kept = vec![false; node_pos.len()];
    for &v in kept.iter().flat_map(|(_, node)| node) {
        on_kept[v] = true;
    }
    let mut partner_of = vec![usize::MAX; node_pos.len()];
    for &(na, nb) in &partner {
        (partner_of[na], partner_of[nb]) = (nb, na);
    }
    let loops_without_crossings = |keep_lone: bool| -> Vec<Vec<Point<2>>> {
        let stays = |v: usize| v < nv || (keep_lone && !on_kept[partner_of[v]]);
        kept.iter()
            .map(|(p, node)| p.iter().zip(node).filter(|&(_, &v)| stays(v)).map(|(q, _)| *q).collect::<Vec<_>>())
            .filter(|p| p.len() >= 3)
            .collect()
    };
    match rebuild(mesh, loops_without_crossings(false), true) {
        Err(MeshError::SelfIntersection { .. }) => rebuild(mesh, loops_without_crossings(true), true).map(Some),
        r => r.map(Some),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::curves::from_polylines;
    use crate::geometry::{circle, union};

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
        let merged = resolve_intersections(&m, 1e-8, false).unwrap().unwrap();
        assert_eq!(merged.num_components(), 1);
        let d: f64 = 1.2;
        let lens = 2.0 * (d / 2.0).acos() - 0.5 * d * (4.0 - d * d).sqrt();
        let exact = 2.0 * std::f64::consts::PI - lens;
        assert!((merged.enclosed_measure() - exact).abs() < 0.01 * exact, "{}", merged.enclosed_measure());
        assert!(resolve_intersections(&overlapping(2.5), 1e-8, false).unwrap().is_none());
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
        let out = resolve_intersections(&crossed, 1e-6, false).unwrap().unwrap();
        assert_eq!(out.num_components(), 2);
        for cyc in out.cycles() {
            let l: Vec<Point<2>> = cyc.iter().map(|&v| out.positions()[v]).collect();
            assert!(loop_area(&l) > 0.0, "each lobe counter-clockwise");
        }
        // areas: each lobe ∫ |y| dx over the lobe, by symmetry equal
        let total = out.enclosed_measure();
        let lobes: Vec<f64> = out
            .cycles()
            .iter()
            .map(|c| loop_area(&c.iter().map(|&v| out.positions()[v]).collect::<Vec<_>>()))
            .collect();
        assert!((lobes[0] - lobes[1]).abs() < 1e-3 * total);
    }

    /// A horseshoe (annular sector between radii 1 and 2, angles `[θ₀, 2π − θ₀]`)
    /// whose arms are then moved to overlap (`θ₀ < 0`): the arms close around the
    /// unit disk, a pocket of the exterior.
    #[test]
    fn a_closed_pocket_is_kept_as_a_hole_or_filled() {
        let horseshoe = |t0: f64| -> Vec<Point<2>> {
            let n = 200;
            let arc = |r: f64, k: usize| {
                let t = t0 + (2.0 * std::f64::consts::PI - 2.0 * t0) * k as f64 / n as f64;
                Point::<2>::new(r * t.cos(), r * t.sin())
            };
            (0..=n).map(|k| arc(2.0, k)).chain((0..=n).rev().map(|k| arc(1.0, k))).collect()
        };
        let valid = from_polylines(vec![horseshoe(0.3)]).unwrap();
        let crossed = valid.with_positions(horseshoe(-0.15));
        let kept = resolve_intersections(&crossed, 1e-6, false).unwrap().unwrap();
        assert_eq!(kept.num_components(), 2);
        let annulus = 3.0 * std::f64::consts::PI;
        assert!((kept.enclosed_measure() - annulus).abs() < 0.01 * annulus, "{}", kept.enclosed_measure());
        let filled = resolve_intersections(&crossed, 1e-6, true).unwrap().unwrap();
        assert_eq!(filled.num_components(), 1);
        let disk = 4.0 * std::f64::consts::PI;
        assert!((filled.enclosed_measure() - disk).abs() < 0.01 * disk, "{}", filled.enclosed_measure());
    }

    /// A fold on the top side of the unit square (its segment `C → D` crosses
    /// `A → B` at `X`) beside a small neighbouring triangle that the shortcut
    /// `A → D` would cross: the lens `X B C` is dropped, and the square keeps `X`
    /// as a corner. Without the neighbour, `X` goes as usual.
    #[test]
    fn a_fold_pressed_against_a_neighbour_keeps_its_crossing_point() {
        let p = |x: f64, y: f64| Point::<2>::new(x, y);
        let square = [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.7, 1.0), p(0.5, 1.0), p(0.6, 0.9), p(0.55, 1.1)]
            .into_iter()
            .chain([p(0.3, 1.0), p(0.0, 1.0)]);
        let neighbour = [p(0.62, 1.02), p(0.64, 1.02), p(0.63, 1.06)];
        let x = p(0.575, 1.0);
        let has_x = |m: &CurveMesh| m.positions().iter().any(|q| (q - x).norm() < 1e-12);
        let mesh = |parts: Vec<Vec<Point<2>>>| {
            let (mut pts, mut els) = (Vec::new(), Vec::new());
            for part in parts {
                let (base, n) = (pts.len(), part.len());
                pts.extend(part);
                els.extend((0..n).map(|k| [base + k, base + (k + 1) % n]));
            }
            CurveMesh::from_trusted_parts(pts, els)
        };
        let pressed = mesh(vec![square.clone().collect(), neighbour.to_vec()]);
        assert_eq!(pressed.crossings().len(), 1);
        let out = resolve_intersections(&pressed, 1e-6, false).unwrap().unwrap();
        assert_eq!(out.num_components(), 2);
        assert!(out.crossings().is_empty());
        assert!(has_x(&out));
        let alone = resolve_intersections(&mesh(vec![square.collect()]), 1e-6, false).unwrap().unwrap();
        assert_eq!(alone.num_components(), 1);
        assert!(!has_x(&alone));
    }
}
#[cfg(test)]
mod periodic_tests {
    use super::*;
    use crate::geometry::{mesh_winding_number, Mesh};

    /// A flat film (y = 0.5 on a period of 1) with a groove whose walls cross at its
    /// neck, enclosing a bulb below.
    fn pinched_groove() -> CurveMesh {
        let mut pts: Vec<Point<2>> = Vec::new();
        for i in 0..8 {
            pts.push(Point::<2>::new(0.05 * i as f64, 0.5));
        }
        pts.extend([
            Point::<2>::new(0.4, 0.5),
            Point::<2>::new(0.46, 0.4),
            Point::<2>::new(0.52, 0.3),
            Point::<2>::new(0.45, 0.2),
            Point::<2>::new(0.45, 0.1),
            Point::<2>::new(0.55, 0.1),
            Point::<2>::new(0.55, 0.2),
            Point::<2>::new(0.48, 0.3),
            Point::<2>::new(0.54, 0.4),
            Point::<2>::new(0.6, 0.5),
        ]);
        for i in 1..8 {
            pts.push(Point::<2>::new(0.6 + 0.05 * i as f64, 0.5));
        }
        let n = pts.len();
        Mesh::periodic_trusted(pts, (0..n).map(|i| [i, (i + 1) % n]).collect(), 1.0)
    }

    #[test]
    fn periodic_winding_counts_gas_above_the_film_and_in_voids() {
        let m = pinched_groove();
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(0.2, 0.7)), 1);
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(1.2, 0.7)), 1);
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(0.2, 0.3)), 0);
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(0.5, 0.15)), 1);
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(-0.5, 0.15)), 1);
        assert_eq!(mesh_winding_number(&m, Point::<2>::new(0.5, 0.45)), 1);
    }

    #[test]
    fn a_film_whose_groove_walls_cross_encloses_a_void() {
        let m = pinched_groove();
        let before = m.enclosed_measure();
        let out = resolve_intersections(&m, 1e-9, false).unwrap().unwrap();
        assert_eq!(out.num_components(), 2);
        let mut w = out.windings();
        w.sort();
        assert_eq!(w, vec![0, 1]);
        // the void runs counter-clockwise; the areas add up to the old one up to the
        // removed crossing points (a few triangles of the coarse polygon)
        for ((pts, _), w) in out.lifted_cycles().iter().zip(out.windings()) {
            if w == 0 {
                assert!(loop_area(pts) > 0.01, "void area {}", loop_area(pts));
            }
        }
        assert!((out.enclosed_measure() - before).abs() < 6e-3, "{} vs {before}", out.enclosed_measure());
    }
}
