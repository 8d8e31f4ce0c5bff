//! `shape.json`: `{"dimension": 2, "components": [{"vertices": [[x, y], ...]}]}` for
//! curves (each component in the direction of its segments, counter-clockwise for
//! outer boundaries), `{"dimension": 3, "vertices": [...], "triangles": [...]}` for
//! surfaces, plus `"energy"` and `"iteration"`. For image jobs also the image size
//! (`"image": {"width", "height"[, "depth"], "scale"}`) and the vertices in image
//! coordinates: `"pixels"` per curve component (column, row from the top; pixel
//! centres at integers) or `"voxels"` for surfaces (voxel indices).

use super::image_results::to_pixel;
use crate::flow::MeshData;
use crate::geometry::segment_cycles;
use crate::imaging::Grid;
use serde_json::{json, Value};

/// The JSON document of a shape at some iteration.
pub fn shape_json(mesh: &MeshData, energy: f64, iteration: usize, image: Option<&Grid>) -> Value {
    let mut doc = shape_json_plain(mesh, energy, iteration);
    if let Some(img) = image {
        let mut info = json!({"width": img.dims[0], "height": img.dims[1], "scale": img.scale()});
        if img.dimension == 3 {
            info["depth"] = json!(img.dims[2]);
        }
        doc["image"] = info;
        if mesh.dimension == 2 {
            for comp in doc["components"].as_array_mut().into_iter().flatten() {
                let pixels: Vec<Value> = comp["vertices"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|v| {
                        let x: Vec<f64> = v.as_array().into_iter().flatten().filter_map(|c| c.as_f64()).collect();
                        json!(to_pixel(img, &x))
                    })
                    .collect();
                comp["pixels"] = json!(pixels);
            }
        } else {
            doc["voxels"] = json!(mesh.positions.iter().map(|p| to_pixel(img, p)).collect::<Vec<_>>());
        }
    }
    doc
}

fn shape_json_plain(mesh: &MeshData, energy: f64, iteration: usize) -> Value {
    let energy = if energy.is_finite() { json!(energy) } else { Value::Null };
    if mesh.dimension == 2 {
        let components: Vec<Value> = segment_cycles(mesh.positions.len(), mesh.elements.iter().map(|e| (e[0], e[1])))
            .into_iter()
            .map(|mut c| {
                let Some(period) = mesh.period else {
                    return json!({ "vertices": c.iter().map(|&v| json!([mesh.positions[v][0], mesh.positions[v][1]])).collect::<Vec<_>>() });
                };
                let (dx, winds) = super::lift_component(mesh, &mut c, period);
                let vertices: Vec<Value> =
                    c.iter().zip(&dx).map(|(&v, d)| json!([mesh.positions[v][0] + d, mesh.positions[v][1]])).collect();
                json!({ "vertices": vertices, "winding": winds as u8 })
            })
            .collect();
        let mut doc = json!({ "dimension": 2, "components": components, "energy": energy, "iteration": iteration });
        if let Some(period) = mesh.period {
            doc["period"] = json!(period);
        }
        doc
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
        let v = shape_json(&MeshData::from(&c), 1.5, 3, None);
        assert_eq!(v["dimension"], 2);
        assert_eq!(v["components"][0]["vertices"].as_array().unwrap().len(), 8);
        assert_eq!(v["iteration"], 3);
    }
}
