//! The fixed part of a shape-design domain (paper §1.2): the outer boundary `Σ` and
//! the control region `D`, the region between two nested closed polygons. The moving
//! curve `Γ` lives inside `Σ` and must not meet `D`.

use super::BulkError;
use crate::geometry::{find_segment_intersections, polygon, winding_number, CurveMesh, MeshError, Point};

/// A closed simple polygon, stored counter-clockwise: a validated one-component
/// curve mesh (the geometry's constructors check finiteness, repeated points and
/// self-intersections).
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    curve: CurveMesh,
}

impl Polygon {
    /// The polygon through `points` (either orientation). `what` names it in errors.
    pub fn new(what: &str, points: Vec<Point<2>>) -> Result<Self, BulkError> {
        Self::from_curve(what, polygon(&points, None))
    }

    /// A polygon from a curve built by the geometry's shapes (`circle`, `rectangle`,
    /// `polygon`); it must have a single component.
    pub fn from_curve(what: &str, curve: Result<CurveMesh, MeshError>) -> Result<Self, BulkError> {
        let bad = |message: String| BulkError::Domain { what: what.to_string(), message };
        let curve = curve.map_err(|e| match e {
            MeshError::SelfIntersection { a, b } => bad(format!("intersects itself (segments {a} and {b})")),
            e => bad(e.to_string()),
        })?;
        if curve.num_components() != 1 {
            return Err(bad(format!("must be one closed curve, got {}", curve.num_components())));
        }
        Ok(Polygon { curve })
    }

    /// The vertices, counter-clockwise.
    pub fn points(&self) -> &[Point<2>] {
        self.curve.positions()
    }

    /// Enclosed area (positive: counter-clockwise).
    pub fn signed_area(&self) -> f64 {
        self.curve.enclosed_measure()
    }

    /// Mean edge length.
    pub fn spacing(&self) -> f64 {
        self.curve.boundary_measure() / self.curve.num_elements() as f64
    }

    /// Whether `p` lies inside (points on the boundary may go either way).
    pub fn contains(&self, p: Point<2>) -> bool {
        winding_number(&[self.points()], p) != 0
    }
}

/// `Σ` and `D = interior(control_outer) \ closure(control_inner)`, validated:
/// `control_inner ⊂ control_outer ⊂ Σ`, no two boundaries meet.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignDomain {
    outer: Polygon,
    control_inner: Polygon,
    control_outer: Polygon,
}

impl DesignDomain {
    pub fn new(outer: Polygon, control_inner: Polygon, control_outer: Polygon) -> Result<Self, BulkError> {
        let bad = |what: &str, m: &str| BulkError::Domain { what: what.to_string(), message: m.to_string() };
        let d = DesignDomain { outer, control_inner, control_outer };
        let loops = [&d.outer, &d.control_inner, &d.control_outer];
        let (points, segments) = loop_segments(&loops);
        if let Some(h) = find_segment_intersections(&points, &segments).first() {
            return Err(BulkError::Domain {
                what: "control".into(),
                message: format!(
                    "the boundaries of the control region and the outer boundary meet near ({:.4}, {:.4})",
                    h.point.x, h.point.y
                ),
            });
        }
        if !d.control_outer.contains(d.control_inner.points()[0]) {
            return Err(bad("control.inner", "must lie inside control.outer"));
        }
        if !d.outer.contains(d.control_outer.points()[0]) {
            return Err(bad("control.outer", "must lie inside the outer boundary"));
        }
        Ok(d)
    }

    /// The outer boundary `Σ` (homogeneous Dirichlet data).
    pub fn outer(&self) -> &Polygon {
        &self.outer
    }

    /// The inner and outer boundaries of `D`.
    pub fn control(&self) -> [&Polygon; 2] {
        [&self.control_inner, &self.control_outer]
    }

    /// Whether `p` lies in the control region `D`.
    pub fn in_control(&self, p: Point<2>) -> bool {
        self.control_outer.contains(p) && !self.control_inner.contains(p)
    }

    /// `|D|`, as polygons.
    pub fn control_area(&self) -> f64 {
        self.control_outer.signed_area() - self.control_inner.signed_area()
    }

    /// Checks that the curve is admissible: it lies inside `Σ`, does not meet `D`, and
    /// its segments cross neither each other nor those of `Σ` and `∂D` (one pass of
    /// the spatial hashing over all of them).
    pub fn check_curve(&self, curve: &CurveMesh) -> Result<(), BulkError> {
        let loops = [&self.outer, &self.control_inner, &self.control_outer];
        let (mut all, mut segs) = loop_segments(&loops);
        let fixed = segs.len();
        let offset = all.len();
        all.extend_from_slice(curve.positions());
        segs.extend(curve.elements().iter().map(|s| [s[0] + offset, s[1] + offset]));
        if let Some(h) = find_segment_intersections(&all, &segs).into_iter().find(|h| h.b >= fixed) {
            let what = if h.a >= fixed {
                "crosses itself"
            } else if h.a < self.outer.points().len() {
                "meets the outer boundary"
            } else {
                "meets the control region"
            };
            return Err(BulkError::Inadmissible(format!("the curve {what} near ({:.4}, {:.4})", h.point.x, h.point.y)));
        }
        // no crossings: each component lies entirely on one side of every boundary
        // and of every other component; one inside another would cut the region
        // between them off from Σ (Neumann data all around: no state)
        let loops: Vec<Vec<Point<2>>> = curve.lifted_cycles().into_iter().map(|(l, _)| l).collect();
        for (k, l) in loops.iter().enumerate() {
            let others: Vec<&[Point<2>]> =
                loops.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, o)| o.as_slice()).collect();
            if winding_number(&others, l[0]) != 0 {
                return Err(BulkError::Inadmissible(format!(
                    "a curve component lies inside another one (at ({:.4}, {:.4})): the region between them \
                     would be cut off from the outer boundary",
                    l[0].x, l[0].y
                )));
            }
        }
        for cycle in curve.cycles() {
            let p = curve.positions()[cycle[0]];
            if !self.outer.contains(p) {
                return Err(BulkError::Inadmissible(format!(
                    "the curve leaves the outer boundary at ({:.4}, {:.4})",
                    p.x, p.y
                )));
            }
            if self.in_control(p) {
                return Err(BulkError::Inadmissible(format!(
                    "the curve enters the control region at ({:.4}, {:.4})",
                    p.x, p.y
                )));
            }
        }
        Ok(())
    }
}

/// Points and closing segments of several polygons, concatenated.
pub(super) fn loop_segments(loops: &[&Polygon]) -> (Vec<Point<2>>, Vec<[usize; 2]>) {
    let mut points = Vec::new();
    let mut segments = Vec::new();
    for l in loops {
        let o = points.len();
        let n = l.points().len();
        points.extend_from_slice(l.points());
        segments.extend((0..n).map(|i| [o + i, o + (i + 1) % n]));
    }
    (points, segments)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: f64, h: f64) -> Vec<Point<2>> {
        vec![
            Point::<2>::new(c - h, c - h),
            Point::<2>::new(c + h, c - h),
            Point::<2>::new(c + h, c + h),
            Point::<2>::new(c - h, c + h),
        ]
    }

    #[test]
    fn orientation_and_containment() {
        let mut pts = square(0.0, 1.0);
        pts.reverse();
        let p = Polygon::new("outer", pts).unwrap();
        assert!((p.signed_area() - 4.0).abs() < 1e-14);
        assert!(p.contains(Point::<2>::new(0.3, -0.9)));
        assert!(!p.contains(Point::<2>::new(1.3, 0.0)));
    }

    #[test]
    fn bad_polygons_and_domains_are_named() {
        let bow = vec![
            Point::<2>::new(0.0, 0.0),
            Point::<2>::new(1.0, 1.0),
            Point::<2>::new(1.0, 0.0),
            Point::<2>::new(0.0, 1.0),
        ];
        let e = Polygon::new("outer", bow).unwrap_err();
        assert!(e.to_string().contains("outer") && e.to_string().contains("itself"), "{e}");
        let outer = Polygon::new("outer", square(0.0, 3.0)).unwrap();
        let a = Polygon::new("control.inner", square(0.0, 2.6)).unwrap();
        let b = Polygon::new("control.outer", square(0.0, 2.5)).unwrap();
        let e = DesignDomain::new(outer, a, b).unwrap_err();
        assert!(e.to_string().contains("control.inner"), "{e}");
    }

    #[test]
    fn curves_crossing_the_control_region_are_inadmissible() {
        let outer = Polygon::new("outer", square(0.0, 3.0)).unwrap();
        let a = Polygon::new("control.inner", square(0.0, 2.0)).unwrap();
        let b = Polygon::new("control.outer", square(0.0, 2.5)).unwrap();
        let d = DesignDomain::new(outer, a, b).unwrap();
        assert!((d.control_area() - 9.0).abs() < 1e-12);
        let curve = |c: f64, h: f64| polygon(&square(c, h), None).unwrap();
        assert!(d.check_curve(&curve(0.0, 1.0)).is_ok());
        assert!(matches!(d.check_curve(&curve(0.0, 2.2)), Err(BulkError::Inadmissible(_))));
        assert!(matches!(d.check_curve(&curve(1.0, 1.5)), Err(BulkError::Inadmissible(_))));
        // two components side by side are fine, one inside the other is not
        let two = |c: f64, h: f64| crate::geometry::union(&[curve(-c, h), curve(c, h)]).unwrap();
        assert!(d.check_curve(&two(0.7, 0.3)).is_ok());
        let nested = crate::geometry::union(&[curve(0.0, 1.5), curve(0.0, 0.5)]).unwrap();
        let e = d.check_curve(&nested).unwrap_err();
        assert!(matches!(&e, BulkError::Inadmissible(m) if m.contains("inside another")), "{e}");
    }
}
