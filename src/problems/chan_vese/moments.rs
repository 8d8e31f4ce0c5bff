//! The region integrals of the Chan–Vese functional: per object `(∫ I, ∫ Q, |Ω|)`
//! as boundary integrals of the antiderivatives of the image splines, by Gauss
//! quadrature on segments and edge midpoints on triangles, four points at a time
//! across elements; the elements of a large mesh in two halves on two threads.

use super::ChanVese;
use crate::geometry::{surface_edges, Mesh, Point, SurfaceEdge};
use crate::imaging::EdgeField;

/// `(∫ I, ∫ Q, |Ω|)` of one object.
pub(super) type Moments = [f64; 3];

/// Two-point Gauss rule on `[0, 1]`.
const GAUSS2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

/// The quadrature points of the element with corners `p`, with their weights,
/// into `lanes` for `object`: two Gauss points per pixel of length on segments,
/// the 3-point rule on sub-triangles of about two pixels on triangles (larger than
/// two voxels; smaller ones take [`edge_midpoints`]). A point's
/// weight is its share of `ν₁` times the element's measure (equal within an
/// element). Plain inlined functions, no closures: they compile into
/// [`accumulate_moments`]' AVX2 version (a closure would be compiled on its own).
#[inline(always)]
fn element_points<const D: usize>(l: f64, p: &[Point<D>; D], lanes: &mut Lanes<'_>, object: usize) {
    if D == 2 {
        let e = p[1] - p[0];
        let m = (e.norm() * l).ceil().clamp(1.0, 4096.0) as usize;
        let w = e[1] / (2 * m) as f64;
        for s in 0..m {
            for g in GAUSS2 {
                let x = p[0] + e * ((s as f64 + g) / m as f64);
                lanes.push([x[0], x[1], 0.0], w, object);
            }
        }
    } else {
        let (u, v) = (p[1] - p[0], p[2] - p[0]);
        let nu1 = 0.5 * (u[1] * v[2] - u[2] * v[1]);
        let hmax = u.norm().max(v.norm()).max((p[2] - p[1]).norm());
        let m = (hmax * l / 2.0).ceil().clamp(1.0, 256.0) as usize;
        let (step, w) = (1.0 / m as f64, nu1 / (3 * m * m) as f64);
        let (x0, u, v) = ([p[0][0], p[0][1], p[0][2]], [u[0], u[1], u[2]], [v[0], v[1], v[2]]);
        for i in 0..m {
            for j in 0..m - i {
                let (s0, t0) = (i as f64 * step, j as f64 * step);
                let corners = [(s0, t0), (s0 + step, t0), (s0, t0 + step)];
                sub_triangle(&x0, &u, &v, corners, w, lanes, object);
                if i + j + 1 < m {
                    let corners = [(s0 + step, t0), (s0 + step, t0 + step), (s0, t0 + step)];
                    sub_triangle(&x0, &u, &v, corners, w, lanes, object);
                }
            }
        }
    }
}

/// The 3-point rule (barycentric `(2/3, 1/6, 1/6)` and permutations) on the
/// sub-triangle with lattice corners `c` of `x₀ + s u + t v`.
#[inline(always)]
fn sub_triangle(
    x0: &[f64; 3],
    u: &[f64; 3],
    v: &[f64; 3],
    c: [(f64, f64); 3],
    w: f64,
    lanes: &mut Lanes<'_>,
    object: usize,
) {
    const THIRD: [[f64; 3]; 3] =
        [[2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0], [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0]];
    for b in THIRD {
        let s = b[0] * c[0].0 + b[1] * c[1].0 + b[2] * c[2].0;
        let t = b[0] * c[0].1 + b[1] * c[1].1 + b[2] * c[2].1;
        let x = [x0[0] + u[0] * s + v[0] * t, x0[1] + u[1] * s + v[1] * t, x0[2] + u[2] * s + v[2] * t];
        lanes.push(x, w, object);
    }
}

/// The moments of the elements of `mesh` added to their objects'; compiled a
/// second time for AVX2 and picked at run time, as the geodesic quadrature.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn accumulate_moments<const D: usize>(
    cv: &ChanVese,
    mesh: &Mesh<D>,
    element_object: &[usize],
    moments: &mut [Moments],
) {
    let l = cv.intensity.scale();
    if D == 3 {
        edge_midpoints(cv, l, mesh, element_object, moments);
    } else {
        in_halves(element_object.len(), moments, |range, part| curve_points(cv, l, mesh, element_object, range, part));
    }
}

/// `points(0..n, moments)`; on a machine of more than one core, with `n` at least
/// [`SPLIT_AT`], as two halves on two threads, the second into moments of its own
/// added after the first (the same sums whatever the threads' timing).
fn in_halves(n: usize, moments: &mut [Moments], points: impl Fn(std::ops::Range<usize>, &mut [Moments]) + Sync) {
    if n < SPLIT_AT || crate::cores() < 2 {
        return points(0..n, moments);
    }
    let mut second = vec![[0.0; 3]; moments.len()];
    std::thread::scope(|scope| {
        scope.spawn(|| points(n / 2..n, &mut second));
        points(0..n / 2, moments);
    });
    for (m, s) in moments.iter_mut().zip(&second) {
        for k in 0..3 {
            m[k] += s[k];
        }
    }
}

/// On a machine of more than one core, curves of at least this many segments,
/// and surfaces of at least this many edges, have their points evaluated on two
/// threads ([`in_halves`]).
const SPLIT_AT: usize = 2048;

/// The points of the segments `range` of a curve mesh added to `moments`;
/// compiled for AVX2 as [`accumulate_moments`] (a thread calls it on its own).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn curve_points<const D: usize>(
    cv: &ChanVese,
    l: f64,
    mesh: &Mesh<D>,
    element_object: &[usize],
    range: std::ops::Range<usize>,
    moments: &mut [Moments],
) {
    let mut lanes = Lanes::new(cv, moments);
    for e in range {
        element_points(l, &mesh.element_points(e), &mut lanes, element_object[e]);
    }
    lanes.finish();
}

/// Surfaces: on a triangle of at most two voxels across, the edge-midpoint rule
/// (`|T|/3` at each edge's midpoint; degree 2, as the interior 3-point rule) with
/// each edge's midpoint evaluated once for the triangles beside it
/// ([`surface_edges`]), half the points of a rule per triangle. A larger triangle
/// takes [`element_points`]' sub-triangles. The edges of a large surface go in two
/// halves to two threads, as the segments of a long curve.
#[inline(always)]
fn edge_midpoints<const D: usize>(
    cv: &ChanVese,
    l: f64,
    mesh: &Mesh<D>,
    element_object: &[usize],
    moments: &mut [Moments],
) {
    let (x, tris) = (mesh.positions(), mesh.elements());
    let mut lanes = Lanes::new(cv, moments);
    // each triangle's weight `ν₁|T|/3`, 0 for a large one (it has its own points)
    let mut weight = Vec::with_capacity(tris.len());
    for (e, &o) in element_object.iter().enumerate() {
        let p = mesh.element_points(e);
        let (u, v) = (p[1] - p[0], p[2] - p[0]);
        let longest = u.norm_squared().max(v.norm_squared()).max((p[2] - p[1]).norm_squared());
        if longest * l * l <= 4.0 {
            weight.push((u[1] * v[2] - u[2] * v[1]) / 6.0);
        } else {
            weight.push(0.0);
            element_points(l, &p, &mut lanes, o);
        }
    }
    lanes.finish();
    let edges = surface_edges(x.len(), tris);
    in_halves(edges.len(), moments, |range, part| midpoints(cv, x, &edges[range], &weight, element_object, part));
}

/// The midpoints of `edges` with the weights of the triangles beside them, added
/// to `moments` (compiled for AVX2 as [`accumulate_moments`]).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn midpoints<const D: usize>(
    cv: &ChanVese,
    x: &[Point<D>],
    edges: &[SurfaceEdge],
    weight: &[f64],
    element_object: &[usize],
    moments: &mut [Moments],
) {
    let mut lanes = Lanes::new(cv, moments);
    for edge in edges {
        let [t, across] = edge.t;
        let w = weight[t] + if across == usize::MAX { 0.0 } else { weight[across] };
        if w != 0.0 {
            let (a, b) = (x[edge.a], x[edge.b]);
            lanes.push([0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])], w, element_object[t]);
        }
    }
    lanes.finish();
}

/// Quadrature points of any elements, evaluated four at a time on both splines
/// ([`EdgeField::antiderivatives`]: one set of weights for both), each added with
/// its weight to its object's `(∫ I, ∫ Q, |Ω|)` as `(Φ_I, Φ_Q, x₁)`.
struct Lanes<'a> {
    cv: &'a ChanVese,
    moments: &'a mut [Moments],
    x: [[f64; 4]; 3],
    w: [f64; 4],
    object: [usize; 4],
    filled: usize,
}

impl<'a> Lanes<'a> {
    #[inline(always)]
    fn new(cv: &'a ChanVese, moments: &'a mut [Moments]) -> Self {
        Lanes { cv, moments, x: [[0.0; 4]; 3], w: [0.0; 4], object: [0; 4], filled: 0 }
    }

    #[inline(always)]
    fn push(&mut self, x: [f64; 3], w: f64, object: usize) {
        let j = self.filled;
        for (lane, v) in self.x.iter_mut().zip(x) {
            lane[j] = v;
        }
        (self.w[j], self.object[j]) = (w, object);
        self.filled += 1;
        if self.filled == 4 {
            self.add();
        }
    }

    /// The filled lanes evaluated and added to their objects.
    #[inline(always)]
    fn add(&mut self) {
        let [pi, pq] = EdgeField::antiderivatives([&*self.cv.intensity, &*self.cv.squares], self.x);
        for j in 0..self.filled {
            let m = &mut self.moments[self.object[j]];
            m[0] += self.w[j] * pi[j];
            m[1] += self.w[j] * pq[j];
            m[2] += self.w[j] * self.x[0][j];
        }
        self.filled = 0;
    }

    /// The last, partly filled lanes (the rest repeat the first point).
    #[inline(always)]
    fn finish(mut self) {
        if self.filled > 0 {
            for j in self.filled..4 {
                for k in 0..3 {
                    self.x[k][j] = self.x[k][0];
                }
            }
            self.add();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, icosphere, union};

    /// A curve long enough to be split over two threads gets the moments of one
    /// pass over all its segments, to rounding.
    #[test]
    fn split_curves_get_the_moments_of_one_pass() {
        let n = 64;
        let values: Vec<f64> = (0..n * n).map(|p| (((p % n) * 7 + (p / n) * 3) % 11) as f64 / 10.0).collect();
        let cv = ChanVese::new(2, [n, n, 1], &values, 0.0, (1.0, 1.0));
        let mesh =
            union(&[circle([0.3, 0.4], 0.2, SPLIT_AT).unwrap(), circle([0.7, 0.6], 0.15, 500).unwrap()]).unwrap();
        let objects: Vec<usize> = (0..mesh.num_elements()).map(|e| usize::from(e >= SPLIT_AT)).collect();
        let mut split = vec![[0.0; 3]; 2];
        accumulate_moments(&cv, &mesh, &objects, &mut split);
        let mut one = vec![[0.0; 3]; 2];
        curve_points(&cv, cv.intensity.scale(), &mesh, &objects, 0..objects.len(), &mut one);
        for (a, b) in split.iter().flatten().zip(one.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-3), "{split:?} {one:?}");
        }
        assert!(split[0][2] > 0.12 && split[1][2] > 0.06, "{split:?}");
    }

    /// On a linear image the spline is the same linear function and `Φ` is
    /// quadratic, which both surface rules integrate exactly on flat triangles:
    /// `(∫ I, |Ω|)` equal the polyhedron's, summed over the tetrahedra from the
    /// origin, with triangles larger than two voxels (sub-triangles) and smaller
    /// (edge midpoints, on one thread and on two).
    #[test]
    fn surface_rules_are_exact_on_a_linear_image() {
        let n = 32;
        let lin = |x: [f64; 3]| 0.2 + 0.3 * x[0] + 0.5 * x[1] - 0.15 * x[2];
        let values: Vec<f64> = (0..n * n * n)
            .map(|p| lin([p % n, (p / n) % n, p / (n * n)].map(|i| (i as f64 + 0.5) / n as f64)))
            .collect();
        let cv = ChanVese::new(3, [n, n, n], &values, 0.0, (1.0, 1.0));
        // level 4 has more edges than `SPLIT_AT`: two threads
        for level in [2, 3, 4] {
            let mesh = icosphere([0.5, 0.45, 0.52], 0.25, level).unwrap();
            let edges = surface_edges(mesh.num_vertices(), mesh.elements()).len();
            assert_eq!(level == 4, edges >= SPLIT_AT, "level {level}: {edges} edges");
            let edge = (mesh.element_points(0)[1] - mesh.element_points(0)[0]).norm() * n as f64;
            assert!((level == 2) == (edge > 2.0), "level {level}: edges of {edge} voxels");
            let (mut volume, mut integral) = (0.0, 0.0);
            for e in 0..mesh.elements().len() {
                let [a, b, c] = mesh.element_points(e);
                let v = a.dot(&b.cross(&c)) / 6.0;
                let centroid = (a + b + c) / 4.0;
                volume += v;
                integral += v * lin([centroid[0], centroid[1], centroid[2]]);
            }
            let mut moments = vec![[0.0; 3]];
            accumulate_moments(&cv, &mesh, &vec![0; mesh.elements().len()], &mut moments);
            assert!((moments[0][2] - volume).abs() < 1e-13, "level {level}: {} {volume}", moments[0][2]);
            assert!((moments[0][0] - integral).abs() < 1e-12, "level {level}: {} {integral}", moments[0][0]);
        }
    }
}
