//! Euclidean distances between the simplices of a surface (a point, a segment, a
//! triangle), and the continuous test of two triangles that move linearly: a
//! conservative advancement on their distance (Mirtich's, as in Tang et al.'s and
//! Brochu–Bridson's collision culling), which proves that they stay apart or
//! reports a possible contact.

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn along(p: P, d: P, s: f64) -> P {
    [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]]
}

/// The distance from `x` to the triangle `t` ([`closest_point_on_triangle`]).
pub fn point_triangle_distance(x: P, t: &[P; 3]) -> f64 {
    let d = sub(x, closest_point_on_triangle(x, t));
    dot(d, d).sqrt()
}

/// The point of the triangle `t` closest to `x`, by the regions of the
/// triangle's plane: a vertex, an edge or the face.
pub fn closest_point_on_triangle(x: P, t: &[P; 3]) -> P {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(x, a));
    {
        let (d1, d2) = (dot(ab, ap), dot(ac, ap));
        let bp = sub(x, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(x, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let (va, vb, vc) = (d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2);
        if d1 <= 0.0 && d2 <= 0.0 {
            a
        } else if d3 >= 0.0 && d4 <= d3 {
            b
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            along(a, ab, d1 / (d1 - d3))
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            along(a, ac, d2 / (d2 - d6))
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let denom = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denom, vc * denom);
            [a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w]
        }
    }
}

/// The distance between the segments `p0 p1` and `q0 q1` (their closest points by
/// the clamped parameters of the two lines; parallel and degenerate segments
/// included).
pub fn segment_distance(p0: P, p1: P, q0: P, q1: P) -> f64 {
    let (d1, d2, r) = (sub(p1, p0), sub(q1, q0), sub(p0, q0));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let tiny = f64::MIN_POSITIVE;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let s = if denom > 0.0 { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    let d = sub(along(p0, d1, s), along(q0, d2, t));
    dot(d, d).sqrt()
}

/// The barycentric coordinates of `q` in the plane of the triangle `t` (of its
/// projection there; a degenerate triangle gives its first corner).
pub fn barycentric(q: P, t: &[P; 3]) -> [f64; 3] {
    let (ab, ac, aq) = (sub(t[1], t[0]), sub(t[2], t[0]), sub(q, t[0]));
    let (d00, d01, d11) = (dot(ab, ab), dot(ab, ac), dot(ac, ac));
    let (d20, d21) = (dot(aq, ab), dot(aq, ac));
    let denom = d00 * d11 - d01 * d01;
    if denom <= 1e-14 * d00 * d11 {
        return [1.0, 0.0, 0.0];
    }
    let (v, w) = ((d11 * d20 - d01 * d21) / denom, (d00 * d21 - d01 * d20) / denom);
    [1.0 - v - w, v, w]
}

/// The distance between two triangles that do not meet: the least of the six
/// vertex–face and the nine edge–edge distances (two disjoint triangles are
/// closest at a vertex of one or at a pair of edges). Triangles that meet may get
/// a positive value: decide meeting first ([`super::surface_intersections`]'s exact
/// test).
pub fn triangle_distance(a: &[P; 3], b: &[P; 3]) -> f64 {
    let mut d = f64::INFINITY;
    for k in 0..3 {
        d = d.min(point_triangle_distance(a[k], b)).min(point_triangle_distance(b[k], a));
        for l in 0..3 {
            d = d.min(segment_distance(a[k], a[(k + 1) % 3], b[l], b[(l + 1) % 3]));
        }
    }
    d
}

/// Iterations of the conservative advancement before a pair that keeps sliding
/// past at a hair's distance is reported as a possible contact.
const ADVANCES: usize = 64;

/// Whether two triangles whose corners move linearly from `a0`, `b0` (at `s = 0`)
/// to `a1`, `b1` (at `s = 1`) provably stay apart for every `s` in `[0, 1]`.
///
/// Their distance is translation-invariant, and a point of a triangle moves (after
/// subtracting the motion of `a`'s first corner) at most as fast as its fastest
/// corner, so it changes at rate at most `v`, the sum of the two triangles' fastest
/// relative corners. From `s`, with distance `d` there, no contact can happen
/// before `s + d / v`: the test advances so, and proves the pair apart once the
/// distance exceeds what is left of the motion; whether the triangles meet at
/// each `s` it stops at is decided exactly (the distance does not). `false` (a possible contact)
/// when they meet, come within `slack`, or are still undecided after [`ADVANCES`]
/// steps: never a contact missed, at worst one reported a hair early.
pub fn sweep_apart(a0: &[P; 3], a1: &[P; 3], b0: &[P; 3], b1: &[P; 3], slack: f64) -> bool {
    let reference = sub(a1[0], a0[0]);
    let speed = |x0: &[P; 3], x1: &[P; 3]| {
        (0..3)
            .map(|k| dot(sub(sub(x1[k], x0[k]), reference), sub(sub(x1[k], x0[k]), reference)).sqrt())
            .fold(0.0, f64::max)
    };
    let v = speed(a0, a1) + speed(b0, b1);
    let at =
        |x0: &[P; 3], x1: &[P; 3], s: f64| -> [P; 3] { std::array::from_fn(|k| along(x0[k], sub(x1[k], x0[k]), s)) };
    let meet = |s: f64| {
        let p = |t: [P; 3]| t.map(|q| super::Point::<3>::new(q[0], q[1], q[2]));
        super::surface_intersections::points_meet(&p(at(a0, a1, s)), &p(at(b0, b1, s)))
    };
    let mut s = 0.0;
    for _ in 0..ADVANCES {
        if meet(s) {
            return false;
        }
        let d = triangle_distance(&at(a0, a1, s), &at(b0, b1, s)) - slack;
        if d <= 0.0 {
            return false;
        }
        if v * (1.0 - s) < d {
            return true;
        }
        s += d / v;
        if s >= 1.0 {
            return !meet(1.0);
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::test_numbers::numbers;

    /// The distances are those of the closest pair of points over dense samples of
    /// both simplices (never more, and within the samples' spacing).
    #[test]
    fn distances_are_the_sampled_minima() {
        let mut r = numbers(7);
        let mut p = || [r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0];
        let n = 40;
        for _ in 0..50 {
            let (p0, p1, q0, q1) = (p(), p(), p(), p());
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let d = sub(along(p0, sub(p1, p0), s), along(q0, sub(q1, q0), t));
                    best = best.min(dot(d, d).sqrt());
                }
            }
            let d = segment_distance(p0, p1, q0, q1);
            assert!(d <= best + 1e-12 && d >= best - 0.1, "{d} against {best}");
        }
        // parallel segments, and a point segment
        assert!((segment_distance([0.0; 3], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [2.0, 1.0, 0.0]) - 1.0).abs() < 1e-15);
        assert!((segment_distance([0.0; 3], [0.0; 3], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0]) - 5.0).abs() < 1e-15);
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let u = [[0.2, 0.2, 0.5], [1.2, 0.2, 0.7], [0.2, 1.2, 0.9]];
        assert!((triangle_distance(&t, &u) - 0.5).abs() < 1e-15);
    }

    fn moved(t: &[P; 3], d: P) -> [P; 3] {
        t.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
    }

    /// A triangle that passes through another within one motion, meeting it at
    /// neither end, is a contact; one that slides past above it is proved apart,
    /// and so is a pair that moves rigidly together however far.
    #[test]
    fn a_pass_through_is_caught_and_sliding_past_is_not() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let small = [[0.2, 0.2, 0.3], [0.4, 0.2, 0.3], [0.2, 0.4, 0.3]];
        let below = moved(&small, [0.0, 0.0, -0.6]);
        assert!(!sweep_apart(&t, &t, &small, &below, 0.0), "tunnelling through the face");
        let beside = moved(&small, [2.0, 0.0, 0.0]);
        assert!(sweep_apart(&t, &t, &small, &beside, 0.0), "sliding 0.3 above it");
        let (t1, s1) = (moved(&t, [5.0, -3.0, 2.0]), moved(&small, [5.0, -3.0, 2.0]));
        assert!(sweep_apart(&t, &t1, &small, &s1, 0.0), "a rigid motion of both");
        assert!(!sweep_apart(&t, &t, &small, &beside, 0.31), "within the slack");
    }
}
