//! Triangulation of the bulk domain `Ω` between the moving curve `Γ` and the fixed
//! outer boundary `Σ`, conforming to the boundary of the control region `D`: a
//! constrained Delaunay triangulation (spade) of all boundary polygons, refined to a
//! minimum angle, with the element size graded from the boundary spacing.
//!
//! Which triangles belong to `Ω` (and to `D`) is decided by a flood fill over the
//! triangles from the convex hull inwards: crossing a constraint edge of `Γ` or `Σ`
//! flips "in `Ω`", crossing one of `∂D` flips "in `D`". Refinement keeps the
//! constraint edges whole (the boundaries are sampled evenly already), so the vertices
//! and edges of `Γ` are exactly those of the curve mesh: a mesh built for one curve
//! can follow the curve's vertices as they move ([`BulkMesh::with_curve_positions`]),
//! and [`super::curve_sensitivity`] differentiates with respect to them.

use super::domain::{loop_segments, DesignDomain};
use super::BulkError;
use crate::geometry::{CurveMesh, Point};
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};
use std::collections::VecDeque;

/// Meshing parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshingOptions {
    /// Minimum angle the refinement aims for, in degrees (at most 33).
    pub min_angle_deg: f64,
    /// Largest allowed triangle area (caps the grading away from the boundaries).
    pub max_area: f64,
    /// Triangles below this area are not refined further (protects against narrow gaps).
    pub min_area: f64,
}

impl MeshingOptions {
    /// Defaults for a domain: 28°, triangle areas at most `h_Σ²` (`h_Σ` the spacing of
    /// `Σ`; this keeps the P1 error `O(h²)` in the far field, measured on the annulus),
    /// no refinement below 1/400 of the smallest boundary spacing squared.
    pub fn for_domain(domain: &DesignDomain, curve_spacing: f64) -> Self {
        let h_sigma = domain.outer().spacing();
        let h_min = curve_spacing.min(domain.control()[0].spacing()).min(h_sigma);
        MeshingOptions { min_angle_deg: 28.0, max_area: h_sigma * h_sigma, min_area: 0.0025 * h_min * h_min }
    }
}

/// Which boundary a vertex or constraint edge lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Boundary {
    Curve,
    Outer,
    Control,
    /// A seed inside `Ω`.
    Interior,
}

/// A P1 triangulation of a plane domain bounded by a moving curve `Γ` and fixed
/// boundaries: shape design's `Ω` between `Γ` and `Σ`, the stressed film below its
/// surface.
///
/// The first `curve_vertices` vertices are the vertices of `Γ`, in the order of the
/// curve mesh; every vertex belongs to at least one triangle.
#[derive(Debug, Clone)]
pub struct DomainMesh {
    pub points: Vec<Point<2>>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[usize; 3]>,
    /// Per vertex: does it carry a Dirichlet value (shape design: on `Σ`; the film:
    /// on the substrate or a wall)?
    pub dirichlet: Vec<bool>,
    pub curve_vertices: usize,
}

/// Shape design's triangulation of `Ω`: the domain mesh (Dirichlet on `Σ`) and where
/// `D`, `Γ` and the free vertices are.
#[derive(Debug, Clone)]
pub struct BulkMesh {
    pub mesh: DomainMesh,
    /// Per triangle: does it lie in `D`?
    pub in_control: Vec<bool>,
    /// Edges of the triangulation on `Γ` (the curve's segments, renumbered).
    pub curve_edges: Vec<[usize; 2]>,
    /// Per vertex: on none of `Γ`, `Σ`, `∂D` (a refinement point or a seed).
    pub free: Vec<bool>,
}

impl BulkMesh {
    /// Triangulates `Ω` for the curve `Γ` (admissible: see [`DesignDomain::check_curve`]).
    pub fn build(domain: &DesignDomain, curve: &CurveMesh, opts: &MeshingOptions) -> Result<BulkMesh, BulkError> {
        Self::build_seeded(domain, curve, opts, &[])
    }

    /// [`Self::build`] with `seeds`: interior points of `Ω` inserted before the
    /// refinement (they must lie inside `Ω`, off its boundaries). Seeding with the
    /// free vertices of an earlier mesh, away from `Γ`, gives the same triangles
    /// there (the Delaunay triangulation of the same points), so `J_h` does not jump
    /// by its discretization error each time `Ω` is triangulated afresh.
    pub fn build_seeded(
        domain: &DesignDomain,
        curve: &CurveMesh,
        opts: &MeshingOptions,
        seeds: &[Point<2>],
    ) -> Result<BulkMesh, BulkError> {
        let (points, segments) = (curve.positions(), curve.elements());
        let n_curve = points.len();
        let outer = domain.outer();
        let [ci, co] = domain.control();
        let (fixed_pts, fixed_segs) = loop_segments(&[outer, ci, co]);
        let n_outer = outer.points().len();
        let mut vertices: Vec<Point<2>> = points.to_vec();
        vertices.extend(fixed_pts.iter());
        vertices.extend_from_slice(seeds);
        let mut class: Vec<Boundary> = vec![Boundary::Curve; n_curve];
        class.extend((0..fixed_pts.len()).map(|i| if i < n_outer { Boundary::Outer } else { Boundary::Control }));
        class.extend(seeds.iter().map(|_| Boundary::Interior));
        let mut edges: Vec<[usize; 2]> = segments.to_vec();
        edges.extend(fixed_segs.iter().map(|s| [s[0] + n_curve, s[1] + n_curve]));
        // crossing a constraint edge of Γ or Σ flips "in Ω", one of ∂D "in D"
        let flips = |a: usize, _b: usize| match class[a] {
            Boundary::Control => (false, true),
            _ => (true, false),
        };
        let t = triangulate(&vertices, &edges, flips, n_curve, opts)?;
        let class_of = |i: usize| t.input_of.get(i).filter(|&&v| v != usize::MAX).map(|&v| class[v]);
        let on_outer = (0..t.points.len()).map(|i| class_of(i) == Some(Boundary::Outer)).collect();
        let free = (0..t.points.len()).map(|i| matches!(class_of(i), None | Some(Boundary::Interior))).collect();
        let curve_edges = t
            .constraint_edges
            .iter()
            .filter(|&&(a, b)| class[a] == Boundary::Curve && class[b] == Boundary::Curve)
            .map(|&(a, b)| [t.index[a], t.index[b]])
            .collect();
        Ok(BulkMesh {
            mesh: DomainMesh { points: t.points, triangles: t.triangles, dirichlet: on_outer, curve_vertices: n_curve },
            in_control: t.second,
            curve_edges,
            free,
        })
    }

    /// The same triangulation with the curve's vertices moved to `positions` (all
    /// other vertices fixed), if every triangle at the curve keeps its orientation and
    /// an angle of at least `min_angle_deg`; `None` otherwise (then re-mesh).
    pub fn with_curve_positions(&self, positions: &[Point<2>], min_angle_deg: f64) -> Option<BulkMesh> {
        let nc = self.mesh.curve_vertices;
        if positions.len() != nc {
            return None;
        }
        let mut moved = self.clone();
        moved.mesh.points[..nc].copy_from_slice(positions);
        let (points, triangles) = (&moved.mesh.points, &moved.mesh.triangles);
        let min_sin = min_angle_deg.to_radians().sin();
        for t in triangles.iter().filter(|t| t.iter().any(|&v| v < nc)) {
            let area = triangle_area(points, t);
            // sin of every angle = 2·area / (product of its two sides)
            for k in 0..3 {
                let (a, b, c) = (points[t[k]], points[t[(k + 1) % 3]], points[t[(k + 2) % 3]]);
                if !(2.0 * area >= min_sin * (b - a).norm() * (c - a).norm()) {
                    return None;
                }
            }
        }
        Some(moved)
    }

    /// Area of `Ω` and of `Ω ∩ D`.
    pub fn areas(&self) -> (f64, f64) {
        let (mut total, mut control) = (0.0, 0.0);
        for (t, &c) in self.mesh.triangles.iter().zip(&self.in_control) {
            let a = triangle_area(&self.mesh.points, t);
            total += a;
            if c {
                control += a;
            }
        }
        (total, control)
    }

    /// Smallest interior angle, in degrees.
    pub fn min_angle_deg(&self) -> f64 {
        let mut worst = 180.0f64;
        let p = &self.mesh.points;
        for t in &self.mesh.triangles {
            for k in 0..3 {
                let (a, b, c) = (p[t[k]], p[t[(k + 1) % 3]], p[t[(k + 2) % 3]]);
                let (u, v) = (b - a, c - a);
                worst = worst.min(u.angle(&v).to_degrees());
            }
        }
        worst
    }
}

/// A constrained Delaunay triangulation of the regions bounded by polygons.
pub(crate) struct Triangulated {
    /// The first `n_keep` input vertices in order, then the others in use.
    pub points: Vec<Point<2>>,
    /// Counter-clockwise triangles of the first region.
    pub triangles: Vec<[usize; 3]>,
    /// Per triangle: inside the second region?
    pub second: Vec<bool>,
    /// Per input vertex: its index in `points` (`usize::MAX` if on no kept triangle).
    pub index: Vec<usize>,
    /// Per vertex of `points` that is an input vertex: its input index
    /// (`usize::MAX` for refinement vertices; only the first `index.len()` entries).
    pub input_of: Vec<usize>,
    /// The constraint edges, as input vertex pairs, whose both ends are kept.
    pub constraint_edges: Vec<(usize, usize)>,
}

/// The two region parities of every face of `cdt` (indexed by face; `None` for a
/// face not reached): a flood fill from the outer face (parities `(false, false)`)
/// in which crossing an edge toggles them by `crossing(is_constraint, a, b)`, `a`
/// and `b` the edge's vertex indices.
pub(crate) fn region_parities(
    cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>,
    crossing: impl Fn(bool, usize, usize) -> (bool, bool),
) -> Vec<Option<(bool, bool)>> {
    let nf = cdt.num_all_faces();
    let outer_face = spade::handles::OUTER_FACE.index();
    // per inner face: the face across each edge (possibly the outer one) and the flips
    let mut neighbours: Vec<[(usize, (bool, bool)); 3]> = vec![[(outer_face, (false, false)); 3]; nf];
    for face in cdt.inner_faces() {
        neighbours[face.fix().index()] = face.adjacent_edges().map(|e| {
            let [a, b] = e.vertices().map(|v| v.fix().index());
            (e.rev().face().fix().index(), crossing(e.is_constraint_edge(), a, b))
        });
    }
    let mut state: Vec<Option<(bool, bool)>> = vec![None; nf];
    state[outer_face] = Some((false, false));
    // the outer face's neighbours are the inner faces that name it
    let mut queue: VecDeque<usize> = VecDeque::new();
    for f in (0..nf).filter(|&f| f != outer_face) {
        if let Some(&(_, c)) = neighbours[f].iter().find(|(g, _)| *g == outer_face) {
            state[f] = Some(c);
            queue.push_back(f);
        }
    }
    while let Some(f) = queue.pop_front() {
        let s = state[f].expect("visited");
        for (g, c) in neighbours[f] {
            if state[g].is_none() {
                state[g] = Some((s.0 ^ c.0, s.1 ^ c.1));
                queue.push_back(g);
            }
        }
    }
    state
}

/// Triangulates the regions bounded by the constraint `edges` among `vertices`:
/// spade's constrained Delaunay triangulation, refined to `opts` with the
/// constraint edges kept whole (so every boundary vertex is an input vertex), and
/// a flood fill from the outer face in which crossing the constraint edge `(a, b)`
/// toggles the two region parities by `flips(a, b)`. The triangles of the first
/// region are kept; the first `n_keep` input vertices come first, in order, and
/// must all be on kept triangles.
pub(crate) fn triangulate(
    vertices: &[Point<2>],
    edges: &[[usize; 2]],
    flips: impl Fn(usize, usize) -> (bool, bool),
    n_keep: usize,
    opts: &MeshingOptions,
) -> Result<Triangulated, BulkError> {
    let n_input = vertices.len();
    let mut conflicts = 0usize;
    let input: Vec<Point2<f64>> = vertices.iter().map(|p| Point2::new(p.x, p.y)).collect();
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::try_bulk_load_cdt(input, edges.to_vec(), |_| conflicts += 1)
            .map_err(|e| BulkError::Meshing(format!("triangulation: {e:?}")))?;
    if conflicts > 0 || cdt.num_vertices() != n_input {
        return Err(BulkError::Inadmissible("the curve touches itself or a fixed boundary".into()));
    }
    let budget = 20 * n_input + 200_000;
    let result = cdt.refine(
        RefinementParameters::new()
            .with_angle_limit(AngleLimit::from_deg(opts.min_angle_deg))
            .with_max_allowed_area(opts.max_area)
            .with_min_required_area(opts.min_area)
            .with_max_additional_vertices(budget)
            .keep_constraint_edges()
            .exclude_outer_faces(false),
    );
    if !result.refinement_complete {
        tracing::debug!("bulk refinement stopped at its vertex budget ({budget})");
    }
    let crossing = |constraint: bool, a: usize, b: usize| -> (bool, bool) {
        if constraint && a < n_input && b < n_input {
            flips(a, b)
        } else {
            (false, false)
        }
    };
    let state = region_parities(&cdt, crossing);
    // keep the triangles of the first region, renumber (the first n_keep first)
    let nv = cdt.num_vertices();
    let mut index = vec![usize::MAX; nv];
    let mut points: Vec<Point<2>> = vertices[..n_keep].to_vec();
    let mut input_of: Vec<usize> = (0..n_keep).collect();
    for (i, slot) in index.iter_mut().enumerate().take(n_keep) {
        *slot = i;
    }
    let mut triangles = Vec::new();
    let mut second = Vec::new();
    for face in cdt.inner_faces() {
        let Some((inside, in_second)) = state[face.fix().index()] else { continue };
        if !inside {
            continue;
        }
        let tri = face.vertices().map(|v| {
            let i = v.fix().index();
            if index[i] == usize::MAX {
                index[i] = points.len();
                let p = v.position();
                points.push(Point::<2>::new(p.x, p.y));
                input_of.push(if i < n_input { i } else { usize::MAX });
            }
            index[i]
        });
        triangles.push(tri);
        second.push(in_second);
    }
    if triangles.is_empty() {
        return Err(BulkError::Meshing("the bulk domain has no triangles".into()));
    }
    let mut constraint_edges = Vec::new();
    for e in cdt.undirected_edges().filter(|e| e.is_constraint_edge()) {
        let [a, b] = e.vertices().map(|v| v.fix().index());
        if a < n_input && b < n_input && index[a] != usize::MAX && index[b] != usize::MAX {
            constraint_edges.push((a, b));
        }
    }
    index.truncate(n_input);
    Ok(Triangulated { points, triangles, second, index, input_of, constraint_edges })
}

/// Signed area of triangle `t`.
pub fn triangle_area(points: &[Point<2>], t: &[usize; 3]) -> f64 {
    let (a, b, c) = (points[t[0]], points[t[1]], points[t[2]]);
    0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x))
}
