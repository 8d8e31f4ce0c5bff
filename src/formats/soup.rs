//! What the mesh readers share: the error naming the input (and the line), the
//! limits checked while reading, and a validated surface from triangles given by
//! coordinates (vertices merged) or by indices.

use crate::geometry::{AnyMesh, Mesh, MeshError, Point};
use crate::limits::MAX_VERTICES;
use std::collections::HashMap;

/// A mesh file that could not be read; names the input and, for text formats, the line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshFileError {
    #[error("input {name:?}: not a recognised mesh file (OBJ, OFF, STL or glTF)")]
    UnknownFormat { name: String },
    #[error("input {name:?}, line {line}: {message}")]
    Parse { name: String, line: usize, message: String },
    #[error("input {name:?}: {message}")]
    Content { name: String, message: String },
    #[error("input {name:?}: invalid mesh: {error}")]
    Mesh { name: String, error: MeshError },
}

/// Largest number of triangles a mesh file may give (a closed surface has about
/// twice as many triangles as vertices).
pub(super) const MAX_TRIANGLES: usize = 4 * MAX_VERTICES;

/// The error of a file with more triangles than [`MAX_TRIANGLES`], checked as they
/// are read so that a crafted file cannot make the reader hold many more.
pub(super) fn too_many_triangles(name: &str, tris: &[[usize; 3]]) -> Result<(), MeshFileError> {
    if tris.len() > MAX_TRIANGLES {
        return Err(MeshFileError::Content {
            name: name.into(),
            message: format!("more than {MAX_TRIANGLES} triangles"),
        });
    }
    Ok(())
}

/// The error of a face or polyline with more corners than a mesh may have vertices.
pub(super) fn too_many_corners(name: &str, line: usize, n: usize) -> Result<(), MeshFileError> {
    if n > MAX_VERTICES + 1 {
        return Err(parse_err(name, line, format!("more than {MAX_VERTICES} corners")));
    }
    Ok(())
}

pub(super) fn parse_err(name: &str, line: usize, message: impl Into<String>) -> MeshFileError {
    MeshFileError::Parse { name: name.into(), line, message: message.into() }
}

pub(super) fn nums<T: std::str::FromStr>(name: &str, line: usize, parts: &[&str]) -> Result<Vec<T>, MeshFileError> {
    parts
        .iter()
        .map(|p| p.parse::<T>().map_err(|_| parse_err(name, line, format!("cannot read number {p:?}"))))
        .collect()
}

pub(super) fn surface(name: &str, positions: Vec<Point<3>>, tris: Vec<[usize; 3]>) -> Result<AnyMesh, MeshFileError> {
    if positions.len() > MAX_VERTICES {
        return Err(MeshFileError::Content {
            name: name.into(),
            message: format!("more than {MAX_VERTICES} vertices"),
        });
    }
    Mesh::new(positions, tris).map(AnyMesh::Surface).map_err(|error| MeshFileError::Mesh { name: name.into(), error })
}

/// Triangles given by coordinates; merge bit-identical vertices.
pub(super) fn from_soup(name: &str, soup: Vec<[Point<3>; 3]>) -> Result<AnyMesh, MeshFileError> {
    let mut map: HashMap<[u64; 3], usize> = HashMap::new();
    let mut positions = Vec::new();
    let mut tris = Vec::with_capacity(soup.len());
    for t in soup {
        if positions.len() > MAX_VERTICES {
            break; // `surface` reports it
        }
        let ids = t.map(|p| {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            *map.entry(key).or_insert_with(|| {
                positions.push(p);
                positions.len() - 1
            })
        });
        tris.push(ids);
    }
    surface(name, positions, tris)
}
