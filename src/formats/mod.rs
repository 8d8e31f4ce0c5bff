//! Readers of the mesh files users upload as initial shapes (bytes in, validated
//! mesh out): OBJ, OFF, STL and glTF 2.0 (`.glb`, or `.gltf` with `data:` buffers).
//! Every reader names the input (and the line of text formats) in its errors and
//! stops at the limits of [`crate::limits`] while reading, so that a crafted file
//! cannot make it hold much more. The result formats are in [`crate::export`].

mod gltf_in;
mod obj_off_stl;
mod soup;

use crate::geometry::AnyMesh;
use obj_off_stl::{read_ascii_stl, read_binary_stl, read_obj, read_off};
pub use soup::MeshFileError;

/// Read a mesh from the bytes of an uploaded file named `name`.
pub fn read_mesh_file(name: &str, bytes: &[u8]) -> Result<AnyMesh, MeshFileError> {
    let is_binary_stl = bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        bytes.len() == 84 + 50 * n
    };
    if bytes.starts_with(b"glTF") {
        return gltf_in::read_gltf(name, bytes);
    }
    if is_binary_stl && !bytes.starts_with(b"solid") {
        return read_binary_stl(name, bytes);
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        if is_binary_stl {
            MeshFileError::UnknownFormat { name: name.into() }
        } else {
            MeshFileError::Content {
                name: name.into(),
                message: "not UTF-8 text, not binary STL and not binary glTF".into(),
            }
        }
    })?;
    let head = text.trim_start();
    if head.starts_with('{') {
        gltf_in::read_gltf(name, bytes)
    } else if head.starts_with("OFF") {
        read_off(name, text)
    } else if head.starts_with("solid") && text.contains("facet") {
        read_ascii_stl(name, text)
    } else if text.lines().any(|l| l.trim_start().starts_with("v ")) {
        read_obj(name, text)
    } else if is_binary_stl {
        read_binary_stl(name, bytes)
    } else {
        Err(MeshFileError::UnknownFormat { name: name.into() })
    }
}
