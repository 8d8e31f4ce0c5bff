//! Mesh management for closed triangle surfaces (paper §4.1): volume-preserving
//! tangential regularization ([`regularize_surface`]), and adaptivity
//! ([`adapt_surface`]) by edge split, collapse and flip with angle-width control,
//! and the replacement of clusters of tiny triangles (a crumpled spot, or a neck
//! pinching off),
//! one module per operation over one [`adjacency`] structure. Pure functions from a
//! surface mesh to a surface mesh.

mod adjacency;
mod clusters;
mod collapse;
mod ears;
mod flip;
mod regularize;
mod split;
mod triangles;

pub use adjacency::{surface_edges, SurfaceEdge};
pub use regularize::regularize_surface;

use adjacency::Adjacency;
use clusters::replace_clusters;
use collapse::collapse_edges;
use flip::flip_edges;
use split::split_edges;
use triangles::tri_normal;

use super::surface_intersections::around;
use super::{Mesh, Point, SurfaceMesh};

/// Parameters of surface mesh management.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceRemeshSettings {
    /// Refine an edge where `h β > epsilon` (`β` the angle between the normals of the
    /// two triangles sharing it); collapse where far below.
    pub epsilon: f64,
    pub h_min: f64,
    pub h_max: f64,
    /// Angle-width control: split the edge opposite an angle wider than this (degrees).
    pub max_angle_deg: f64,
}

/// Mean edge length, the largest `h β` and the largest `β/h` over the edges (`β` the
/// angle between the normals of the two triangles at the edge).
pub fn edge_statistics(mesh: &SurfaceMesh) -> (f64, f64, f64) {
    let p = mesh.positions();
    let edges = surface_edges(p.len(), mesh.elements());
    let normals = mesh.element_normals();
    let (mut sum, mut hb, mut bh) = (0.0, 0.0f64, 0.0f64);
    for e in &edges {
        let h = (p[e.b] - p[e.a]).norm();
        sum += h;
        if e.t[1] != usize::MAX {
            let beta = normals[e.t[0]].dot(&normals[e.t[1]]).clamp(-1.0, 1.0).acos();
            hb = hb.max(h * beta);
            bh = bh.max(beta / h);
        }
    }
    (sum / edges.len().max(1) as f64, hb, bh)
}

/// Vertices of the input that an adaptation leaves as they are: no operation
/// takes an edge, a flip's quad or a cluster's patch with one of them.
pub(super) struct Frozen<'a>(&'a [bool]);

impl Frozen<'_> {
    /// Whether one of `vertices` is frozen (those past the input's, new ones, are not).
    fn any(&self, vertices: &[usize]) -> bool {
        vertices.iter().any(|&v| self.0.get(v).copied().unwrap_or(false))
    }
}

/// Freezes (for [`adapt_surface_except`]) the vertices of `mesh` that an
/// adaptation `adapted` of it may have used for the triangles of `pairs`: those
/// within `reach` times the longest edge of a pair's two triangles from their
/// box. At `reach` 1 that holds the operations of one stage (a split's new
/// vertex lies half the split edge, one new edge, from its ends, a collapse's
/// between its two, and a flip's and a cluster's cap are made of their
/// corners); a chain of operations over the stages reaches further.
pub fn freeze_around(
    mesh: &SurfaceMesh,
    adapted: &SurfaceMesh,
    pairs: &[(usize, usize)],
    reach: f64,
    frozen: &mut [bool],
) {
    let boxes: Vec<_> = pairs
        .iter()
        .map(|&(a, b)| {
            let corners: Vec<Point<3>> = [a, b].iter().flat_map(|&t| adapted.element_points(t)).collect();
            let edge = (0..6).map(|k| (corners[k] - corners[k / 3 * 3 + (k + 1) % 3]).norm()).fold(0.0, f64::max);
            let (lo, hi) = around(corners.iter());
            (lo.map(|c| c - reach * edge), hi.map(|c| c + reach * edge))
        })
        .collect();
    for (v, x) in mesh.positions().iter().enumerate() {
        frozen[v] |= boxes.iter().any(|(lo, hi)| (0..3).all(|k| lo[k] <= x[k] && x[k] <= hi[k]));
    }
}

/// One adaptation pass: clusters of tiny triangles replaced ([`replace_clusters`]),
/// splits (refinement and angle-width control), collapses, flips, each stage kept
/// only if its result is a valid closed oriented surface (a stage that would break
/// it is skipped, the others still apply). Returns `None` if nothing changed.
pub fn adapt_surface(mesh: &SurfaceMesh, s: &SurfaceRemeshSettings) -> Option<SurfaceMesh> {
    adapt_surface_except(mesh, s, &[])
}

/// [`adapt_surface`] with the vertices `v` of `frozen[v]` left as they are, with
/// every triangle that has one of them (`frozen` may be shorter than the
/// vertices: those past it are not frozen).
pub fn adapt_surface_except(mesh: &SurfaceMesh, s: &SurfaceRemeshSettings, frozen: &[bool]) -> Option<SurfaceMesh> {
    let frozen = Frozen(frozen);
    let mut p = mesh.positions().to_vec();
    let mut tris = mesh.elements().to_vec();
    let mut adjacency = Adjacency::of(p.len(), &tris);
    let mut changed = false;
    // a stage runs on copies; the adjacency of its result serves the check and the
    // next stage
    type Op<'a> = &'a dyn Fn(&mut Vec<Point<3>>, &mut Vec<[usize; 3]>, &Adjacency) -> bool;
    let mut stage = |op: Op<'_>, p: &mut Vec<Point<3>>, tris: &mut Vec<[usize; 3]>, adjacency: &mut Adjacency| {
        let (mut p2, mut t2) = (p.clone(), tris.clone());
        if !op(&mut p2, &mut t2, adjacency) {
            return;
        }
        let after = Adjacency::of(p2.len(), &t2);
        if closed_and_oriented(&p2, &t2, &after) {
            (*p, *tris, *adjacency) = (p2, t2, after);
            changed = true;
        }
    };
    stage(&|p, t, a| replace_clusters(p, t, a, s, &frozen), &mut p, &mut tris, &mut adjacency);
    stage(
        &|p, t, a| match split_edges(p, t, a, s, &frozen) {
            Some(new) => {
                *t = new;
                true
            }
            None => false,
        },
        &mut p,
        &mut tris,
        &mut adjacency,
    );
    stage(&|p, t, a| collapse_edges(p, t, a, s, &frozen), &mut p, &mut tris, &mut adjacency);
    stage(&|p, t, a| flip_edges(p, t, a, s, &frozen), &mut p, &mut tris, &mut adjacency);
    if !changed {
        return None;
    }
    // drop vertices no longer used and renumber
    let mut used = vec![usize::MAX; p.len()];
    let mut positions = Vec::with_capacity(p.len());
    for t in &tris {
        for &v in t {
            if used[v] == usize::MAX {
                used[v] = positions.len();
                positions.push(p[v]);
            }
        }
    }
    let tris: Vec<[usize; 3]> = tris.iter().map(|t| t.map(|v| used[v])).collect();
    Some(Mesh::from_trusted_parts(positions, tris))
}

/// The checks a remeshing pass can break: every edge in exactly two triangles, in
/// opposite directions, and no degenerate triangle (the link condition of the
/// collapses keeps vertex stars manifold).
fn closed_and_oriented(p: &[Point<3>], tris: &[[usize; 3]], adjacency: &Adjacency) -> bool {
    let edges = &adjacency.edges;
    if edges.windows(2).any(|w| (w[0].a, w[0].b) == (w[1].a, w[1].b)) {
        return false;
    }
    let forward = |t: &[usize; 3], a: usize, b: usize| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    let areas: Vec<f64> = tris.iter().map(|t| tri_normal(p, t).norm()).collect();
    let scale = areas.iter().sum::<f64>() / tris.len().max(1) as f64;
    edges.iter().all(|e| e.t[1] != usize::MAX && forward(&tris[e.t[0]], e.a, e.b) != forward(&tris[e.t[1]], e.a, e.b))
        && areas.iter().all(|&a| a > 1e-10 * scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{ellipsoid, icosphere};

    #[test]
    fn regularization_keeps_volume_and_improves_angles() {
        let s = icosphere([0.0; 3], 1.0, 3).unwrap();
        // shear the vertices tangentially
        let p: Vec<Point<3>> = s
            .positions()
            .iter()
            .map(|x| {
                let t = Point::<3>::new(-x.y, x.x, 0.0) * (0.15 * (3.0 * x.z).sin());
                (x + t).normalize()
            })
            .collect();
        let bad = s.with_positions(p);
        let q0 = bad.quality();
        let r = regularize_surface(&bad, 10);
        let q1 = r.quality();
        assert!((r.enclosed_measure() - bad.enclosed_measure()).abs() < 1e-12, "volume kept");
        assert!(q1.min_angle_deg > q0.min_angle_deg + 5.0, "{q0:?} -> {q1:?}");
    }

    #[test]
    fn adaptivity_refines_tips_and_controls_wide_angles() {
        let e = ellipsoid([0.0; 3], [2.0, 0.5, 0.5], 3).unwrap();
        let mean = {
            let q = e.quality();
            0.5 * (q.min_edge + q.max_edge)
        };
        let s = SurfaceRemeshSettings { epsilon: 0.02, h_min: 0.1 * mean, h_max: 2.0 * mean, max_angle_deg: 120.0 };
        let mut m = e.clone();
        for _ in 0..6 {
            if let Some(next) = adapt_surface(&m, &s) {
                m = regularize_surface(&next, 3);
            }
        }
        let q = m.quality();
        assert!(q.max_angle_deg <= 125.0, "{q:?}");
        let mean_edge = |pred: &dyn Fn(f64) -> bool| {
            let mut sum = 0.0;
            let mut cnt = 0.0;
            for t in m.elements() {
                let c = (m.positions()[t[0]] + m.positions()[t[1]] + m.positions()[t[2]]) / 3.0;
                if pred(c.x) {
                    sum += (m.positions()[t[1]] - m.positions()[t[0]]).norm();
                    cnt += 1.0;
                }
            }
            sum / cnt
        };
        let tips = mean_edge(&|x| x.abs() > 1.8);
        let flanks = mean_edge(&|x| x.abs() < 0.5);
        eprintln!("tips {tips} flanks {flanks} vertices {} quality {q:?}", m.num_vertices());
        assert!(flanks > 1.5 * tips, "tips {tips} flanks {flanks}");
    }

    /// An adaptation with the vertices of one half of an ellipsoid frozen keeps
    /// every triangle that has one of them as it was, and adapts the other half;
    /// `freeze_around` freezes the vertices near a pair of triangles.
    #[test]
    fn frozen_vertices_keep_their_triangles() {
        let e = ellipsoid([0.0; 3], [2.0, 0.5, 0.5], 3).unwrap();
        let q = e.quality();
        let mean = 0.5 * (q.min_edge + q.max_edge);
        let s = SurfaceRemeshSettings { epsilon: 0.02, h_min: 0.1 * mean, h_max: 2.0 * mean, max_angle_deg: 120.0 };
        let corners = |m: &SurfaceMesh, t: &[usize; 3]| {
            let mut c = t.map(|v| m.positions()[v].map(f64::to_bits));
            c.sort_unstable_by_key(|p| [p[0], p[1], p[2]]);
            c
        };
        let frozen: Vec<bool> = e.positions().iter().map(|x| x.x < 0.0).collect();
        let m = adapt_surface_except(&e, &s, &frozen).unwrap();
        let after: std::collections::HashSet<_> = m.elements().iter().map(|t| corners(&m, t)).collect();
        let kept = e.elements().iter().filter(|t| t.iter().any(|&v| frozen[v]));
        assert!(kept.clone().all(|t| after.contains(&corners(&e, t))));
        let changed =
            |m: &SurfaceMesh, side: f64| m.elements().iter().filter(|t| side * m.positions()[t[0]].x > 0.0).count();
        assert_eq!(changed(&m, -1.0), changed(&e, -1.0), "the frozen half");
        assert!(changed(&m, 1.0) > changed(&e, 1.0) + 20, "the free half refined at its tip");
        // the vertices near two triangles at the tip x = 2
        let tip: Vec<usize> = (0..e.num_elements()).filter(|&t| e.element_points(t)[0].x > 1.9).take(2).collect();
        let mut near = vec![false; e.num_vertices()];
        freeze_around(&e, &e, &[(tip[0], tip[1])], 1.0, &mut near);
        let frozen_x: Vec<f64> = (0..e.num_vertices()).filter(|&v| near[v]).map(|v| e.positions()[v].x).collect();
        assert!(frozen_x.len() >= 6 && frozen_x.iter().all(|&x| x > 1.0), "{frozen_x:?}");
    }
}
