//! The geometry that makes a 2D result visible in every glTF viewer: the region a
//! set of closed curves encloses, triangulated (holes respected), and each curve as
//! a thin ribbon of triangles. Renderers draw no lines (Blender) or hairlines
//! (model-viewer, three.js); triangles they all draw.

use crate::flow::MeshData;
use crate::geometry::{
    bounding_box, find_segment_intersections, in_box, segment_cycles, winding_number, BoxGrid, Point,
};

/// Width of the curve ribbons, relative to the diagonal of the curves' bounding box.
pub(super) const RIBBON_WIDTH: f64 = 0.004;

/// What shows a 2D state in renderers that draw no lines: the region its curves
/// enclose, triangulated, and a ribbon along each curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Filled {
    /// The region's points and triangles (none if the curves enclose nothing).
    pub points: Vec<[f64; 2]>,
    pub region: Vec<[usize; 3]>,
    /// The ribbons' vertices and triangles, and the state's vertex behind each
    /// ribbon vertex (for its colour).
    pub ribbon_points: Vec<[f64; 2]>,
    pub ribbon_triangles: Vec<[u32; 3]>,
    pub ribbon_source: Vec<usize>,
    /// The ribbons' width.
    pub width: f64,
}

impl Filled {
    /// The region and ribbons of the curves of `m`; `None` for surfaces, an empty
    /// state, or curves that cross (no region to fill). Periodic curves (the
    /// stressed film) are drawn over one period, lifted: the region is the film
    /// between its surface and the substrate `y = 0`, voids left open.
    pub fn of(m: &MeshData) -> Option<Filled> {
        if m.dimension != 2 || m.elements.is_empty() {
            return None;
        }
        let drawing = Drawing::of(m);
        let region = region_triangles(&drawing.points, &drawing.region)?;
        let width = RIBBON_WIDTH * bounding_diagonal(&drawing.points);
        let (mut ribbon_points, mut ribbon_triangles, mut ribbon_source) = (Vec::new(), Vec::new(), Vec::new());
        for (l, closed) in &drawing.curves {
            let (v, t) = ribbon(&drawing.points, l, width, *closed);
            let base = ribbon_points.len() as u32;
            ribbon_points.extend(v);
            ribbon_source.extend(l.iter().flat_map(|&i| [drawing.source[i]; 2]));
            ribbon_triangles.extend(t.iter().map(|t| t.map(|i| i + base)));
        }
        Some(Filled { points: drawing.points, region, ribbon_points, ribbon_triangles, ribbon_source, width })
    }
}

/// The diagonal of the bounding box of `points` (ribbons are a share of it wide:
/// the curves' for a frame, `Σ`'s for the domain).
pub(super) fn bounding_diagonal(points: &[[f64; 2]]) -> f64 {
    let b = bounding_box(points.iter().copied());
    (b[2] - b[0]).hypot(b[3] - b[1])
}

/// The curves of a 2D state as drawn in the plane: points (periodic components
/// lifted over one period), each curve with whether it is closed, the polygons
/// whose even–odd interior is the region, and the state's vertex behind each point.
struct Drawing {
    pub points: Vec<[f64; 2]>,
    pub source: Vec<usize>,
    pub curves: Vec<(Vec<usize>, bool)>,
    pub region: Vec<Vec<usize>>,
}

impl Drawing {
    fn of(m: &MeshData) -> Drawing {
        let cycles = segment_cycles(m.positions.len(), m.elements.iter().map(|e| (e[0], e[1])));
        let Some(period) = m.period else {
            let points = m.positions.iter().map(|p| [p[0], p[1]]).collect();
            let curves = cycles.iter().map(|c| (c.clone(), true)).collect();
            return Drawing { points, source: (0..m.positions.len()).collect(), curves, region: cycles };
        };
        let mut d = Drawing { points: Vec::new(), source: Vec::new(), curves: Vec::new(), region: Vec::new() };
        for mut cycle in cycles {
            let (dx, winds) = super::lift_component(m, &mut cycle, period);
            let start = d.points.len();
            for (k, &v) in cycle.iter().enumerate() {
                d.points.push([m.positions[v][0] + dx[k], m.positions[v][1]]);
                d.source.push(v);
            }
            let l: Vec<usize> = (start..d.points.len()).collect();
            d.curves.push((l.clone(), !winds));
            let mut polygon = l;
            if winds {
                // down to the substrate at both ends of the period
                let (first, last) = (d.points[start], d.points[d.points.len() - 1]);
                for (p, v) in [([last[0], 0.0], cycle[cycle.len() - 1]), ([first[0], 0.0], cycle[0])] {
                    polygon.push(d.points.len());
                    d.points.push(p);
                    d.source.push(v);
                }
            }
            d.region.push(polygon);
        }
        d
    }
}

/// The triangles of the region enclosed by the closed polygons `loops` (indices
/// into `points`), by the even–odd rule: each loop is nested in the loops around
/// it, a loop inside an even number of others bounds the region from outside and
/// one inside an odd number is a hole of the innermost loop around it; each outer
/// loop with its holes is cut into ears (`earcut`, the triangulation renderers use
/// to fill shapes: robust and quick on round contours, whose nearly cocircular
/// points make a Delaunay triangulation fall back to exact arithmetic). Triangles
/// use the input indices only and turn counter-clockwise. `None` when segments
/// cross or touch (no region to fill).
pub fn region_triangles(points: &[[f64; 2]], loops: &[Vec<usize>]) -> Option<Vec<[usize; 3]>> {
    let loops: Vec<&[usize]> = loops.iter().map(|l| l.as_slice()).filter(|l| l.len() >= 3).collect();
    let segments: Vec<[usize; 2]> =
        loops.iter().flat_map(|l| (0..l.len()).map(move |k| [l[k], l[(k + 1) % l.len()]])).collect();
    let at: Vec<Point<2>> = points.iter().map(|p| Point::<2>::new(p[0], p[1])).collect();
    if !find_segment_intersections(&at, &segments).is_empty() {
        return None;
    }
    let rings: Vec<Vec<Point<2>>> = loops.iter().map(|l| l.iter().map(|&v| at[v]).collect()).collect();
    let boxes: Vec<[f64; 4]> = loops.iter().map(|l| bounding_box(l.iter().map(|&v| points[v]))).collect();
    let grid = BoxGrid::new(&boxes);
    // the loops around each loop (its first point inside them: loops do not touch)
    let around: Vec<Vec<usize>> = (0..loops.len())
        .map(|i| {
            let p = points[loops[i][0]];
            let candidates = grid.at(p);
            candidates
                .filter(|&j| j != i && in_box(&boxes[j], p) && winding_number(&[&rings[j]], at[loops[i][0]]) != 0)
                .collect()
        })
        .collect();
    let mut holes: Vec<Vec<usize>> = vec![Vec::new(); loops.len()];
    for (i, a) in around.iter().enumerate() {
        if a.len() % 2 == 1 {
            // the innermost loop around it: the one with the most loops around itself
            let parent = *a.iter().max_by_key(|&&j| around[j].len()).expect("odd, so not empty");
            holes[parent].push(i);
        }
    }
    let mut earcut = earcut::Earcut::new();
    let (mut local, mut index, mut starts, mut out) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut triangles = Vec::new();
    for (i, l) in loops.iter().enumerate() {
        if around[i].len() % 2 == 1 {
            continue;
        }
        index.clear();
        starts.clear();
        index.extend_from_slice(l);
        for &h in &holes[i] {
            starts.push(index.len() as u32);
            index.extend_from_slice(loops[h]);
        }
        local.clear();
        local.extend(index.iter().map(|&v| points[v]));
        earcut.earcut_slice(&local, &starts, &mut out);
        for t in out.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|k| index[k as usize]);
            // counter-clockwise, as the ribbons and the domain's faces
            triangles.push(if cross(points[a], points[b], points[c]) < 0.0 { [a, c, b] } else { [a, b, c] });
        }
    }
    Some(triangles)
}

/// Twice the signed area of the triangle `a b c`.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// A ribbon of width `width` along the polygon `l` of `points` (closed, or an open
/// polyline): two
/// vertices per polygon vertex, offset by `±width/2` along the vertex normal (the
/// bisector of the two segments' normals), and two triangles per segment. Returns
/// the ribbon's vertices (`2k` inner side, `2k + 1` outer side of vertex `k`) and
/// triangles (counter-clockwise seen from `+z` for a counter-clockwise loop).
pub fn ribbon(points: &[[f64; 2]], l: &[usize], width: f64, closed: bool) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let n = l.len();
    let mut vertices = Vec::with_capacity(2 * n);
    for k in 0..n {
        // an open polyline's ends take the tangent of their one segment
        let (before, after) = match closed {
            true => ((k + n - 1) % n, (k + 1) % n),
            false => (k.saturating_sub(1), (k + 1).min(n - 1)),
        };
        let (a, b, c) = (points[l[before]], points[l[k]], points[l[after]]);
        let (tx, ty) = (c[0] - a[0], c[1] - a[1]);
        let len = tx.hypot(ty);
        let (nx, ny) = if len > 0.0 { (ty / len, -tx / len) } else { (0.0, 0.0) };
        let h = 0.5 * width;
        vertices.push([b[0] - h * nx, b[1] - h * ny]);
        vertices.push([b[0] + h * nx, b[1] + h * ny]);
    }
    let mut triangles = Vec::with_capacity(2 * n);
    for k in 0..if closed { n } else { n.saturating_sub(1) } {
        let (i0, o0, i1, o1) = (2 * k, 2 * k + 1, 2 * ((k + 1) % n), 2 * ((k + 1) % n) + 1);
        triangles.push([i0 as u32, o0 as u32, o1 as u32]);
        triangles.push([i0 as u32, o1 as u32, i1 as u32]);
    }
    (vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(points: &[[f64; 2]], tris: &[[usize; 3]]) -> f64 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| points[i]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
            })
            .sum()
    }

    /// A square of side 4 with a square hole of side 2: the region has area 12, and
    /// no triangle lies in the hole.
    #[test]
    fn a_square_with_a_hole() {
        let points = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [1.0, 1.0], [1.0, 3.0], [3.0, 3.0], [3.0, 1.0]];
        let loops = vec![vec![0, 1, 2, 3], vec![4, 5, 6, 7]];
        let tris = region_triangles(&points, &loops).unwrap();
        assert!((area(&points, &tris) - 12.0).abs() < 1e-12);
        assert_eq!(tris.len(), 8);
        // the outer square alone
        let loops = vec![vec![0, 1, 2, 3]];
        assert!((area(&points[..4], &region_triangles(&points[..4], &loops).unwrap()) - 16.0).abs() < 1e-12);
        // crossing segments: no fill
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(region_triangles(&bow, &[vec![0, 1, 2, 3]]).is_none());
    }

    /// Nested loops by the even–odd rule: an island inside the hole is filled again,
    /// every triangle turns counter-clockwise, and a round contour of 256 nearly
    /// cocircular points is cut into its 254 triangles with its polygon's area.
    #[test]
    fn nested_loops_and_a_round_contour() {
        let square = |c: f64, r: f64, clockwise: bool| {
            let mut s = vec![[c - r, c - r], [c + r, c - r], [c + r, c + r], [c - r, c + r]];
            if clockwise {
                s.reverse();
            }
            s
        };
        // outer side 8, hole side 6, island side 2, and a separate square beside them
        let mut points = square(4.0, 4.0, false);
        points.extend(square(4.0, 3.0, true));
        points.extend(square(4.0, 1.0, false));
        points.extend(square(12.0, 1.0, true));
        let loops: Vec<Vec<usize>> = (0..4).map(|k| (4 * k..4 * k + 4).collect()).collect();
        let tris = region_triangles(&points, &loops).unwrap();
        assert!((area(&points, &tris) - (64.0 - 36.0 + 4.0 + 4.0)).abs() < 1e-12);
        for t in &tris {
            let [a, b, c] = t.map(|i| points[i]);
            assert!(cross(a, b, c) > 0.0, "{t:?}");
        }
        let n = 256;
        let circle: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                [t.cos(), t.sin()]
            })
            .collect();
        let tris = region_triangles(&circle, &[(0..n).collect()]).unwrap();
        assert_eq!(tris.len(), n - 2);
        let polygon = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin();
        assert!((area(&circle, &tris) - polygon).abs() < 1e-12);
        // two loops that touch at a corner: no fill
        let touching = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]];
        assert!(region_triangles(&touching, &[vec![0, 1, 2, 3], vec![4, 5, 6, 7]]).is_none());
    }

    /// The ribbon of a square has its inner and outer sides at ±w/2 (on the
    /// bisectors at the corners) and covers the band between them.
    #[test]
    fn a_ribbon_around_a_square() {
        let points = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let (v, t) = ribbon(&points, &[0, 1, 2, 3], 0.2, true);
        assert_eq!((v.len(), t.len()), (8, 8));
        let r = 0.1 / std::f64::consts::SQRT_2;
        assert!((v[0][0] - r).abs() < 1e-12 && (v[0][1] - r).abs() < 1e-12, "{:?}", v[0]);
        assert!((v[1][0] + r).abs() < 1e-12 && (v[1][1] + r).abs() < 1e-12, "{:?}", v[1]);
        let (_, open) = ribbon(&points, &[0, 1, 2, 3], 0.2, false);
        assert_eq!(open.len(), 6);
        for tri in &t {
            let [a, b, c] = tri.map(|i| v[i as usize]);
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            assert!(cross.abs() > 1e-6);
        }
    }
}
