//! Removal of clusters of tiny triangles. A cluster of edges far below `h_min`,
//! which the edge collapses cannot coarsen (its triangles are too crumpled for
//! their turn and angle checks, its vertex stars too tangled for the link
//! condition), is cut out with the triangles around it, and each boundary loop
//! of the hole is closed by a fan around one new vertex, placed so that the
//! enclosed volume is kept; a loop that no such fan closes without folding (not
//! star-shaped seen along its normal) is closed by triangles between its own
//! vertices ([`ear_cap`]), which changes the volume by at most the patch's.
//!
//! The patch cut out is a disk (a crumpled spot or spike: one fan replaces it),
//! an annulus (a thin neck whose circumference has shrunk below `h_min`: two
//! fans cap the two sides, and the surface pinches off there, as the paper's
//! topological changes of curves do), or a whole closed component that has
//! shrunk to less than `SPAN·h_min` (it vanishes, as curves below `min_area` do;
//! the last component stays).

use super::adjacency::Adjacency;
use super::ears::{ear_cap, folded};
use super::{Frozen, SurfaceRemeshSettings};
use crate::geometry::{components, Point};

/// Edges shorter than this fraction of `h_min` join their ends into a cluster.
const TINY: f64 = 0.25;

/// A cluster is replaced only when its vertices span less than this many `h_min`.
const SPAN: f64 = 4.0;

/// The patch around a cluster grows by at most this many rings of triangles
/// until its boundary loops can be closed by fans.
const RINGS: usize = 6;

/// Replaces each cluster of vertices joined by edges below `TINY·h_min`: the patch
/// is the triangles touching the cluster, grown ring by ring until it is a disk
/// or an annulus whose fans do not fold, or a whole small component (removed).
/// Returns whether a cluster was replaced (the fans' triangles are appended, the
/// patches' inner vertices left unused); `p` and `tris` are untouched otherwise.
pub(super) fn replace_clusters(
    p: &mut Vec<Point<3>>,
    tris: &mut Vec<[usize; 3]>,
    adjacency: &Adjacency,
    s: &SurfaceRemeshSettings,
    frozen: &Frozen,
) -> bool {
    let clusters = clusters(p, adjacency, TINY * s.h_min);
    let mut locked: Vec<bool> = (0..p.len()).map(|v| frozen.any(&[v])).collect();
    let mut dead = vec![false; tris.len()];
    let mut fans: Vec<Cap> = Vec::new();
    // patches replaced, and whether one was cut at a neck (or vanished)
    let (mut removed, mut cut) = (0, false);
    for cluster in clusters.iter().filter(|c| span(p, c) < SPAN * s.h_min) {
        // fans on the growing patches first; ears only if no fan closes any
        'ears: for ears in [false, true] {
            let mut inner = cluster.clone();
            for _ in 0..RINGS {
                let triangles = star_of(adjacency, &inner);
                let vertices = vertices_of(tris, &triangles);
                if vertices.iter().any(|&v| locked[v]) {
                    break 'ears;
                }
                let Some(patch) = Patch::of(tris, &triangles, vertices.len()) else {
                    inner = vertices;
                    continue;
                };
                // a whole component within the cluster's reach has shrunk away
                let vanished = patch.loops.is_empty() && span(p, &vertices) < SPAN * s.h_min;
                let caps = if vanished { Some(Vec::new()) } else { patch.caps(p, tris, ears) };
                if let Some(caps) = caps {
                    for &t in &triangles {
                        dead[t] = true;
                    }
                    for &v in &vertices {
                        locked[v] = true;
                    }
                    removed += 1;
                    cut |= caps.len() != 1;
                    fans.extend(caps);
                    break 'ears;
                }
                inner = vertices;
            }
        }
    }
    if removed == 0 {
        return false;
    }
    let mut kept: Vec<[usize; 3]> = tris.iter().zip(&dead).filter(|(_, d)| !**d).map(|(t, _)| *t).collect();
    if kept.is_empty() && fans.is_empty() {
        return false; // the last component stays (its tangles end the run)
    }
    for cap in fans {
        match cap {
            Cap::Fan(centre, boundary) => {
                p.push(centre);
                let x = p.len() - 1;
                kept.extend((0..boundary.len()).map(|i| [boundary[i], boundary[(i + 1) % boundary.len()], x]));
            }
            Cap::Ears(triangles) => kept.extend(triangles),
        }
    }
    if cut {
        drop_slivers(p, &mut kept, (2.0 * s.h_min).powi(3));
    }
    *tris = kept;
    true
}

/// Drops the closed components that enclose less than `min_volume` (a cut at a
/// neck next to a spike's tip leaves the tip), unless that would drop them all.
fn drop_slivers(p: &[Point<3>], tris: &mut Vec<[usize; 3]>, min_volume: f64) {
    let (component, count) = components(p.len(), tris);
    let mut volume = vec![0.0; count];
    let mut reference = vec![None; count];
    for t in tris.iter() {
        let c = component[t[0]];
        let o: Point<3> = *reference[c].get_or_insert(p[t[0]]);
        let [x, y, z] = t.map(|v| p[v] - o);
        volume[c] += x.dot(&y.cross(&z)) / 6.0;
    }
    if volume.iter().any(|v| v.abs() >= min_volume) {
        tris.retain(|t| volume[component[t[0]]].abs() >= min_volume);
    }
}

/// The vertex sets (of two or more, each in increasing order) joined by edges
/// shorter than `tiny`, in the order of their second vertex.
fn clusters(p: &[Point<3>], adjacency: &Adjacency, tiny: f64) -> Vec<Vec<usize>> {
    let short: Vec<[usize; 2]> =
        adjacency.edges.iter().filter(|e| (p[e.b] - p[e.a]).norm() < tiny).map(|e| [e.a, e.b]).collect();
    if short.is_empty() {
        return Vec::new();
    }
    let (component, count) = components(p.len(), &short);
    let mut members = vec![Vec::new(); count];
    for (v, &c) in component.iter().enumerate() {
        members[c].push(v);
    }
    members.retain(|m| m.len() >= 2);
    members.sort_unstable_by_key(|m| m[1]);
    members
}

/// The diagonal of the bounding box of the vertices `vs`.
fn span(p: &[Point<3>], vs: &[usize]) -> f64 {
    let (lo, hi) = vs.iter().fold((p[vs[0]], p[vs[0]]), |(lo, hi), &v| (lo.inf(&p[v]), hi.sup(&p[v])));
    (hi - lo).norm()
}

/// The triangles that contain a vertex of `inner`, sorted.
fn star_of(adjacency: &Adjacency, inner: &[usize]) -> Vec<usize> {
    let mut triangles: Vec<usize> = inner.iter().flat_map(|&v| adjacency.stars.star(v).iter().copied()).collect();
    triangles.sort_unstable();
    triangles.dedup();
    triangles
}

/// The vertices of the triangles `triangles`, sorted.
fn vertices_of(tris: &[[usize; 3]], triangles: &[usize]) -> Vec<usize> {
    let mut vertices: Vec<usize> = triangles.iter().flat_map(|&t| tris[t]).collect();
    vertices.sort_unstable();
    vertices.dedup();
    vertices
}

/// What closes one boundary loop of a patch cut out.
enum Cap {
    /// A fan around a new vertex at the point, over the loop.
    Fan(Point<3>, Vec<usize>),
    /// Triangles between the loop's own vertices.
    Ears(Vec<[usize; 3]>),
}

/// A patch of triangles of genus 0 with one or two boundary loops.
struct Patch<'a> {
    triangles: &'a [usize],
    /// The boundary loops, each in the direction of its triangles.
    loops: Vec<Vec<usize>>,
}

impl<'a> Patch<'a> {
    /// The patch of `triangles` (on `vertices` vertices), if it is a disk, an
    /// annulus or a sphere: every boundary vertex starts exactly one boundary edge,
    /// and the Euler characteristic is 2 minus the number of loops.
    fn of(tris: &[[usize; 3]], triangles: &'a [usize], vertices: usize) -> Option<Patch<'a>> {
        let mut directed: Vec<(usize, usize)> =
            triangles.iter().flat_map(|&t| (0..3).map(move |k| (tris[t][k], tris[t][(k + 1) % 3]))).collect();
        directed.sort_unstable();
        let next: Vec<(usize, usize)> =
            directed.iter().copied().filter(|&(a, b)| directed.binary_search(&(b, a)).is_err()).collect();
        if (!next.is_empty() && next.len() < 3) || next.windows(2).any(|w| w[0].0 == w[1].0) {
            return None;
        }
        let step = |a: usize| next.binary_search_by(|e| e.0.cmp(&a)).ok().map(|k| next[k].1);
        let mut seen = vec![false; next.len()];
        let mut loops = Vec::new();
        while let Some(start) = seen.iter().position(|s| !s) {
            let mut lp = vec![next[start].0];
            seen[start] = true;
            let mut v = next[start].1;
            while v != lp[0] {
                let k = next.binary_search_by(|e| e.0.cmp(&v)).ok()?;
                seen[k] = true;
                lp.push(v);
                v = step(v)?;
            }
            loops.push(lp);
        }
        let edges = (directed.len() + next.len()) / 2;
        let chi = (vertices + triangles.len()) as i64 - edges as i64;
        (loops.len() <= 2 && loops.iter().all(|l| l.len() >= 3) && chi == 2 - loops.len() as i64)
            .then_some(Patch { triangles, loops })
    }

    /// One fan per boundary loop: its vertex above the loop's centroid along the
    /// loop's vector area `S_k`, at a height `s` common to the loops that keeps the
    /// enclosed volume (a fan's signed volume about a point `r` is `(x − r)·S_k/6`).
    /// A loop whose fan would have a degenerate or folded triangle (its normal
    /// against `S_k`) is closed by ears instead if `ears`; `None` if that fails
    /// too, or without `ears`.
    fn caps(&self, p: &[Point<3>], tris: &[[usize; 3]], ears: bool) -> Option<Vec<Cap>> {
        let all: Vec<usize> = self.loops.iter().flatten().copied().collect();
        let r = all.iter().fold(Point::<3>::zeros(), |acc, &v| acc + p[v]) / all.len() as f64;
        let volume: f64 = self
            .triangles
            .iter()
            .map(|&t| {
                let [x, y, z] = tris[t].map(|v| p[v] - r);
                x.dot(&y.cross(&z))
            })
            .sum();
        let centroid = |l: &[usize]| l.iter().fold(Point::<3>::zeros(), |acc, &v| acc + p[v]) / l.len() as f64;
        let area = |l: &[usize]| {
            (0..l.len()).fold(Point::<3>::zeros(), |acc, i| acc + (p[l[i]] - r).cross(&(p[l[(i + 1) % l.len()]] - r)))
        };
        let loops: Vec<(Point<3>, Point<3>)> = self.loops.iter().map(|l| (centroid(l), area(l))).collect();
        let flat: f64 = loops.iter().map(|(c, s)| (c - r).dot(s)).sum();
        let scale: f64 = loops.iter().map(|(_, s)| s.norm()).sum();
        if scale == 0.0 {
            return None;
        }
        let height = (volume - flat) / scale;
        let mut caps = Vec::with_capacity(self.loops.len());
        for (l, (c, s)) in self.loops.iter().zip(&loops) {
            let x = c + s.normalize() * height;
            let folds = (0..l.len()).any(|i| folded(p[l[i]], p[l[(i + 1) % l.len()]], x, s));
            caps.push(match (folds, ears) {
                (false, _) => Cap::Fan(x, l.clone()),
                (true, true) => Cap::Ears(ear_cap(p, l, s)?),
                (true, false) => return None,
            });
        }
        Some(caps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{icosphere, Mesh, SurfaceMesh};

    fn settings(h_min: f64) -> SurfaceRemeshSettings {
        SurfaceRemeshSettings { epsilon: 1.0, h_min, h_max: 10.0, max_angle_deg: 120.0 }
    }

    fn replaced(m: &SurfaceMesh, s: &SurfaceRemeshSettings) -> Option<SurfaceMesh> {
        let (mut p, mut t) = (m.positions().to_vec(), m.elements().to_vec());
        let adjacency = Adjacency::of(p.len(), &t);
        replace_clusters(&mut p, &mut t, &adjacency, s, &Frozen(&[])).then(|| {
            let mut used: Vec<usize> = t.iter().flatten().copied().collect();
            used.sort_unstable();
            used.dedup();
            let mut index = vec![usize::MAX; p.len()];
            for (k, &v) in used.iter().enumerate() {
                index[v] = k;
            }
            let t = t.iter().map(|tr| tr.map(|v| index[v])).collect();
            Mesh::new(used.iter().map(|&v| p[v]).collect(), t).unwrap()
        })
    }

    /// A crumpled spot on a sphere: one triangle divided again and again about a
    /// point near its centre, with heights of ±1e-5, into 61 triangles whose
    /// smallest edges are about 1e-5. The spot is replaced by one fan, and the
    /// enclosed volume is kept.
    #[test]
    fn a_crumpled_spot_becomes_one_fan_keeping_the_volume() {
        let sphere = icosphere([0.0; 3], 1.0, 2).unwrap();
        let (mut p, mut tris) = (sphere.positions().to_vec(), sphere.elements().to_vec());
        let t0 = tris[0];
        let centre = (p[t0[0]] + p[t0[1]] + p[t0[2]]) / 3.0;
        let normal = centre.normalize();
        // triangle k → three triangles about a point near the centre, repeatedly
        for k in 0..20 {
            let t =
                tris.swap_remove(tris.iter().position(|t| t.iter().all(|&v| (p[v] - centre).norm() < 0.2)).unwrap());
            let offset = Point::<3>::new((k as f64).sin(), (k as f64 * 1.7).cos(), 0.3) * 1e-5;
            let height = if k % 2 == 0 { 1e-5 } else { -1e-5 };
            p.push(centre + offset + normal * height);
            let x = p.len() - 1;
            tris.extend([[t[0], t[1], x], [t[1], t[2], x], [t[2], t[0], x]]);
        }
        let spot = Mesh::new(p, tris).unwrap();
        let s = settings(0.05);
        let out = replaced(&spot, &s).expect("the spot is replaced");
        let q = out.quality();
        assert!(q.min_edge > 0.05, "{q:?}");
        assert_eq!(out.component_labels().1, 1);
        let (v0, v1) = (spot.enclosed_measure(), out.enclosed_measure());
        assert!((v1 - v0).abs() < 1e-12 * v0, "{v0} {v1}");
        // a sphere without tiny edges is left as it is
        assert!(replaced(&sphere, &s).is_none());
    }

    /// A sphere shrunk to a radius of 1e-4 beside a sphere of radius 1: the small
    /// one, all of whose edges are tiny, has vanished and is removed; alone it
    /// stays (the mesh is never emptied).
    #[test]
    fn a_component_shrunk_below_h_min_vanishes_unless_it_is_the_last() {
        let big = icosphere([0.0; 3], 1.0, 2).unwrap();
        let small = icosphere([3.0, 0.0, 0.0], 1e-4, 1).unwrap();
        let n = big.num_vertices();
        let p: Vec<Point<3>> = big.positions().iter().chain(small.positions()).copied().collect();
        let t: Vec<[usize; 3]> =
            big.elements().iter().copied().chain(small.elements().iter().map(|t| t.map(|v| v + n))).collect();
        let both = Mesh::new(p, t).unwrap();
        let s = settings(0.05);
        let out = replaced(&both, &s).expect("the small sphere vanishes");
        assert_eq!(out.component_labels().1, 1);
        assert!((out.enclosed_measure() - big.enclosed_measure()).abs() < 1e-12);
        assert!(replaced(&small, &s).is_none());
    }

    /// A sphere pinched at its equator to a ring of radius 1e-4: the band around
    /// the ring is an annulus; both sides are capped, the surface pinches off into
    /// two closed pieces, and their volumes add up to the pinched sphere's.
    #[test]
    fn a_neck_thinner_than_h_min_pinches_off() {
        let (n, rings) = (12usize, 9usize);
        let mut p = vec![Point::<3>::new(0.0, 0.0, 1.0)];
        for r in 1..rings {
            let theta = std::f64::consts::PI * r as f64 / rings as f64;
            let radius = if r == rings / 2 { 1e-4 } else { theta.sin() };
            for k in 0..n {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                p.push(Point::<3>::new(radius * phi.cos(), radius * phi.sin(), theta.cos()));
            }
        }
        p.push(Point::<3>::new(0.0, 0.0, -1.0));
        let south = p.len() - 1;
        let at = |r: usize, k: usize| 1 + (r - 1) * n + k % n;
        let mut tris = Vec::new();
        for k in 0..n {
            tris.push([0, at(1, k), at(1, k + 1)]);
            for r in 1..rings - 1 {
                tris.push([at(r, k), at(r + 1, k), at(r + 1, k + 1)]);
                tris.push([at(r, k), at(r + 1, k + 1), at(r, k + 1)]);
            }
            tris.push([south, at(rings - 1, k + 1), at(rings - 1, k)]);
        }
        let pinched = Mesh::new(p, tris).unwrap();
        let v0 = pinched.enclosed_measure();
        assert!(v0 > 0.0);
        let out = replaced(&pinched, &settings(0.05)).expect("the neck is cut");
        assert_eq!(out.component_labels().1, 2);
        let v1 = out.enclosed_measure();
        assert!((v1 - v0).abs() < 1e-12 * v0, "{v0} {v1}");
    }

    /// A patch whose boundary is a comb (seen along its normal, not star-shaped
    /// about its centroid): no fan closes it without folding, the ears do.
    #[test]
    fn a_comb_shaped_patch_is_closed_by_ears_only_when_asked() {
        let p = super::super::ears::tests::comb(|x, y| 0.01 * x * y);
        let l: Vec<usize> = (0..p.len()).collect();
        let tris = ear_cap(&p, &l, &Point::<3>::z()).unwrap();
        let all: Vec<usize> = (0..tris.len()).collect();
        let patch = Patch::of(&tris, &all, p.len()).expect("a disk");
        assert_eq!(patch.loops.len(), 1);
        assert!(patch.caps(&p, &tris, false).is_none());
        let caps = patch.caps(&p, &tris, true).unwrap();
        assert!(matches!(&caps[..], [Cap::Ears(t)] if t.len() == p.len() - 2));
    }
}
