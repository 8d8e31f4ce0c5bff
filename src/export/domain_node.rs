//! The fixed domain of a shape-design job in its glTF results: one node named
//! [`DOMAIN_NODE`] (extras `{"shapeflow": "display"}`, so the mesh readers skip
//! it), not animated, with the outer boundary `Σ` and the two curves of the control
//! region as `LINE_LOOP`s and ribbons (material `domain`), and the control region
//! `D` between them filled (material `control region`). This module gives the
//! geometry of its primitives; gltf/nodes.rs encodes them.

use super::fill::{region_triangles, ribbon};

/// The outline of a shape-design domain: `Σ`, and the inner and outer curves of
/// the control region `D` (closed polygons, either orientation).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DomainOutline {
    pub outer: Vec<[f64; 2]>,
    pub control: [Vec<[f64; 2]>; 2],
}

/// The node's name.
pub const DOMAIN_NODE: &str = "domain: Σ and D";

/// What a primitive of the domain node draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    /// A closed curve (`LINE_LOOP`, material `domain`).
    Loop,
    /// The control region `D` (`TRIANGLES`, material `control region`).
    Control,
    /// The ribbons along the curves (`TRIANGLES`, material `domain`).
    Ribbons,
}

/// One primitive: plane points at height `z`, and its triangles (none for a loop).
pub(super) struct Primitive {
    pub part: Part,
    pub points: Vec<[f64; 2]>,
    pub z: f64,
    pub triangles: Vec<[u32; 3]>,
}

/// The primitives of `domain`'s node, ribbons `ribbon_width` wide (a little above `D`).
pub(super) fn domain_primitives(domain: &DomainOutline, ribbon_width: f64) -> Vec<Primitive> {
    let loops = [&domain.outer, &domain.control[0], &domain.control[1]];
    let mut out: Vec<Primitive> = loops
        .iter()
        .map(|l| Primitive { part: Part::Loop, points: l.to_vec(), z: 0.0, triangles: Vec::new() })
        .collect();
    // the control region: the two control curves, filled by the even–odd rule
    let points: Vec<[f64; 2]> = domain.control.iter().flatten().copied().collect();
    let n0 = domain.control[0].len();
    let rings = vec![(0..n0).collect::<Vec<_>>(), (n0..points.len()).collect()];
    if let Some(tris) = region_triangles(&points, &rings).filter(|t| !t.is_empty()) {
        let triangles = tris.iter().map(|t| t.map(|v| v as u32)).collect();
        out.push(Primitive { part: Part::Control, points, z: 0.0, triangles });
    }
    let (mut points, mut triangles) = (Vec::new(), Vec::new());
    for l in loops {
        let order: Vec<usize> = (0..l.len()).collect();
        let (v, t) = ribbon(l, &order, ribbon_width, true);
        let base = points.len() as u32;
        points.extend(v);
        triangles.extend(t.iter().map(|t| t.map(|i| i + base)));
    }
    out.push(Primitive { part: Part::Ribbons, points, z: 0.5 * ribbon_width, triangles });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::fill::bounding_diagonal;

    /// A square `Σ` around a square annulus `D`: three loops, `D`'s area exact.
    #[test]
    fn the_control_region_is_filled_between_its_curves() {
        let square = |h: f64| vec![[-h, -h], [h, -h], [h, h], [-h, h]];
        let d = DomainOutline { outer: square(3.0), control: [square(1.0), square(2.0)] };
        let parts = domain_primitives(&d, 0.01);
        assert_eq!(parts.iter().filter(|p| p.part == Part::Loop).count(), 3);
        let control = parts.iter().find(|p| p.part == Part::Control).unwrap();
        let area: f64 = control
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| control.points[i as usize]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
            })
            .sum();
        assert!((area - 12.0).abs() < 1e-12, "{area}");
        assert_eq!(parts.last().unwrap().triangles.len(), 2 * 12, "two triangles per segment of the three loops");
        assert!((bounding_diagonal(&d.outer) - 6.0 * 2f64.sqrt()).abs() < 1e-12);
    }
}
