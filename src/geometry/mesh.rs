//! The mesh type: vertex positions plus an element list.

use super::{simplex, validate, Point};
use std::sync::{Arc, OnceLock};

/// Errors of the validated mesh constructors. Every variant names the offending
/// vertex, element or edge by its index.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("mesh has no elements")]
    Empty,
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite { vertex: usize },
    #[error("element {element} refers to vertex {index}, but there are only {count} vertices")]
    IndexOutOfRange { element: usize, index: usize, count: usize },
    #[error("element {element} repeats a vertex")]
    RepeatedVertex { element: usize },
    #[error("element {element} is degenerate (zero length or area)")]
    Degenerate { element: usize },
    #[error("element {element} duplicates element {other}")]
    Duplicate { element: usize, other: usize },
    #[error("vertex {vertex} is used by no element")]
    UnusedVertex { vertex: usize },
    #[error("curve vertex {vertex} starts {outgoing} and ends {incoming} segments; closed curves need one of each")]
    CurveVertexDegree { vertex: usize, incoming: usize, outgoing: usize },
    #[error("curve component through vertex {vertex} has only {len} vertices; at least 3 are needed")]
    ShortComponent { vertex: usize, len: usize },
    #[error(
        "edge ({a}, {b}) is used {count} times in the same direction: non-manifold or inconsistently oriented surface"
    )]
    InconsistentEdge { a: usize, b: usize, count: usize },
    #[error("edge ({a}, {b}) has no opposite half-edge: the surface is not closed")]
    OpenEdge { a: usize, b: usize },
    #[error("vertex {vertex} is non-manifold: its triangles do not form a single fan")]
    NonManifoldVertex { vertex: usize },
    #[error("enclosed {what} is {value:e} <= 0: elements are oriented inward (expected counter-clockwise curves / outward-facing triangles)")]
    InwardOrientation { what: &'static str, value: f64 },
    #[error("the period must be a positive number (got {period})")]
    BadPeriod { period: f64 },
    #[error("curve component through vertex {vertex} winds {winding} times around the period; 0 (closed, counter-clockwise) or 1 (in +x) is allowed")]
    BadWinding { vertex: usize, winding: i64 },
    #[error("segments {a} and {b} intersect")]
    SelfIntersection { a: usize, b: usize },
}

/// A closed mesh of dimension `D - 1` in `R^D`: for `D = 2` a set of closed polygons
/// (elements are segments `[a, b]`, oriented so that the interior lies to the left),
/// for `D = 3` a closed oriented triangle surface (elements `[a, b, c]`
/// counter-clockwise seen from outside).
///
/// Built by [`Mesh::new`], which validates; afterwards the connectivity is trusted.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh<const D: usize> {
    positions: Vec<Point<D>>,
    /// Shared between meshes of one connectivity ([`Mesh::with_positions`] is what
    /// a flow does at every trial step and every managed step).
    elements: Arc<[[usize; D]]>,
    /// The component labels of this connectivity, computed when first asked for
    /// and shared with the element list.
    components: Components,
    /// Curves only: the period `L` in `x` of a curve on the cylinder `R/LZ × R`.
    /// Positions are then representatives modulo `L`, and a segment `[a, b]` runs
    /// from `X_a` to the image of `X_b` nearest to it, `X_b + L·round((x_a − x_b)/L) e_x`
    /// (segments are shorter than `L/2` in `x`). See [`Mesh::new_periodic`].
    period: Option<f64>,
}

/// [`Mesh::component_labels`] of one connectivity, made once for all the meshes
/// that share its element list (a flow's trial steps and managed steps between
/// two changes of connectivity). A cache, not part of the mesh's value: any two
/// compare equal.
#[derive(Clone, Default)]
struct Components(Arc<OnceLock<(Vec<usize>, usize)>>);

impl PartialEq for Components {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Components {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Components")
    }
}

/// Closed curves in the plane.
pub type CurveMesh = Mesh<2>;
/// Closed triangle surfaces in space.
pub type SurfaceMesh = Mesh<3>;

impl<const D: usize> Mesh<D> {
    /// Validated constructor: finite coordinates, indices in range, no repeated
    /// vertex in an element, no degenerate or duplicate element, every vertex used;
    /// curves: every vertex starts one and ends one segment, components of at least
    /// three vertices; surfaces: every edge shared by exactly two triangles with
    /// opposite orientation and every vertex star a single fan. Finally the enclosed
    /// area/volume must be positive (outward orientation).
    pub fn new(positions: Vec<Point<D>>, elements: Vec<[usize; D]>) -> Result<Self, MeshError> {
        validate::validate(&positions, &elements)?;
        Ok(Mesh { positions, elements: elements.into(), components: Components::default(), period: None })
    }

    /// A mesh produced by the remeshing kernels, whose connectivity is valid by
    /// construction; only debug builds re-check it.
    pub(crate) fn from_trusted_parts(positions: Vec<Point<D>>, elements: Vec<[usize; D]>) -> Self {
        debug_assert!(elements.iter().all(|e| e.iter().all(|&v| v < positions.len())));
        Mesh { positions, elements: elements.into(), components: Components::default(), period: None }
    }

    /// The period `L` in `x` of a periodic curve mesh, `None` for ordinary meshes.
    pub fn period(&self) -> Option<f64> {
        self.period
    }

    /// The image of `p` (a vertex position) nearest to `near` in `x` under the
    /// period, or `p` itself for non-periodic meshes.
    #[inline]
    pub fn lift(&self, p: Point<D>, near: &Point<D>) -> Point<D> {
        lift_near(self.period, p, near)
    }

    /// Same connectivity, new positions (the flow's update `X_{n+1} = X_n + τ V⃗`).
    /// Panics if the number of positions changes.
    pub fn with_positions(&self, positions: Vec<Point<D>>) -> Self {
        assert_eq!(positions.len(), self.positions.len());
        Mesh { positions, elements: self.elements.clone(), components: self.components.clone(), period: self.period }
    }

    /// Replace the positions in place (same count).
    pub fn set_positions(&mut self, positions: Vec<Point<D>>) {
        assert_eq!(positions.len(), self.positions.len());
        self.positions = positions;
    }

    pub fn positions(&self) -> &[Point<D>] {
        &self.positions
    }

    pub fn elements(&self) -> &[[usize; D]] {
        &self.elements
    }

    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// The element list, shared by the meshes of one connectivity.
    pub(crate) fn shared_elements(&self) -> &Arc<[[usize; D]]> {
        &self.elements
    }

    pub fn num_elements(&self) -> usize {
        self.elements.len()
    }

    /// The `D` vertex positions of element `e`.
    #[inline]
    pub fn element_points(&self, e: usize) -> [Point<D>; D] {
        let el = &self.elements[e];
        let first = self.positions[el[0]];
        std::array::from_fn(|k| if k == 0 { first } else { self.lift(self.positions[el[k]], &first) })
    }

    /// Measure (length or area) and unit outward normal of element `e`.
    #[inline]
    pub fn element_geometry(&self, e: usize) -> (f64, Point<D>) {
        simplex::measure_and_normal(&self.element_points(e))
    }

    /// Number of connected components (curves: closed polygons; surfaces: connected
    /// triangle sets), by union–find over the elements.
    pub fn num_components(&self) -> usize {
        self.component_labels().1
    }

    /// Component label of every vertex and the number of components (made once
    /// per connectivity).
    pub fn component_labels(&self) -> (Vec<usize>, usize) {
        self.components.0.get_or_init(|| components(self.positions.len(), &self.elements)).clone()
    }
}

/// `p` shifted by a multiple of the period in `x` to lie nearest to `near`.
#[inline]
pub(crate) fn lift_near<const D: usize>(period: Option<f64>, mut p: Point<D>, near: &Point<D>) -> Point<D> {
    if let Some(l) = period {
        p[0] += l * ((near[0] - p[0]) / l).round();
    }
    p
}

impl Mesh<2> {
    /// Validated constructor of a curve on the cylinder `R/LZ × R` (period `L` in
    /// `x`): the checks of [`Mesh::new`] on the lifted segments, intersections
    /// including those with periodic images; every component winds `w ∈ {0, 1}`
    /// times around the cylinder (`w = 1`: in the `+x` direction, the region on its
    /// left, above it, is the interior) and a closed component (`w = 0`) runs
    /// counter-clockwise.
    pub fn new_periodic(positions: Vec<Point<2>>, elements: Vec<[usize; 2]>, period: f64) -> Result<Self, MeshError> {
        if !(period.is_finite() && period > 0.0) {
            return Err(MeshError::BadPeriod { period });
        }
        let mesh =
            Mesh { positions, elements: elements.into(), components: Components::default(), period: Some(period) };
        validate::validate_periodic(&mesh)?;
        Ok(mesh)
    }

    /// A periodic curve from the remeshing kernels (valid by construction).
    pub(crate) fn periodic_trusted(positions: Vec<Point<2>>, elements: Vec<[usize; 2]>, period: f64) -> Self {
        debug_assert!(elements.iter().all(|e| e.iter().all(|&v| v < positions.len())));
        Mesh { positions, elements: elements.into(), components: Components::default(), period: Some(period) }
    }

    /// Components as lifted polylines: each cycle of [`Mesh::cycles`] with every
    /// vertex moved to the image nearest its predecessor, and the component's shift
    /// (the closing segment runs from the last point to `first + shift`; zero
    /// unless the component winds around a periodic mesh).
    pub fn lifted_cycles(&self) -> Vec<(Vec<Point<2>>, Point<2>)> {
        self.cycles()
            .iter()
            .map(|c| {
                let mut pts: Vec<Point<2>> = Vec::with_capacity(c.len());
                for &v in c {
                    let p = match pts.last() {
                        Some(prev) => self.lift(self.positions[v], prev),
                        None => self.positions[v],
                    };
                    pts.push(p);
                }
                let closing = self.lift(pts[0], pts.last().unwrap());
                (pts.clone(), closing - pts[0])
            })
            .collect()
    }

    /// Pairs of crossing or touching segments (with periodic images on the cylinder).
    pub fn crossings(&self) -> Vec<super::SegmentHit> {
        match self.period {
            Some(l) => super::find_periodic_intersections(&self.positions, &self.elements, l),
            None => super::find_segment_intersections(&self.positions, &self.elements),
        }
    }

    /// The crossings among `hits` (of this mesh's segments) that join two different
    /// components.
    pub fn crossings_between_components<'a>(&self, hits: &'a [super::SegmentHit]) -> Vec<&'a super::SegmentHit> {
        if hits.is_empty() {
            return Vec::new();
        }
        let (label, _) = self.component_labels();
        hits.iter().filter(|h| label[self.elements[h.a][0]] != label[self.elements[h.b][0]]).collect()
    }

    /// Number of times each component of [`Mesh::cycles`] winds around the cylinder
    /// (0 for non-periodic meshes).
    pub fn windings(&self) -> Vec<i64> {
        let l = self.period.unwrap_or(f64::INFINITY);
        self.lifted_cycles().iter().map(|(_, shift)| (shift.x / l).round() as i64).collect()
    }

    /// The closed polygons of a curve mesh as vertex index cycles, each in the
    /// direction of its segments (counter-clockwise for outer boundaries), ordered by
    /// their smallest vertex index.
    pub fn cycles(&self) -> Vec<Vec<usize>> {
        segment_cycles(self.positions.len(), self.elements.iter().map(|e| (e[0], e[1])))
    }
}

/// Vertex cycles of closed polylines given as directed segments `(a, b)` over `n`
/// vertices: each cycle follows the segments, cycles ordered by their smallest
/// vertex; vertices on no segment are skipped.
pub fn segment_cycles(n: usize, segments: impl Iterator<Item = (usize, usize)>) -> Vec<Vec<usize>> {
    let mut next = vec![usize::MAX; n];
    for (a, b) in segments {
        next[a] = b;
    }
    let mut seen = vec![false; n];
    let mut out = Vec::new();
    for start in 0..n {
        if seen[start] || next[start] == usize::MAX {
            continue;
        }
        let mut cyc = Vec::new();
        let mut v = start;
        while v != usize::MAX && !seen[v] {
            seen[v] = true;
            cyc.push(v);
            v = next[v];
        }
        out.push(cyc);
    }
    out
}

/// Component label (`0..count`, in the order of each component's first vertex) of
/// each of `n` vertices joined by `elements` (segments, triangles, or any vertex
/// sets), and the number of components; a vertex in no element is a component of
/// its own. Union–find over the elements.
pub fn components<const K: usize>(n: usize, elements: &[[usize; K]]) -> (Vec<usize>, usize) {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for el in elements {
        let r0 = find(&mut parent, el[0]);
        for &v in &el[1..] {
            let r = find(&mut parent, v);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut label = vec![usize::MAX; n];
    let mut count = 0;
    let mut out = vec![0; n];
    for v in 0..n {
        let r = find(&mut parent, v);
        if label[r] == usize::MAX {
            label[r] = count;
            count += 1;
        }
        out[v] = label[r];
    }
    (out, count)
}

#[cfg(test)]
mod tests {
    use crate::geometry::{circle, union, Point};

    /// The labels are made once per connectivity: a mesh moved by
    /// `with_positions` shares them, a new connectivity makes its own; the cache
    /// does not enter a mesh's value.
    #[test]
    fn component_labels_follow_the_connectivity() {
        let two = union(&[circle([0.0, 0.0], 1.0, 12).unwrap(), circle([3.0, 0.0], 1.0, 8).unwrap()]).unwrap();
        let fresh = two.with_positions(two.positions().to_vec());
        assert_eq!(two.component_labels(), fresh.component_labels());
        assert!(std::ptr::eq(two.components.0.get().unwrap(), fresh.components.0.get().unwrap()));
        assert_eq!(two.num_components(), 2);
        let moved = two.with_positions(two.positions().iter().map(|p| p + Point::<2>::new(0.5, 0.0)).collect());
        assert_eq!(moved, moved.with_positions(moved.positions().to_vec()));
        assert_ne!(moved, two);
        let one = circle([0.0, 0.0], 1.0, 20).unwrap();
        assert_eq!(one.component_labels(), (vec![0; 20], 1));
        assert_eq!(one, circle([0.0, 0.0], 1.0, 20).unwrap().with_positions(one.positions().to_vec()));
    }
}
