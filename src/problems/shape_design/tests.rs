use super::run::seeds_away_from;
use super::*;
use crate::bulk::BulkMesh;

#[test]
fn alpha_of_eq_84() {
    assert_eq!(alpha_84(-0.1, 0.3, 0.01), 1.0);
    assert_eq!(alpha_84(0.5, 0.6, 0.01), 0.01);
    // transition: p_m = 0 gives the midpoint (1 + h²)/2
    assert!((alpha_84(0.0, 0.2, 0.01) - 0.505).abs() < 1e-12);
    // p̄ = osc gives h²
    assert!((alpha_84(0.1, 0.3, 0.04) - 0.04).abs() < 1e-12);
    assert_eq!(alpha_84(0.0, 0.0, 0.01), 1.0);
}

/// A fresh triangulation seeded from an earlier one keeps the earlier triangles
/// over `D` exactly; an unseeded one does not.
#[test]
fn seeded_triangulation_keeps_the_far_field() {
    use crate::bulk::Polygon;
    use crate::geometry::circle;
    use std::collections::BTreeSet;
    let ring = |what: &str, r: f64, n: usize| Polygon::from_curve(what, circle([0.0, 0.0], r, n)).unwrap();
    let domain = DesignDomain::new(ring("outer", 3.0, 96), ring("inner", 2.0, 64), ring("outer", 2.5, 80)).unwrap();
    let opts = MeshingOptions::for_domain(&domain, 0.1);
    let first = BulkMesh::build(&domain, &circle([0.0, 0.0], 0.5, 32).unwrap(), &opts).unwrap();
    let background: Vec<Point<2>> =
        first.mesh.points.iter().zip(&first.free).filter(|(_, &f)| f).map(|(p, _)| *p).collect();
    let over_d = |m: &BulkMesh| -> BTreeSet<[[u64; 2]; 3]> {
        m.mesh
            .triangles
            .iter()
            .zip(&m.in_control)
            .filter(|(_, &c)| c)
            .map(|(t, _)| {
                let mut v = t.map(|i| [m.mesh.points[i].x.to_bits(), m.mesh.points[i].y.to_bits()]);
                v.sort();
                v
            })
            .collect()
    };
    let moved = circle([0.05, -0.03], 0.6, 40).unwrap();
    let seeds = seeds_away_from(&background, &moved);
    assert!(seeds.len() < background.len(), "seeds near the new curve are dropped");
    assert!(seeds.iter().all(|p| (p - Point::<2>::new(0.05, -0.03)).norm() > 0.6));
    let seeded = BulkMesh::build_seeded(&domain, &moved, &opts, &seeds).unwrap();
    assert_eq!(over_d(&seeded), over_d(&first));
    let fresh = BulkMesh::build(&domain, &moved, &opts).unwrap();
    assert_ne!(over_d(&fresh), over_d(&first));
}

#[test]
fn targets() {
    let c = Point::<2>::zeros();
    let t = Target::LogRadial { center: c, radius: 3.0 };
    assert!((t.value(Point::<2>::new(0.0, 3.0))).abs() < 1e-15);
    let t = Target::Polar { center: c, a: 0.45, b: 0.4, k: 6.0 };
    assert!((t.value(Point::<2>::new(2.0, 0.0)) - 0.85).abs() < 1e-15);
    assert!((t.value(Point::<2>::new(0.0, 2.0)) - 0.05).abs() < 1e-12);
}
