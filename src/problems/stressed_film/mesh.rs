//! Triangulation of the film `Ω` in its cell: the free surface cut at the lateral
//! walls, the walls and the substrate as Dirichlet boundaries, the voids as holes.

use super::FilmCell;
use crate::bulk::{triangulate, BulkError, DomainMesh, MeshingOptions};
use crate::geometry::{CurveMesh, Point};

/// Meshes the film below the curve `Γ`, which must have exactly one component
/// winding around the period (the free surface, crossing the line `x ≡ 0 mod L`
/// once, above the substrate) and any number of closed ones (voids) that stay
/// inside `0 < x < L` and above `y = 0`. Walls and substrate are sampled at the
/// mean segment length of `Γ`. The first vertices are those of `Γ`, in its order,
/// placed in the cell `0 ≤ x ≤ L` (voids entirely inside it); the two points where
/// the film surface meets the walls and the sampled walls and substrate follow; the
/// walls and the substrate are its Dirichlet vertices.
pub fn film_mesh(cell: &FilmCell, curve: &CurveMesh, opts: &MeshingOptions) -> Result<DomainMesh, BulkError> {
    let l = cell.length;
    let bad = |m: &str| BulkError::Inadmissible(m.to_string());
    let windings = curve.windings();
    if windings.iter().filter(|&&w| w == 1).count() != 1 || curve.period() != Some(l) {
        return Err(bad("the film surface must be one periodic curve across the cell"));
    }
    let nc = curve.num_vertices();
    let mut cell_pos = vec![Point::<2>::zeros(); nc];
    let mut edges: Vec<[usize; 2]> = Vec::with_capacity(nc + 64);
    let mut wall_top = None;
    for ((cycle, (pts, shift)), w) in curve.cycles().iter().zip(curve.lifted_cycles()).zip(&windings) {
        let n = cycle.len();
        if *w == 0 {
            // a void: shifted to the cell by its first vertex, then checked
            let dx = -l * (pts[0].x / l).floor();
            for (k, &v) in cycle.iter().enumerate() {
                let p = pts[k] + Point::<2>::new(dx, 0.0);
                if !(p.x > 0.0 && p.x < l && p.y > 0.0) {
                    return Err(bad("a void meets a lateral wall or the substrate"));
                }
                cell_pos[v] = p;
                edges.push([v, cycle[(k + 1) % n]]);
            }
            continue;
        }
        // the film surface: the segment that crosses a multiple of L
        let at = |k: usize| if k < n { pts[k] } else { pts[k - n] + shift };
        let crossings: Vec<usize> = (0..n).filter(|&k| (at(k).x / l).floor() != (at(k + 1).x / l).floor()).collect();
        if crossings.len() != 1 {
            return Err(bad("the film surface must meet each lateral wall once (it overhangs a wall)"));
        }
        let k0 = crossings[0];
        let m = (at(k0 + 1).x / l).floor();
        let (a, b) = (at(k0), at(k0 + 1));
        let y0 = a.y + (b.y - a.y) * (m * l - a.x) / (b.x - a.x);
        if !(y0 > 0.0) {
            return Err(bad("the film surface meets the substrate"));
        }
        // vertices k0+1 .. k0+n in the cell frame
        for j in 1..=n {
            let (k, v) = (k0 + j, cycle[(k0 + j) % n]);
            let p = at(k) - Point::<2>::new(m * l, 0.0);
            if !(p.y > 0.0) {
                return Err(bad("the film surface meets the substrate"));
            }
            cell_pos[v] = p;
            if j < n {
                edges.push([v, cycle[(k + 1) % n]]);
            }
        }
        wall_top = Some((y0, cycle[(k0 + 1) % n], cycle[k0]));
    }
    let (y0, first, last) = wall_top.expect("one film surface");
    // the walls and the substrate, from the top of the left wall round to the top
    // of the right one; a film vertex within `snap` of a wall is its top itself
    let h = curve.boundary_measure() / curve.num_elements() as f64;
    let snap = 1e-3 * h;
    let left = (cell_pos[first].x < snap).then_some(first);
    let right = (cell_pos[last].x > l - snap).then_some(last);
    let (y_left, y_right) = (left.map_or(y0, |v| cell_pos[v].y), right.map_or(y0, |v| cell_pos[v].y));
    if let Some(v) = left {
        cell_pos[v].x = 0.0;
    }
    if let Some(v) = right {
        cell_pos[v].x = l;
    }
    let corners =
        [Point::<2>::new(0.0, y_left), Point::<2>::new(0.0, 0.0), Point::<2>::new(l, 0.0), Point::<2>::new(l, y_right)];
    let mut path: Vec<Point<2>> = Vec::new();
    for i in 0..3 {
        let (from, to) = (corners[i], corners[i + 1]);
        let k = ((to - from).norm() / h).ceil().max(1.0) as usize;
        path.extend((0..k).map(|j| from + (to - from) * (j as f64 / k as f64)));
    }
    path.push(corners[3]);
    let mut vertices = cell_pos;
    let np = path.len();
    let mut ids = Vec::with_capacity(np);
    for (j, p) in path.into_iter().enumerate() {
        match (j, left, right) {
            (0, Some(v), _) => ids.push(v),
            (j, _, Some(v)) if j == np - 1 => ids.push(v),
            _ => {
                ids.push(vertices.len());
                vertices.push(p);
            }
        }
    }
    edges.extend(ids.windows(2).map(|w| [w[0], w[1]]));
    if left.is_none() {
        edges.push([first, ids[0]]);
    }
    if right.is_none() {
        edges.push([last, ids[np - 1]]);
    }
    let t = triangulate(&vertices, &edges, |_, _| (true, false), nc, opts)?;
    let on_wall = |i: usize| i != usize::MAX && (i >= nc || Some(i) == left || Some(i) == right);
    let dirichlet = t.input_of.iter().map(|&i| on_wall(i)).collect();
    Ok(DomainMesh { points: t.points, triangles: t.triangles, dirichlet, curve_vertices: nc })
}
