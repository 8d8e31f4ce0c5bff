//! The fixed part of a shape-design domain (paper §1.2): the outer boundary `Σ` and
//! the control region `D`, the region between two nested closed polygons. The moving
//! curve `Γ` lives inside `Σ` and must not meet `D`.

use super::BulkError;
use crate::geometry::{find_segment_intersections, Point};

/// A closed simple polygon, stored counter-clockwise (first point not repeated).
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    points: Vec<Point<2>>,
}

impl Polygon {
    /// Validates a closed polygon (at least 3 distinct points, finite, simple, nonzero
    /// area) and orients it counter-clockwise. `what` names it in errors.
    pub fn new(what: &str, points: Vec<Point<2>>) -> Result<Self, BulkError> {
        let bad = |m: String| BulkError::Domain { what: what.to_string(), message: m };
        if points.len() < 3 {
            return Err(bad(format!("needs at least 3 points, got {}", points.len())));
        }
        if let Some(i) = points.iter().position(|p| !p.x.is_finite() || !p.y.is_finite()) {
            return Err(bad(format!("point {i} is not finite")));
        }
        let n = points.len();
        if let Some(i) = (0..n).find(|&i| points[i] == points[(i + 1) % n]) {
            return Err(bad(format!("points {i} and {} coincide", (i + 1) % n)));
        }
        let segments: Vec<[usize; 2]> = (0..n).map(|i| [i, (i + 1) % n]).collect();
        if let Some(h) = find_segment_intersections(&points, &segments).first() {
            return Err(bad(format!("intersects itself near ({:.4}, {:.4})", h.point.x, h.point.y)));
        }
        let mut poly = Polygon { points };
        let area = poly.signed_area();
        if area.abs() <= 1e-14 * poly.diameter().powi(2) {
            return Err(bad("encloses no area".into()));
        }
        if area < 0.0 {
            poly.points.reverse();
        }
        Ok(poly)
    }

    pub fn points(&self) -> &[Point<2>] {
        &self.points
    }

    /// `½ Σ x_i × x_{i+1}` (positive for counter-clockwise polygons).
    pub fn signed_area(&self) -> f64 {
        let n = self.points.len();
        (0..n)
            .map(|i| {
                let (a, b) = (self.points[i], self.points[(i + 1) % n]);
                a.x * b.y - a.y * b.x
            })
            .sum::<f64>()
            * 0.5
    }

    /// Largest distance between two of its points' bounding box corners.
    pub fn diameter(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (hi - lo).norm()
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounds(&self) -> (Point<2>, Point<2>) {
        let mut lo = Point::<2>::repeat(f64::INFINITY);
        let mut hi = Point::<2>::repeat(f64::NEG_INFINITY);
        for p in &self.points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (lo, hi)
    }

    /// Mean edge length.
    pub fn spacing(&self) -> f64 {
        let n = self.points.len();
        (0..n).map(|i| (self.points[(i + 1) % n] - self.points[i]).norm()).sum::<f64>() / n as f64
    }

    /// Whether `p` lies inside (crossing-number rule; points on the boundary may go either way).
    pub fn contains(&self, p: Point<2>) -> bool {
        let n = self.points.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
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
        if !d.control_outer.contains(d.control_inner.points[0]) {
            return Err(bad("control.inner", "must lie inside control.outer"));
        }
        if !d.outer.contains(d.control_outer.points[0]) {
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

    /// Checks that the curve (points and segments) is admissible: it lies inside `Σ`,
    /// does not meet `D` and its segments do not cross those of `Σ` or `∂D`.
    /// Crossings of the curve with itself are left to the caller.
    pub fn check_curve(&self, points: &[Point<2>], segments: &[[usize; 2]]) -> Result<(), BulkError> {
        let loops = [&self.outer, &self.control_inner, &self.control_outer];
        let (mut all, mut segs) = loop_segments(&loops);
        let fixed = segs.len();
        let offset = all.len();
        all.extend_from_slice(points);
        segs.extend(segments.iter().map(|s| [s[0] + offset, s[1] + offset]));
        for h in find_segment_intersections(&all, &segs) {
            if h.a < fixed && h.b >= fixed {
                return Err(BulkError::Inadmissible(format!(
                    "the curve meets the {} near ({:.4}, {:.4})",
                    if h.a < self.outer.points.len() { "outer boundary" } else { "control region" },
                    h.point.x,
                    h.point.y
                )));
            }
        }
        // no crossings: each connected piece of the curve is entirely on one side
        for s in segments {
            let p = points[s[0]];
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
        let n = l.points.len();
        points.extend_from_slice(&l.points);
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
        let segs = [[0, 1], [1, 2], [2, 3], [3, 0]];
        assert!(d.check_curve(&square(0.0, 1.0), &segs).is_ok());
        assert!(matches!(d.check_curve(&square(0.0, 2.2), &segs), Err(BulkError::Inadmissible(_))));
        assert!(matches!(d.check_curve(&square(1.0, 1.5), &segs), Err(BulkError::Inadmissible(_))));
    }
}
