//! Two sheets of a closed surface that nearly touch, joined on the mesh itself
//! (the zippering of El Topo, Brochu & Bridson 2009): on each sheet the patch
//! closer to the other sheet than half the reach is removed, and the two holes
//! are bridged by a tube of triangles whose rungs join the holes' rims in the
//! order of their angle around the axis between the sheets. The rest of the
//! mesh is left as it is. Sheets of two components become one component; two
//! sheets of one component make a handle.

use super::{Mesh, Point, SurfaceMesh};
use facing::Facing;
use std::collections::{HashMap, HashSet};

mod facing;

/// The closest two vertices closer than `reach` whose sheets face each other:
/// each lies in front of the other along its outward normal, and the normals are
/// nearly opposite. Neighbours on one smooth sheet never do; two sheets that the
/// flow brought together (of two components, or of one) do. `None` if no two do.
pub fn closest_facing_vertices(mesh: &SurfaceMesh, reach: f64) -> Option<(usize, usize)> {
    (reach > 0.0).then(|| Facing::new(mesh, reach).closest_pair())?
}

/// `mesh` with the sheets at vertices `a` and `b` joined: on each, the patch
/// around the vertex that lies closer than `reach / 2` to the other sheet (at
/// least the vertex's star) removed, and the two rims bridged by a tube. `None`
/// where the patches share a vertex, a rim is not one simple loop, a rim does
/// not turn once around the axis from `a` to `b` in one sense (the two in
/// opposite senses, as facing sheets' rims do), or the result is not a valid
/// closed surface. The tube is not checked against the rest of the surface:
/// the caller checks the result for intersections.
pub fn zip_sheets(mesh: &SurfaceMesh, a: usize, b: usize, reach: f64) -> Option<SurfaceMesh> {
    let x = mesh.positions();
    let facing = Facing::new(mesh, reach);
    let (patch_a, patch_b) = (facing.patch(a, 0.5 * reach)?, facing.patch(b, 0.5 * reach)?);
    let corners = |s: &[usize]| -> HashSet<usize> { s.iter().flat_map(|&t| mesh.elements()[t]).collect() };
    if !corners(&patch_a).is_disjoint(&corners(&patch_b)) {
        return None;
    }
    let removed: HashSet<usize> = patch_a.iter().chain(&patch_b).copied().collect();
    let kept: Vec<[usize; 3]> =
        mesh.elements().iter().enumerate().filter(|(i, _)| !removed.contains(i)).map(|(_, &t)| t).collect();
    let rim_a = rim(&kept, &patch_a, mesh.elements())?;
    let rim_b = rim(&kept, &patch_b, mesh.elements())?;
    // the axis: from the sheet at `a` to the one at `b` (their normals' difference,
    // which stays a direction where the two are a hair apart)
    let axis = (facing.normal(a) - facing.normal(b)).try_normalize(1e-12)?;
    let mean = |rim: &[usize]| rim.iter().fold(Point::<3>::zeros(), |s, &v| s + x[v]) / rim.len() as f64;
    let centre = (mean(&rim_a) + mean(&rim_b)) * 0.5;
    let helper = if axis[0].abs() < 0.9 { Point::<3>::new(1.0, 0.0, 0.0) } else { Point::<3>::new(0.0, 1.0, 0.0) };
    let e1 = axis.cross(&helper).normalize();
    let e2 = axis.cross(&e1);
    let angle = |v: usize| {
        let r = x[v] - centre;
        r.dot(&e2).atan2(r.dot(&e1))
    };
    let (turns_a, angles_a) = turning(&rim_a, angle)?;
    let (turns_b, _) = turning(&rim_b, angle)?;
    if turns_a != -turns_b {
        return None;
    }
    // the second rim against its own direction turns as the first; both as
    // increasing angles from the first rim's first corner, the second starting
    // at its corner nearest to that one in angle
    let s = f64::from(turns_a);
    let mut other: Vec<usize> = rim_b.iter().rev().copied().collect();
    let off = |v: usize| wrapped(s * (angle(v) - angles_a[0]));
    let start = (0..other.len()).min_by(|&i, &j| off(other[i]).abs().total_cmp(&off(other[j]).abs()))?;
    other.rotate_left(start);
    let alpha = unwrapped(&rim_a, |v| s * angle(v));
    let alpha: Vec<f64> = alpha.iter().map(|t| t - alpha[0]).collect();
    let beta = unwrapped(&other, |v| s * angle(v));
    let beta: Vec<f64> = beta.iter().map(|t| t - beta[0] + off(other[0])).collect();
    let (n, m) = (rim_a.len(), other.len());
    let next_a = |i: usize| if i + 1 < n { alpha[i + 1] } else { alpha[0] + std::f64::consts::TAU };
    let next_b = |j: usize| if j + 1 < m { beta[j + 1] } else { beta[0] + std::f64::consts::TAU };
    // (where that would turn a kept triangle over, the rims stay where they are)
    let moved = onto_one_cylinder(x, &kept, [&rim_a, &rim_b], centre, axis).unwrap_or_else(|| x.to_vec());
    let mut triangles = kept;
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        if j == m || (i < n && next_a(i) <= next_b(j)) {
            triangles.push([rim_a[(i + 1) % n], rim_a[i], other[j % m]]);
            i += 1;
        } else {
            triangles.push([other[j], other[(j + 1) % m], rim_a[i % n]]);
            j += 1;
        }
    }
    let (used, triangles) = super::unions::used_vertices(&moved, &triangles);
    match Mesh::new(used, triangles) {
        Ok(m) => Some(m),
        Err(e) => {
            tracing::debug!("a zipped surface is not a closed surface: {e}");
            None
        }
    }
}

/// The rim of the patch `patch` (triangle indices into `all`) as the kept
/// triangles run along it: each corner followed by the next along a kept
/// triangle's edge whose reverse is in the patch. `None` unless that is one
/// simple loop of at least three corners.
fn rim(kept: &[[usize; 3]], patch: &[usize], all: &[[usize; 3]]) -> Option<Vec<usize>> {
    let removed: HashSet<(usize, usize)> =
        patch.iter().flat_map(|&t| (0..3).map(move |k| (all[t][k], all[t][(k + 1) % 3]))).collect();
    let mut next: HashMap<usize, usize> = HashMap::new();
    for t in kept {
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            if removed.contains(&(q, p)) && next.insert(p, q).is_some() {
                return None;
            }
        }
    }
    let first = *next.keys().min()?;
    let mut loop_ = vec![first];
    let mut c = next[&first];
    while c != first {
        if loop_.len() > next.len() {
            return None;
        }
        loop_.push(c);
        c = *next.get(&c)?;
    }
    (loop_.len() == next.len() && loop_.len() >= 3).then_some(loop_)
}

/// The positions `x` with the corners of both rims moved across the axis
/// (through `centre` along `axis`) onto one cylinder around it, of their mean
/// distance from it: the tube's rungs then run along the cylinder, not over
/// one sheet's kept triangles beside the other's rim (which a chord to a rim
/// further out passes below, the sheets curving away from each other). `None`
/// if a kept triangle at a rim would turn over.
fn onto_one_cylinder(
    x: &[Point<3>],
    kept: &[[usize; 3]],
    rims: [&[usize]; 2],
    centre: Point<3>,
    axis: Point<3>,
) -> Option<Vec<Point<3>>> {
    let across = |p: &Point<3>| {
        let r = p - centre;
        r - axis * r.dot(&axis)
    };
    let corners = || rims.iter().flat_map(|r| r.iter().copied());
    let radius = corners().map(|v| across(&x[v]).norm()).sum::<f64>() / corners().count() as f64;
    let mut moved = x.to_vec();
    for v in corners() {
        let r = across(&x[v]);
        moved[v] = x[v] + r * (radius / r.norm() - 1.0);
    }
    let on_rim: HashSet<usize> = corners().collect();
    let normal = |p: &[Point<3>], t: &[usize; 3]| (p[t[1]] - p[t[0]]).cross(&(p[t[2]] - p[t[0]]));
    let turned = kept
        .iter()
        .filter(|t| t.iter().any(|v| on_rim.contains(v)))
        .any(|t| normal(x, t).dot(&normal(&moved, t)) <= 0.0);
    (!turned && radius > 0.0).then_some(moved)
}

/// How many times the closed loop `corners` turns around the axis by `angle`
/// (+1 or −1) and the corners' angles; `None` unless it turns once, every step
/// in the same sense by less than half a turn.
fn turning(corners: &[usize], angle: impl Fn(usize) -> f64) -> Option<(i32, Vec<f64>)> {
    let angles: Vec<f64> = corners.iter().map(|&v| angle(v)).collect();
    let steps: Vec<f64> = (0..angles.len()).map(|k| wrapped(angles[(k + 1) % angles.len()] - angles[k])).collect();
    let total: f64 = steps.iter().sum();
    let sense = if total > 0.0 { 1.0 } else { -1.0 };
    let once = (total.abs() - std::f64::consts::TAU).abs() < 1e-6;
    (once && steps.iter().all(|&d| d * sense > 0.0)).then_some((sense as i32, angles))
}

/// `d` wrapped into `(−π, π]`.
fn wrapped(d: f64) -> f64 {
    let w = d.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

/// The angles `angle(corner)` along `corners`, unwrapped into an increasing sequence.
fn unwrapped(corners: &[usize], angle: impl Fn(usize) -> f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(corners.len());
    let mut last = angle(corners[0]);
    out.push(last);
    for &v in &corners[1..] {
        last += (angle(v) - last).rem_euclid(std::f64::consts::TAU);
        out.push(last);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{box_surface, ellipsoid, icosphere, surface_intersections, surface_union};

    fn euler(m: &SurfaceMesh) -> i64 {
        let edges: HashSet<(usize, usize)> = m
            .elements()
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
            .collect();
        m.num_vertices() as i64 - edges.len() as i64 + m.num_elements() as i64
    }

    /// Two spheres a hair apart join into one closed surface of genus 0 that meets
    /// itself nowhere and encloses the two volumes (the tube adds a little); its
    /// vertices are theirs less the two removed.
    #[test]
    fn two_spheres_a_hair_apart_zip_into_one() {
        let a = icosphere([-1.005, 0.0, 0.0], 1.0, 3).unwrap();
        let b = ellipsoid([1.01, 0.02, -0.01], [1.0, 0.9, 1.1], 3).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let (p, q) = closest_facing_vertices(&two, 0.1).expect("the facing poles");
        let one = zip_sheets(&two, p, q, 0.1).expect("zipped");
        assert_eq!(one.component_labels().1, 1);
        assert_eq!(euler(&one), 2);
        assert!(one.num_vertices() < two.num_vertices());
        assert!(surface_intersections(one.positions(), one.elements(), 1).is_empty());
        let (v0, v1) = (two.enclosed_measure(), one.enclosed_measure());
        assert!(v1 > v0 && v1 / v0 - 1.0 < 1e-3, "{v0} → {v1}");
        // spheres apart by more than the reach face each other nowhere
        let far =
            surface_union(&[icosphere([-1.2, 0.0, 0.0], 1.0, 3).unwrap(), icosphere([1.2, 0.0, 0.0], 1.0, 3).unwrap()]);
        assert!(closest_facing_vertices(&far.unwrap(), 0.1).is_none());
        // nor does a sphere's own surface
        assert!(closest_facing_vertices(&icosphere([0.0; 3], 1.0, 4).unwrap(), 0.5).is_none());
    }

    /// Two cigars side by side, zipped at two places along their length, make
    /// one surface with a handle (χ = 0) that meets itself nowhere; a vertex and
    /// its neighbour (stars that share vertices) are not zipped.
    #[test]
    fn two_zips_between_two_cigars_make_a_handle() {
        let a = ellipsoid([0.0, -0.305, 0.0], [1.0, 0.3, 0.3], 3).unwrap();
        let b = ellipsoid([0.0, 0.305, 0.0], [1.0, 0.3, 0.3], 3).unwrap();
        let mut m = surface_union(&[a, b]).unwrap();
        for x in [-0.5, 0.5] {
            let at = Point::<3>::new(x, 0.0, 0.0);
            let nearest = |below: bool| {
                (0..m.num_vertices())
                    .filter(|&v| (m.positions()[v][1] < 0.0) == below)
                    .min_by(|&u, &v| (m.positions()[u] - at).norm().total_cmp(&(m.positions()[v] - at).norm()))
                    .unwrap()
            };
            let (p, q) = (nearest(true), nearest(false));
            m = zip_sheets(&m, p, q, 0.1).expect("zipped");
            assert_eq!(m.component_labels().1, 1);
            assert!(surface_intersections(m.positions(), m.elements(), 1).is_empty());
        }
        assert_eq!(euler(&m), 0);
        let t = m.elements()[0];
        assert!(zip_sheets(&m, t[0], t[1], 0.1).is_none());
    }

    /// Two cubes face to face a hair apart (a flat contact over a whole face, as
    /// the flow's contact rule leaves two sheets pressed together): the patches
    /// are the facing faces, and the zipped surface is one that meets itself
    /// nowhere, of the two volumes.
    #[test]
    fn two_cubes_pressed_together_zip_across_their_faces() {
        let a = box_surface([-0.5005, 0.0, 0.0], [1.0, 1.0, 1.0], 6.0).unwrap();
        let b = box_surface([0.5005, 0.1, 0.0], [1.0, 1.0, 1.0], 6.0).unwrap();
        let two = surface_union(&[a, b]).unwrap();
        let (p, q) = closest_facing_vertices(&two, 0.2).expect("the facing faces");
        let one = zip_sheets(&two, p, q, 0.2).expect("zipped");
        assert_eq!(one.component_labels().1, 1);
        assert_eq!(euler(&one), 2);
        assert!(surface_intersections(one.positions(), one.elements(), 1).is_empty());
        let (v0, v1) = (two.enclosed_measure(), one.enclosed_measure());
        assert!((v1 / v0 - 1.0).abs() < 0.05, "{v0} → {v1}");
    }
}
