//! glTF uploads: node transforms applied, curves and surfaces read, crafted files
//! refused with errors rather than panics or endless work.

use super::*;

/// A glTF document with one buffer (`uri` None: the GLB's BIN chunk) holding
/// f32 positions then u16 indices, one mesh primitive of `mode`, one node.
fn gltf_doc(
    positions: &[[f32; 3]],
    indices: &[u16],
    mode: u32,
    node: serde_json::Value,
    uri: Option<String>,
) -> (serde_json::Value, Vec<u8>) {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let pos_len = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let mut buffer = serde_json::json!({"byteLength": bin.len()});
    if let Some(u) = uri {
        buffer["uri"] = serde_json::json!(u);
    }
    let mut node = node;
    node["mesh"] = serde_json::json!(0);
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [node],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
        "buffers": [buffer],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": pos_len},
                        {"buffer": 0, "byteOffset": pos_len, "byteLength": 2 * indices.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
                       "min": [-10.0, -10.0, -10.0], "max": [10.0, 10.0, 10.0]},
                      {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}]
    });
    (doc, bin)
}

fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

#[test]
fn gltf_uploads_give_surfaces_and_curves_with_node_transforms() {
    use base64::Engine;
    // a tetrahedron whose faces have their own vertices (as exporters split them at seams)
    let v = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let soup: Vec<[f32; 3]> = faces.iter().flatten().map(|&i| v[i]).collect();
    let idx: Vec<u16> = (0..12).collect();
    let moved = serde_json::json!({"translation": [2.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0]});
    let (doc, bin) = gltf_doc(&soup, &idx, 4, moved, None);
    let AnyMesh::Surface(s) = read_mesh_file("tet.glb", &glb(&doc, &bin)).unwrap() else { panic!("a surface") };
    assert_eq!((s.num_vertices(), s.num_elements()), (4, 4));
    assert!((s.enclosed_measure() - 8.0 / 6.0).abs() < 1e-12, "{}", s.enclosed_measure());
    assert!(s.positions().iter().all(|p| p.x >= 2.0 - 1e-12), "translated after scaling");
    // the same as .gltf JSON with an embedded buffer
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let (doc, _) = gltf_doc(&soup, &idx, 4, serde_json::json!({}), Some(uri));
    let AnyMesh::Surface(s) = read_mesh_file("tet.gltf", &serde_json::to_vec(&doc).unwrap()).unwrap() else { panic!() };
    assert!((s.enclosed_measure() - 1.0 / 6.0).abs() < 1e-12);
    // a LINE_LOOP unit square in z = 0, rotated a quarter turn about z
    let sq = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let quarter =
        serde_json::json!({"rotation": [0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2]});
    let (doc, bin) = gltf_doc(&sq, &[0, 1, 2, 3], 2, quarter, None);
    let AnyMesh::Curve(c) = read_mesh_file("square.glb", &glb(&doc, &bin)).unwrap() else { panic!("a curve") };
    assert_eq!(c.num_vertices(), 4);
    assert!((c.enclosed_measure() - 1.0).abs() < 1e-6);
    assert!(c.positions().iter().all(|p| p.x <= 1e-6), "rotated into x ≤ 0");
    // errors name the input and say what is wrong
    let (doc, _) = gltf_doc(&soup, &idx, 4, serde_json::json!({}), Some("tet.bin".into()));
    let e = read_mesh_file("ext.gltf", &serde_json::to_vec(&doc).unwrap()).unwrap_err().to_string();
    assert!(e.contains("ext.gltf") && e.contains("external file"), "{e}");
    let (doc, bin) = gltf_doc(&sq, &[0, 1, 2, 3], 3, serde_json::json!({}), None);
    let e = read_mesh_file("strip.glb", &glb(&doc, &bin)).unwrap_err().to_string();
    assert!(e.contains("strip.glb") && e.contains("LineStrip"), "{e}");
    let (doc, bin) = gltf_doc(&sq, &[0, 1, 2, 9], 2, serde_json::json!({}), None);
    let e = read_mesh_file("bad.glb", &glb(&doc, &bin)).unwrap_err().to_string();
    assert!(e.contains("bad.glb") && e.contains("index 9"), "{e}");
    let e = read_mesh_file("trunc.glb", &glb(&doc, &bin)[..40]).unwrap_err().to_string();
    assert!(e.contains("trunc.glb") && e.contains("glTF"), "{e}");
}

#[test]
fn crafted_gltf_files_are_errors_not_panics_or_endless_work() {
    let sq = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let (doc, bin) = gltf_doc(&sq, &[0, 1, 2, 3], 2, serde_json::json!({}), None);
    let bad = |edit: &dyn Fn(&mut serde_json::Value)| -> String {
        let mut d = doc.clone();
        edit(&mut d);
        read_mesh_file("crafted.glb", &glb(&d, &bin)).expect_err("should be rejected").to_string()
    };
    // an edit of the document, and what the error must say
    type Case<'a> = (&'a dyn Fn(&mut serde_json::Value), &'a str);
    let cases: Vec<Case> = vec![
        // a node reached twice (2^64 visits if followed blindly)
        (
            &|d| {
                d["nodes"] = serde_json::json!([{"children": [1, 1]}, {"mesh": 0}]);
            },
            "reached twice",
        ),
        (&|d| d["bufferViews"][0]["byteStride"] = serde_json::json!(4), "stride"),
        (&|d| d["accessors"][1]["componentType"] = serde_json::json!(5126), "unsigned integer"),
        (&|d| d["accessors"][0]["count"] = serde_json::json!(1_000_000_000u64), "position and index records"),
        (&|d| d["accessors"][0]["count"] = serde_json::json!(5), "past the end"),
        (
            &|d| d["accessors"][1]["sparse"] = serde_json::json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 1}}),
            "sparse",
        ),
        (&|d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = serde_json::json!(5), "glTF"),
        (&|d| d["accessors"][0]["type"] = serde_json::json!("VEC2"), "float VEC3"),
        (&|d| d["accessors"][0]["min"] = serde_json::json!(vec![0.0; 17]), "more than 16"),
        (
            &|d| {
                d["nodes"] = serde_json::json!(vec![serde_json::json!({}); 400_000]);
            },
            "outside its strings",
        ),
    ];
    for (edit, needle) in cases {
        let e = bad(edit);
        assert!(e.contains("crafted.glb") && e.contains(needle), "{needle}: {e}");
    }
    // a GLB header declaring fewer bytes than the header itself (found by fuzzing:
    // the crate subtracts unchecked) and one cut short
    for len in [0u32, 11] {
        let mut b = glb(&doc, &bin);
        b[8..12].copy_from_slice(&len.to_le_bytes());
        let e = read_mesh_file("crafted.glb", &b).unwrap_err().to_string();
        assert!(e.contains("crafted.glb") && e.contains("header"), "{e}");
    }
    let e = read_mesh_file("crafted.glb", b"glTF\x02\0\0\0").unwrap_err().to_string();
    assert!(e.contains("crafted.glb") && e.contains("header"), "{e}");
}

#[test]
fn a_long_chain_of_gltf_nodes_is_walked_without_recursion() {
    let sq = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let (mut doc, bin) = gltf_doc(&sq, &[0, 1, 2, 3], 2, serde_json::json!({}), None);
    let n = 30_000;
    let mut nodes: Vec<serde_json::Value> = (1..n).map(|i| serde_json::json!({"children": [i]})).collect();
    nodes.push(serde_json::json!({"mesh": 0, "translation": [0.5, 0.0, 0.0]}));
    doc["nodes"] = serde_json::json!(nodes);
    let AnyMesh::Curve(c) = read_mesh_file("chain.glb", &glb(&doc, &bin)).unwrap() else { panic!("a curve") };
    assert!(c.positions().iter().all(|p| p.x >= 0.5), "the leaf's transform applies");
}
