//! Validation of a mesh at construction (see [`super::Mesh::new`]).

use super::intersect::cross;
use super::{simplex, Mesh, MeshError, Point};

pub(super) fn validate<const D: usize>(positions: &[Point<D>], elements: &[[usize; D]]) -> Result<(), MeshError> {
    basic_checks(positions, elements, |el| std::array::from_fn(|k| positions[el[k]]))?;
    match D {
        2 => {
            validate_curve(positions.len(), elements)?;
            let pts: Vec<Point<2>> = positions.iter().map(|p| Point::<2>::new(p[0], p[1])).collect();
            let segs: Vec<[usize; 2]> = elements.iter().map(|e| [e[0], e[1]]).collect();
            if let Some(h) = super::find_segment_intersections(&pts, &segs).first() {
                return Err(MeshError::SelfIntersection { a: h.a, b: h.b });
            }
        }
        3 => validate_surface(positions.len(), elements)?,
        _ => unreachable!(),
    }
    let enclosed: f64 =
        elements.iter().map(|el| simplex::enclosed_contribution(&std::array::from_fn(|k| positions[el[k]]))).sum();
    if enclosed <= 0.0 {
        let what = if D == 2 { "area" } else { "volume" };
        return Err(MeshError::InwardOrientation { what, value: enclosed });
    }
    Ok(())
}

/// [`validate`] for a curve on the cylinder (see [`Mesh::new_periodic`]).
pub(super) fn validate_periodic(mesh: &Mesh<2>) -> Result<(), MeshError> {
    let (positions, elements) = (mesh.positions(), mesh.elements());
    let period = mesh.period().expect("periodic mesh");
    basic_checks(positions, elements, |el| {
        let first = positions[el[0]];
        [first, mesh.lift(positions[el[1]], &first)]
    })?;
    validate_curve(positions.len(), elements)?;
    let cycles = mesh.cycles();
    for ((cycle, (points, _)), w) in cycles.iter().zip(mesh.lifted_cycles()).zip(mesh.windings()) {
        let area: f64 = (0..points.len()).map(|k| cross(points[k], points[(k + 1) % points.len()])).sum();
        if !(w == 1 || (w == 0 && area > 0.0)) {
            return Err(MeshError::BadWinding { vertex: cycle[0], winding: w });
        }
    }
    if let Some(h) = super::intersect::find_periodic_intersections(positions, elements, period).first() {
        return Err(MeshError::SelfIntersection { a: h.a, b: h.b });
    }
    Ok(())
}

/// Coordinates finite, indices in range, no repeated vertex, no degenerate or
/// duplicate element, every vertex used.
fn basic_checks<const D: usize>(
    positions: &[Point<D>],
    elements: &[[usize; D]],
    points_of: impl Fn(&[usize; D]) -> [Point<D>; D],
) -> Result<(), MeshError> {
    if elements.is_empty() {
        return Err(MeshError::Empty);
    }
    let n = positions.len();
    for (vertex, p) in positions.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(MeshError::NonFinite { vertex });
        }
    }
    let tiny = degenerate_measure(positions);
    let mut used = vec![false; n];
    for (e, el) in elements.iter().enumerate() {
        for &index in el {
            if index >= n {
                return Err(MeshError::IndexOutOfRange { element: e, index, count: n });
            }
            used[index] = true;
        }
        for a in 0..D {
            for b in a + 1..D {
                if el[a] == el[b] {
                    return Err(MeshError::RepeatedVertex { element: e });
                }
            }
        }
        let (m, _) = simplex::measure_and_normal(&points_of(el));
        if m <= tiny {
            return Err(MeshError::Degenerate { element: e });
        }
    }
    if let Some(vertex) = used.iter().position(|u| !u) {
        return Err(MeshError::UnusedVertex { vertex });
    }
    // duplicates: equal sorted vertex lists; the error names the earliest element
    // that repeats one before it, and the first of those
    let mut keys: Vec<([usize; D], usize)> = elements
        .iter()
        .enumerate()
        .map(|(e, el)| {
            let mut key = *el;
            key.sort_unstable();
            (key, e)
        })
        .collect();
    keys.sort_unstable();
    // within a run of equal keys the indices ascend, so the smallest later index
    // of a pair is a run's second element, paired with the run's first
    let repeat = keys.windows(2).filter(|w| w[0].0 == w[1].0).map(|w| (w[1].1, w[0].1)).min();
    match repeat {
        Some((element, other)) => Err(MeshError::Duplicate { element, other }),
        None => Ok(()),
    }
}

/// The measure (length, area) at or below which an element of a mesh with these
/// vertices counts as degenerate: `1e-13 diam^(D−1)` with the bounding box's
/// diameter. Validation rejects such elements, and the flow rejects a step that
/// makes one.
pub fn degenerate_measure<const D: usize>(positions: &[Point<D>]) -> f64 {
    let scale = bounding_diameter(positions).max(f64::MIN_POSITIVE);
    1e-13 * scale.powi(D as i32 - 1)
}

fn bounding_diameter<const D: usize>(positions: &[Point<D>]) -> f64 {
    let mut lo = Point::<D>::repeat(f64::INFINITY);
    let mut hi = Point::<D>::repeat(f64::NEG_INFINITY);
    for p in positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (hi - lo).norm()
}

fn validate_curve<const D: usize>(n: usize, elements: &[[usize; D]]) -> Result<(), MeshError> {
    let mut outgoing = vec![0usize; n];
    let mut incoming = vec![0usize; n];
    let mut next = vec![usize::MAX; n];
    for el in elements {
        outgoing[el[0]] += 1;
        incoming[el[1]] += 1;
        next[el[0]] = el[1];
    }
    for v in 0..n {
        if outgoing[v] != 1 || incoming[v] != 1 {
            return Err(MeshError::CurveVertexDegree { vertex: v, incoming: incoming[v], outgoing: outgoing[v] });
        }
    }
    let mut seen = vec![false; n];
    for start in 0..n {
        if seen[start] {
            continue;
        }
        let mut len = 0;
        let mut v = start;
        while !seen[v] {
            seen[v] = true;
            len += 1;
            v = next[v];
        }
        if len < 3 {
            return Err(MeshError::ShortComponent { vertex: start, len });
        }
    }
    Ok(())
}

/// A closed, consistently oriented surface whose every vertex's triangles form one
/// fan (also the patch search's condition for cutting patches).
pub(super) fn validate_surface<const D: usize>(n: usize, elements: &[[usize; D]]) -> Result<(), MeshError> {
    // Vertex stars: the links (a -> b for triangle (v, a, b)); the directed edges
    // out of `v` are `v -> a` for its links' first vertices.
    let mut star_start = vec![0usize; n + 1];
    for el in elements {
        for &v in el {
            star_start[v + 1] += 1;
        }
    }
    for v in 0..n {
        star_start[v + 1] += star_start[v];
    }
    let mut fill = star_start.clone();
    let mut links = vec![(0usize, 0usize); star_start[n]];
    for el in elements {
        for k in 0..3 {
            let v = el[k];
            links[fill[v]] = (el[(k + 1) % 3], el[(k + 2) % 3]);
            fill[v] += 1;
        }
    }
    let star = |v: usize| &links[star_start[v]..star_start[v + 1]];
    // each directed edge once, and its reverse present (in the order of (a, b))
    let mut out: Vec<usize> = Vec::new();
    for a in 0..n {
        out.clear();
        out.extend(star(a).iter().map(|l| l.0));
        out.sort_unstable();
        for (i, &b) in out.iter().enumerate() {
            if i > 0 && out[i - 1] == b {
                continue;
            }
            let count = out[i..].iter().take_while(|&&c| c == b).count();
            if count > 1 {
                return Err(MeshError::InconsistentEdge { a, b, count });
            }
            if !star(b).iter().any(|l| l.0 == a) {
                return Err(MeshError::OpenEdge { a, b });
            }
        }
    }
    // the links of each star must form one cycle
    for v in 0..n {
        let star = star(v);
        // a star holds a handful of links: a linear search is the fastest map
        let next = |a: usize| star.iter().find(|l| l.0 == a).map(|l| l.1);
        let Some(&(first, _)) = star.first() else {
            return Err(MeshError::NonManifoldVertex { vertex: v });
        };
        let mut a = first;
        let mut steps = 0;
        loop {
            a = match next(a) {
                Some(b) => b,
                None => return Err(MeshError::NonManifoldVertex { vertex: v }),
            };
            steps += 1;
            if a == first || steps > star.len() {
                break;
            }
        }
        if steps != star.len() {
            return Err(MeshError::NonManifoldVertex { vertex: v });
        }
    }
    Ok(())
}
