//! `shape.json`: `{"dimension": 2, "components": [{"vertices": [[x, y], ...]}]}` for
//! curves (each component in the direction of its segments, counter-clockwise for
//! outer boundaries), `{"dimension": 3, "vertices": [...], "triangles": [...]}` for
//! surfaces, plus `"energy"` and `"iteration"`.

use crate::flow::MeshData;
use crate::geometry::segment_cycles;
use serde_json::{json, Value};

/// The JSON document of a shape at some iteration.
pub fn shape_json(mesh: &MeshData, energy: f64, iteration: usize) -> Value {
    let energy = if energy.is_finite() { json!(energy) } else { Value::Null };
    if mesh.dimension == 2 {
        let components: Vec<Value> = segment_cycles(mesh.positions.len(), mesh.elements.iter().map(|e| (e[0], e[1])))
            .iter()
            .map(|c| json!({ "vertices": c.iter().map(|&v| json!([mesh.positions[v][0], mesh.positions[v][1]])).collect::<Vec<_>>() }))
            .collect();
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
