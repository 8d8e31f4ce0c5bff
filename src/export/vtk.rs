//! VTK's XML formats, as ParaView, PyVista and meshio read them: a shape as
//! PolyData (`.vtp`: a curve as lines, a surface as triangles, with point data)
//! and a time series as a collection (`.pvd`: one file per time step).
//!
//! Arrays are written `format="binary"` (base64 of a `UInt64` byte count and the
//! little-endian values), points as `Float64` triples (a curve's `z` is 0).

use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use std::fmt::Write;

/// The cells of a piece: a curve's segments (VTK lines) or a surface's triangles
/// (VTK polys).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VtkCells {
    Lines,
    Polys,
}

/// One shape to write: its points, its cells (vertex indices) and the per-point
/// fields (name, one value per point).
#[derive(Debug, Clone, PartialEq)]
pub struct VtkPiece<'a> {
    pub points: Vec<[f64; 3]>,
    pub cells: Vec<&'a [usize]>,
    pub kind: VtkCells,
    pub point_data: Vec<(String, &'a [f64])>,
    /// One integer per cell (e.g. its component), written as cell data.
    pub cell_data: Vec<(String, Vec<i32>)>,
}

fn binary(bytes: &[u8]) -> String {
    let mut data = Vec::with_capacity(8 + bytes.len());
    data.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    data.extend_from_slice(bytes);
    STANDARD.encode(data)
}

fn f64s<'a>(values: impl IntoIterator<Item = &'a f64>) -> String {
    binary(&values.into_iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>())
}

fn i64s(values: impl IntoIterator<Item = i64>) -> String {
    binary(&values.into_iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>())
}

/// Keeps a name an XML attribute can hold as it is (letters, digits, `_`, `-`, `.`).
fn attribute(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || "_-. ".contains(c) { c } else { '_' }).collect()
}

/// The `.vtp` file of `piece`. Point data whose length is not the number of points
/// is left out.
pub fn vtp(piece: &VtkPiece) -> Vec<u8> {
    let n = piece.points.len();
    let (lines, polys) = match piece.kind {
        VtkCells::Lines => (piece.cells.len(), 0),
        VtkCells::Polys => (0, piece.cells.len()),
    };
    let mut out = String::with_capacity(64 * n + 1024);
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str(
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PolyData>\n",
    );
    let _ = writeln!(
        out,
        "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"0\" NumberOfLines=\"{lines}\" NumberOfStrips=\"0\" NumberOfPolys=\"{polys}\">"
    );
    let fields: Vec<&(String, &[f64])> = piece.point_data.iter().filter(|(_, v)| v.len() == n).collect();
    match fields.first() {
        Some((first, _)) => {
            let _ = writeln!(out, "<PointData Scalars=\"{}\">", attribute(first));
        }
        None => out.push_str("<PointData>\n"),
    }
    for (name, values) in fields {
        let _ = writeln!(
            out,
            "<DataArray type=\"Float64\" Name=\"{}\" format=\"binary\">{}</DataArray>",
            attribute(name),
            f64s(values.iter())
        );
    }
    out.push_str("</PointData>\n<CellData>\n");
    for (name, values) in piece.cell_data.iter().filter(|(_, v)| v.len() == piece.cells.len()) {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let _ = writeln!(
            out,
            "<DataArray type=\"Int32\" Name=\"{}\" format=\"binary\">{}</DataArray>",
            attribute(name),
            binary(&bytes)
        );
    }
    out.push_str("</CellData>\n<Points>\n");
    let _ = writeln!(
        out,
        "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"binary\">{}</DataArray>",
        f64s(piece.points.iter().flatten())
    );
    out.push_str("</Points>\n");
    for (tag, count) in [("Verts", 0), ("Lines", lines), ("Strips", 0), ("Polys", polys)] {
        let _ = writeln!(out, "<{tag}>");
        let cells: &[&[usize]] = if count > 0 { &piece.cells } else { &[] };
        let connectivity = i64s(cells.iter().flat_map(|c| c.iter().map(|&v| v as i64)));
        let offsets = i64s(cells.iter().scan(0i64, |end, c| {
            *end += c.len() as i64;
            Some(*end)
        }));
        let _ = writeln!(
            out,
            "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"binary\">{connectivity}</DataArray>"
        );
        let _ = writeln!(out, "<DataArray type=\"Int64\" Name=\"offsets\" format=\"binary\">{offsets}</DataArray>");
        let _ = writeln!(out, "</{tag}>");
    }
    out.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");
    out.into_bytes()
}

/// The `.pvd` collection of `steps` (flow time, file name relative to the `.pvd`).
/// The times are made strictly increasing (a time equal to or below the one
/// before is written as the next number above it), since readers merge equal time
/// steps into one: a surgery takes no flow time, and its state is a frame of its own.
pub fn pvd(steps: &[(f64, String)]) -> Vec<u8> {
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<Collection>\n");
    let mut last = f64::NEG_INFINITY;
    for (time, file) in steps {
        let t = if time.is_finite() && *time > last { *time } else { next_up(last) };
        last = t;
        let file = file.replace('&', "&amp;").replace('"', "&quot;").replace('<', "&lt;").replace('>', "&gt;");
        let _ = writeln!(out, "<DataSet timestep=\"{t:?}\" group=\"\" part=\"0\" file=\"{file}\"/>");
    }
    out.push_str("</Collection>\n</VTKFile>\n");
    out.into_bytes()
}

/// The smallest number above `x` (0 for −∞).
fn next_up(x: f64) -> f64 {
    if x == f64::NEG_INFINITY {
        0.0
    } else if x == 0.0 {
        f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() + 1)
    } else {
        f64::from_bits(x.to_bits() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(array: &str) -> Vec<u8> {
        let data = STANDARD.decode(array).unwrap();
        let len = u64::from_le_bytes(data[..8].try_into().unwrap()) as usize;
        assert_eq!(len, data.len() - 8);
        data[8..].to_vec()
    }

    #[test]
    fn a_triangle_with_a_field() {
        let cells: Vec<Vec<usize>> = vec![vec![0, 1, 2]];
        let field = [1.0, 2.0, 3.0];
        let piece = VtkPiece {
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            cells: cells.iter().map(|c| c.as_slice()).collect(),
            kind: VtkCells::Polys,
            point_data: vec![("curvature".into(), &field[..])],
            cell_data: vec![("component".into(), vec![0])],
        };
        let text = String::from_utf8(vtp(&piece)).unwrap();
        assert!(text.contains("NumberOfPoints=\"3\"") && text.contains("NumberOfPolys=\"1\""));
        let array = |name: &str| {
            let start = text.find(&format!("Name=\"{name}\"")).unwrap();
            let open = start + text[start..].find('>').unwrap() + 1;
            let close = open + text[open..].find('<').unwrap();
            decode(&text[open..close])
        };
        let values: Vec<f64> =
            array("curvature").chunks(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
        assert_eq!(values, field);
        assert_eq!(array("Points").len(), 9 * 8);
        // the polys' arrays come after the (empty) lines' ones
        let polys = &text[text.find("<Polys>").unwrap()..];
        let open = polys.find("\"offsets\" format=\"binary\">").unwrap() + 26;
        let offsets = decode(&polys[open..open + polys[open..].find('<').unwrap()]);
        assert_eq!(i64::from_le_bytes(offsets[..8].try_into().unwrap()), 3);
    }

    #[test]
    fn times_rise_strictly() {
        let text =
            String::from_utf8(pvd(&[(0.0, "a.vtp".into()), (0.5, "b.vtp".into()), (0.5, "d/c.vtp".into())])).unwrap();
        assert!(text.contains("file=\"d/c.vtp\""));
        let times: Vec<f64> = text
            .match_indices("timestep=\"")
            .map(|(i, _)| {
                let s = &text[i + 10..];
                s[..s.find('"').unwrap()].parse().unwrap()
            })
            .collect();
        assert_eq!(times.len(), 3);
        assert!(times[0] == 0.0 && times[1] == 0.5 && times[2] > 0.5 && times[2] < 0.5 + 1e-15);
    }
}
