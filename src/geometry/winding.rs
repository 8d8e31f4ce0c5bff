//! Winding numbers of points: with respect to closed loops, and for a curve mesh,
//! plain or periodic ([`WindingProbe`] for many points of one mesh).

use super::intersect::cross;
use super::{CurveMesh, Point};

/// Winding number of the point `p` with respect to closed loops (each a list of
/// vertices, the closing segment implied).
pub fn winding_number<L: AsRef<[Point<2>]>>(loops: &[L], p: Point<2>) -> i32 {
    let mut w = 0;
    for l in loops {
        let l = l.as_ref();
        let n = l.len();
        for k in 0..n {
            let (a, b) = (l[k], l[(k + 1) % n]);
            if a.y <= p.y {
                if b.y > p.y && cross(b - a, p - a) > 0.0 {
                    w += 1;
                }
            } else if b.y <= p.y && cross(b - a, p - a) < 0.0 {
                w -= 1;
            }
        }
    }
    w
}

/// The winding number of `p` for a curve mesh, periodic or not (see
/// [`WindingProbe`]; to ask about many points, make the probe once).
pub fn mesh_winding_number(mesh: &CurveMesh, p: Point<2>) -> i32 {
    WindingProbe::of(mesh).at(p)
}

/// Winding numbers of points for one curve mesh, with what every point needs
/// computed once.
///
/// In the plane, the mesh's loops with their bounding boxes: a point is tested
/// only against the loops whose box holds it (a closed loop winds zero times
/// around a point outside its box).
///
/// On the cylinder, where a component winding in `+x` has its interior above it,
/// the vertical ray from `p` upwards is followed to `y = +∞` (interior of the
/// winding components, exterior of the closed ones): the number is the count of
/// winding components, plus one for each segment running in `−x` above `p`, minus
/// one for each running in `+x` (half-open in `x`, every image of `p` considered).
pub(super) struct WindingProbe<'a> {
    mesh: &'a CurveMesh,
    kind: Kind,
}

enum Kind {
    /// Each loop with its bounding box.
    Plane(Vec<(Vec<Point<2>>, [Point<2>; 2])>),
    /// The period and the count of winding components.
    Cylinder { period: f64, windings: i32 },
}

impl<'a> WindingProbe<'a> {
    pub(super) fn of(mesh: &'a CurveMesh) -> Self {
        let kind = match mesh.period() {
            Some(period) => Kind::Cylinder { period, windings: mesh.windings().iter().map(|&k| k as i32).sum() },
            None => Kind::Plane(
                mesh.lifted_cycles()
                    .into_iter()
                    .map(|(l, _)| {
                        let bbox = l.iter().fold([l[0], l[0]], |[lo, hi], p| [lo.inf(p), hi.sup(p)]);
                        (l, bbox)
                    })
                    .collect(),
            ),
        };
        WindingProbe { mesh, kind }
    }

    pub(super) fn at(&self, p: Point<2>) -> i32 {
        match &self.kind {
            Kind::Plane(loops) => loops
                .iter()
                .filter(|(_, [lo, hi])| lo.x <= p.x && p.x <= hi.x && lo.y <= p.y && p.y <= hi.y)
                .map(|(l, _)| winding_number(&[l], p))
                .sum(),
            &Kind::Cylinder { period, windings } => {
                let mut w = windings;
                for e in 0..self.mesh.num_elements() {
                    let [a, b] = self.mesh.element_points(e);
                    let (lo, hi) = (a.x.min(b.x), a.x.max(b.x));
                    // the image of p.x in [lo, lo + L)
                    let x = p.x + period * ((lo - p.x) / period).ceil();
                    if !(x >= lo && x < hi) {
                        continue;
                    }
                    let y = a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x);
                    if y > p.y {
                        w += if b.x < a.x { 1 } else { -1 };
                    }
                }
                w
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring (a circle with a reversed one inside), a disc beside it and a
    /// figure eight: at points on a grid over all of them, inside and outside the
    /// loops' boxes, the probe gives the winding numbers of all the loops.
    #[test]
    fn the_probe_gives_the_winding_numbers_of_the_mesh() {
        let ring = |c: [f64; 2], r: f64, n: usize, turn: f64| -> Vec<Point<2>> {
            (0..n)
                .map(|k| {
                    let t = turn * std::f64::consts::TAU * k as f64 / n as f64;
                    Point::<2>::new(c[0] + r * t.cos(), c[1] + r * t.sin())
                })
                .collect()
        };
        let eight = vec![
            Point::<2>::new(4.0, 0.0),
            Point::<2>::new(6.0, 2.0),
            Point::<2>::new(6.0, 0.0),
            Point::<2>::new(4.0, 2.0),
        ];
        let parts = vec![
            ring([0.0, 0.0], 2.0, 64, 1.0),
            ring([0.0, 0.0], 1.0, 32, -1.0),
            ring([1.5, 0.0], 1.0, 40, 1.0),
            eight,
        ];
        let m = crate::geometry::curves::from_polylines_trusted(parts.clone()).unwrap();
        let probe = WindingProbe::of(&m);
        let mut nonzero = 0;
        for i in 0..90 {
            for j in 0..50 {
                let p = Point::<2>::new(-2.5 + 0.1 * i as f64 + 0.003, -2.5 + 0.1 * j as f64 + 0.007);
                assert_eq!(probe.at(p), winding_number(&parts, p), "at {p:?}");
                nonzero += (probe.at(p) != 0) as usize;
            }
        }
        assert!(nonzero > 500, "{nonzero}");
    }
}
