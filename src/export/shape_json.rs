//! `shape.json`: `{"dimension": 2, "components": [{"vertices": [[x, y], ...]}]}` for
//! curves (each component in the direction of its segments, counter-clockwise for
//! outer boundaries), `{"dimension": 3, "vertices": [...], "triangles": [...]}` for
//! surfaces, plus `"energy"` and `"iteration"`.

use crate::flow::MeshData;
use serde_json::{json, Value};

/// The JSON document of a shape at some iteration.
pub fn shape_json(mesh: &MeshData, energy: f64, iteration: usize) -> Value {
    let energy = if energy.is_finite() { json!(energy) } else { Value::Null };
    if mesh.dimension == 2 {
        let n = mesh.positions.len();
        let mut next = vec![usize::MAX; n];
        for e in &mesh.elements {
            next[e[0]] = e[1];
        }
        let mut seen = vec![false; n];
        let mut components = Vec::new();
        for start in 0..n {
            if seen[start] || next[start] == usize::MAX {
                continue;
            }
            let mut verts = Vec::new();
            let mut v = start;
            while !seen[v] && v != usize::MAX {
                seen[v] = true;
                verts.push(json!([mesh.positions[v][0], mesh.positions[v][1]]));
                v = next[v];
            }
            components.push(json!({ "vertices": verts }));
        }
        json!({ "dimension": 2, "components": components, "energy": energy, "iteration": iteration })
    } else {
        json!({
            "dimension": 3,
            "vertices": mesh.positions,
            "triangles": mesh.elements,
            "energy": energy,
            "iteration": iteration,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::circle;

    #[test]
    fn curve_layout() {
        let c = circle([0.0, 0.0], 1.0, 8).unwrap();
        let v = shape_json(&MeshData::from(&c), 1.5, 3);
        assert_eq!(v["dimension"], 2);
        assert_eq!(v["components"][0]["vertices"].as_array().unwrap().len(), 8);
        assert_eq!(v["iteration"], 3);
    }
}
