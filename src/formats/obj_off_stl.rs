//! Readers of Wavefront OBJ (`v`/`f` surfaces, or `v`/`l` closed polylines in the
//! plane z = 0), OFF and STL (ASCII or binary; coincident vertices merged).

use super::soup::{
    from_soup, nums, parse_err, surface, too_many_corners, too_many_triangles, MeshFileError, MAX_TRIANGLES,
};
use crate::geometry::{AnyMesh, Mesh, Point};
use crate::limits::MAX_VERTICES;
use std::collections::HashMap;

pub(super) fn read_obj(name: &str, text: &str) -> Result<AnyMesh, MeshFileError> {
    let mut verts: Vec<Point<3>> = Vec::new();
    let mut tris = Vec::new();
    let mut loops: Vec<Vec<usize>> = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let mut tokens = raw.split_whitespace();
        let Some(tag) = tokens.next() else {
            continue;
        };
        let index = |tok: &str| -> Result<usize, MeshFileError> {
            let first = tok.split('/').next().unwrap_or("");
            let i: i64 = first.parse().map_err(|_| parse_err(name, line, format!("bad index {tok:?}")))?;
            let n = verts.len() as i64;
            let idx = if i < 0 { n + i } else { i - 1 };
            if idx < 0 || idx >= n {
                return Err(parse_err(name, line, format!("index {i} out of range (1..={n})")));
            }
            Ok(idx as usize)
        };
        match tag {
            "v" => {
                let c: Vec<&str> = tokens.take(3).collect();
                if c.len() < 3 {
                    return Err(parse_err(name, line, "vertex needs x y z"));
                }
                let c: Vec<f64> = nums(name, line, &c)?;
                verts.push(Point::<3>::new(c[0], c[1], c[2]));
                if verts.len() > MAX_VERTICES {
                    return Err(MeshFileError::Content {
                        name: name.into(),
                        message: format!("more than {MAX_VERTICES} vertices"),
                    });
                }
            }
            "f" => {
                let ids = tokens.map(index).take(MAX_VERTICES + 2).collect::<Result<Vec<_>, _>>()?;
                too_many_corners(name, line, ids.len())?;
                if ids.len() < 3 {
                    return Err(parse_err(name, line, "face needs at least 3 vertices"));
                }
                for j in 1..ids.len() - 1 {
                    tris.push([ids[0], ids[j], ids[j + 1]]);
                }
                too_many_triangles(name, &tris)?;
            }
            "l" => {
                let mut ids = tokens.map(index).take(MAX_VERTICES + 2).collect::<Result<Vec<_>, _>>()?;
                too_many_corners(name, line, ids.len())?;
                if ids.len() > 1 && ids.first() == ids.last() {
                    ids.pop();
                }
                loops.push(ids);
            }
            _ => {}
        }
    }
    if tris.is_empty() && !loops.is_empty() {
        if let Some(i) = verts.iter().position(|p| p.z != 0.0) {
            return Err(MeshFileError::Content {
                name: name.into(),
                message: format!("curve vertex {} is not in the plane z = 0", i + 1),
            });
        }
        let mut positions = Vec::new();
        let mut elements = Vec::new();
        let mut map = HashMap::new();
        for l in &loops {
            let local: Vec<usize> = l
                .iter()
                .map(|&v| {
                    *map.entry(v).or_insert_with(|| {
                        positions.push(Point::<2>::new(verts[v].x, verts[v].y));
                        positions.len() - 1
                    })
                })
                .collect();
            for j in 0..local.len() {
                elements.push([local[j], local[(j + 1) % local.len()]]);
            }
        }
        return Mesh::new(positions, elements)
            .map(AnyMesh::Curve)
            .map_err(|error| MeshFileError::Mesh { name: name.into(), error });
    }
    surface(name, verts, tris)
}

pub(super) fn read_off(name: &str, text: &str) -> Result<AnyMesh, MeshFileError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| {
        let t = l.trim();
        !t.is_empty() && !t.starts_with('#')
    });
    let (_, first) = lines.next().ok_or_else(|| parse_err(name, 1, "empty file"))?;
    let mut header: Vec<&str> = first.split_whitespace().skip(1).collect();
    let mut line_no = 1;
    if header.is_empty() {
        let (k, l) = lines.next().ok_or_else(|| parse_err(name, 2, "missing counts"))?;
        header = l.split_whitespace().collect();
        line_no = k + 1;
    }
    if header.len() < 2 {
        return Err(parse_err(name, line_no, "expected vertex and face counts"));
    }
    let counts: Vec<usize> = nums(name, line_no, &header[..2])?;
    let (nv, nf) = (counts[0], counts[1]);
    if nv > MAX_VERTICES {
        return Err(MeshFileError::Content {
            name: name.into(),
            message: format!("more than {MAX_VERTICES} vertices"),
        });
    }
    if nf > MAX_TRIANGLES {
        return Err(MeshFileError::Content { name: name.into(), message: format!("more than {MAX_TRIANGLES} faces") });
    }
    // every vertex and face takes a line: the counts cannot reserve more than the text
    let mut verts = Vec::with_capacity(nv.min(text.len() / 6));
    let mut tris = Vec::with_capacity(nf.min(text.len() / 6));
    for _ in 0..nv {
        let (k, l) = lines.next().ok_or_else(|| parse_err(name, 0, "file ends inside the vertex list"))?;
        let p: Vec<&str> = l.split_whitespace().take(3).collect();
        if p.len() < 3 {
            return Err(parse_err(name, k + 1, "vertex needs x y z"));
        }
        let c: Vec<f64> = nums(name, k + 1, &p[..3])?;
        verts.push(Point::<3>::new(c[0], c[1], c[2]));
    }
    for _ in 0..nf {
        let (k, l) = lines.next().ok_or_else(|| parse_err(name, 0, "file ends inside the face list"))?;
        let mut p = l.split_whitespace();
        let Some(cnt) = p.next() else {
            continue;
        };
        let cnt: usize = nums(name, k + 1, &[cnt])?[0];
        // a face with more corners than the mesh has vertices repeats one
        if cnt > nv {
            return Err(parse_err(name, k + 1, format!("a face of {cnt} corners in a mesh of {nv} vertices")));
        }
        // indices after the count's (colours) are ignored
        let rest: Vec<usize> = nums(name, k + 1, &p.take(cnt).collect::<Vec<_>>())?;
        if cnt < 3 || rest.len() < cnt {
            return Err(parse_err(name, k + 1, "face needs a count and that many indices (at least 3)"));
        }
        if let Some(bad) = rest[..cnt].iter().find(|&&i| i >= nv) {
            return Err(parse_err(name, k + 1, format!("index {bad} out of range (0..{nv})")));
        }
        for j in 1..cnt - 1 {
            tris.push([rest[0], rest[j], rest[j + 1]]);
        }
        too_many_triangles(name, &tris)?;
    }
    surface(name, verts, tris)
}

pub(super) fn read_ascii_stl(name: &str, text: &str) -> Result<AnyMesh, MeshFileError> {
    let mut soup = Vec::new();
    let mut cur: Vec<Point<3>> = Vec::new();
    for (k, l) in text.lines().enumerate() {
        let p: Vec<&str> = l.split_whitespace().collect();
        match p.first() {
            Some(&"vertex") => {
                if p.len() < 4 {
                    return Err(parse_err(name, k + 1, "vertex needs x y z"));
                }
                let c: Vec<f64> = nums(name, k + 1, &p[1..4])?;
                cur.push(Point::<3>::new(c[0], c[1], c[2]));
            }
            Some(&"endfacet") => {
                if cur.len() != 3 {
                    return Err(parse_err(name, k + 1, "facet must have 3 vertices"));
                }
                soup.push([cur[0], cur[1], cur[2]]);
                cur.clear();
            }
            _ => {}
        }
    }
    from_soup(name, soup)
}

pub(super) fn read_binary_stl(name: &str, bytes: &[u8]) -> Result<AnyMesh, MeshFileError> {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    if n > 3 * MAX_VERTICES {
        return Err(MeshFileError::Content { name: name.into(), message: format!("{n} triangles is too many") });
    }
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64;
    let soup = (0..n)
        .map(|t| {
            let base = 84 + 50 * t + 12;
            std::array::from_fn(|v| {
                let o = base + 12 * v;
                Point::<3>::new(f(o), f(o + 4), f(o + 8))
            })
        })
        .collect();
    from_soup(name, soup)
}
