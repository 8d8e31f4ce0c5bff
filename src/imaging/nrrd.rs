//! NRRD volumes (<http://teem.sourceforge.net/nrrd/format.html>): a text header
//! (`NRRD000x`, `field: value` lines, a blank line) followed by the attached data.
//! Read: `dimension: 3`, types uint8/uint16/float32 (any of their NRRD spellings),
//! `raw` or `gzip` encoding, either endianness; the placement from `space`,
//! `space directions` (or `spacings`) and `space origin`, an anisotropic volume
//! resampled to cubic voxels of its smallest spacing as the other volume readers do
//! ([`isotropic`]). Written: uint8 masks and uint16 labels, gzip, with the grid's
//! placement.

use super::grid::{Grid, Placement, SampleKind};
use super::limits::ImageLimits;
use super::volumes::isotropic;
use super::ImageError;
use flate2::read::GzDecoder;
use flate2::write::GzEncoder;
use std::io::{Read, Write};

fn sample_kind(t: &str) -> Option<SampleKind> {
    match t {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Some(SampleKind::U8),
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Some(SampleKind::U16),
        "float" | "float32" => Some(SampleKind::F32),
        _ => None,
    }
}

/// Parse an NRRD volume named `input` into a 3D grid (index order as in the file:
/// the first axis is `x`).
pub fn parse_nrrd(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    let fail = |m: String| ImageError::new(input, m);
    // header: lines up to the first empty line
    let mut pos = 0;
    let mut fields: Vec<(String, String)> = Vec::new();
    let mut first = true;
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(fail("has an NRRD header with no blank line before the data".into()));
        };
        let line = std::str::from_utf8(&bytes[pos..pos + len])
            .map_err(|_| fail("has an NRRD header that is not text".into()))?
            .trim_end_matches('\r');
        pos += len + 1;
        if first {
            if !line.starts_with("NRRD000") {
                return Err(fail(format!("has a bad NRRD magic line {line:?}")));
            }
            first = false;
            continue;
        }
        if line.is_empty() {
            break;
        }
        if line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once(": ") {
            fields.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
        } else if line.contains(":=") {
            continue; // key/value comments
        } else {
            return Err(fail(format!("has a malformed NRRD header line {line:?}")));
        }
    }
    let get = |k: &str| fields.iter().find(|(f, _)| f == k).map(|(_, v)| v.as_str());
    if get("data file").or(get("datafile")).is_some() {
        return Err(fail("refers to a detached data file; only attached data is supported".into()));
    }
    let ty = get("type").ok_or_else(|| fail("has no NRRD `type` field".into()))?;
    let kind = sample_kind(ty)
        .ok_or_else(|| fail(format!("has NRRD type `{ty}`; supported are uint8, uint16 and float32")))?;
    let dim: usize = get("dimension")
        .ok_or_else(|| fail("has no NRRD `dimension` field".into()))?
        .parse()
        .map_err(|_| fail("has a non-numeric NRRD `dimension`".into()))?;
    if dim != 3 {
        return Err(fail(format!("has NRRD dimension {dim}; a volume needs 3")));
    }
    let sizes: Vec<usize> = get("sizes")
        .ok_or_else(|| fail("has no NRRD `sizes` field".into()))?
        .split_whitespace()
        .map(|s| s.parse().map_err(|_| fail(format!("has a bad NRRD size {s:?}"))))
        .collect::<Result<_, _>>()?;
    if sizes.len() != 3 {
        return Err(fail(format!("has {} NRRD sizes for dimension 3", sizes.len())));
    }
    limits.check(input, &sizes)?;
    let n = sizes[0] * sizes[1] * sizes[2];
    let width = match kind {
        SampleKind::U8 => 1,
        SampleKind::U16 => 2,
        SampleKind::F32 => 4,
    };
    let big = match get("endian") {
        None | Some("little") => false,
        Some("big") => true,
        Some(e) => return Err(fail(format!("has an unknown NRRD endian `{e}`"))),
    };
    let payload = &bytes[pos..];
    let data: Vec<u8> = match get("encoding") {
        Some("raw") => payload.to_vec(),
        Some("gzip" | "gz") => {
            let mut out = Vec::with_capacity(n * width);
            GzDecoder::new(payload)
                .take((n * width) as u64 + 1)
                .read_to_end(&mut out)
                .map_err(|e| fail(format!("has corrupt gzip data: {e}")))?;
            out
        }
        Some(e) => return Err(fail(format!("has NRRD encoding `{e}`; supported are raw and gzip"))),
        None => return Err(fail("has no NRRD `encoding` field".into())),
    };
    if data.len() < n * width {
        return Err(fail(format!("has {} bytes of data, {} expected for {sizes:?} {ty}", data.len(), n * width)));
    }
    let values: Vec<f64> = data[..n * width]
        .chunks_exact(width)
        .map(|c| match kind {
            SampleKind::U8 => c[0] as f64,
            SampleKind::U16 => {
                let a = [c[0], c[1]];
                (if big { u16::from_be_bytes(a) } else { u16::from_le_bytes(a) }) as f64
            }
            SampleKind::F32 => {
                let a = [c[0], c[1], c[2], c[3]];
                (if big { f32::from_be_bytes(a) } else { f32::from_le_bytes(a) }) as f64
            }
        })
        .collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(fail(format!("voxel {i} is not a finite number")));
    }
    let axes = voxel_axes(get("spacings"), get("space directions")).map_err(fail)?;
    let origin = match get("space origin") {
        Some(text) => space_origin(text).map_err(fail)?,
        None => [0.0; 3],
    };
    let space = get("space").map(|name| name.to_ascii_lowercase());
    let grid = Grid::new(3, [sizes[0], sizes[1], sizes[2]], values, kind);
    isotropic(input, grid.placed(Placement { axes, origin, space }), limits)
}

/// An NRRD vector `(x,y,z)` of finite numbers.
fn vector(text: &str) -> Option<[f64; 3]> {
    let inner = text.trim().trim_start_matches('(').trim_end_matches(')');
    let parts: Result<Vec<f64>, _> = inner.split(',').map(|c| c.trim().parse::<f64>()).collect();
    match parts.ok()?[..] {
        [x, y, z] if [x, y, z].iter().all(|v| v.is_finite()) => Some([x, y, z]),
        _ => None,
    }
}

/// `space origin: (x,y,z)`.
fn space_origin(text: &str) -> Result<[f64; 3], String> {
    vector(text).ok_or_else(|| {
        format!("has a malformed NRRD `space origin` {text:?}: three finite numbers in parentheses are needed")
    })
}

/// The step of each axis in space: `space directions: (x,y,z) (x,y,z) (x,y,z)`,
/// else `spacings: a b c` along the coordinate axes ("nan", an axis without
/// spacing, counts as 1), else unit steps.
fn voxel_axes(spacings: Option<&str>, directions: Option<&str>) -> Result<[[f64; 3]; 3], String> {
    if let Some(text) = directions {
        let mut axes = Vec::new();
        for item in text.split_whitespace() {
            if item == "none" {
                continue;
            }
            match vector(item) {
                Some(v) if v.iter().any(|&c| c != 0.0) => axes.push(v),
                _ => return Err(format!("has a malformed NRRD `space directions` vector {item:?}")),
            }
        }
        return match axes[..] {
            [u, v, w] => Ok([u, v, w]),
            _ => Err(format!("has NRRD `space directions` {text:?}: three vectors are needed")),
        };
    }
    if let Some(text) = spacings {
        let values: Result<Vec<f64>, _> = text.split_whitespace().map(str::parse::<f64>).collect();
        let values = values.map_err(|_| format!("has a non-numeric NRRD `spacings` {text:?}"))?;
        let values: Vec<f64> = values.into_iter().map(|v| if v.is_nan() { 1.0 } else { v }).collect();
        return match values[..] {
            [a, b, c] if [a, b, c].iter().all(|v| v.is_finite() && *v > 0.0) => {
                Ok(Placement::aligned([a, b, c], [0.0; 3]).axes)
            }
            _ => Err(format!("has NRRD `spacings` {values:?}: three positive numbers are needed")),
        };
    }
    Ok(Placement::default().axes)
}

/// A 0/1 uint8 mask on the samples of `grid` as a gzip NRRD file.
pub fn encode_nrrd_mask(grid: &Grid, mask: &[bool]) -> Vec<u8> {
    let raw: Vec<u8> = mask.iter().map(|&m| m as u8).collect();
    encode_gzip_nrrd(grid, "mask", "uint8", &raw)
}

/// A label volume on the samples of `grid` as uint16 (little endian), gzip NRRD.
pub fn encode_nrrd_labels(grid: &Grid, labels: &[u16]) -> Vec<u8> {
    let raw: Vec<u8> = labels.iter().flat_map(|l| l.to_le_bytes()).collect();
    encode_gzip_nrrd(grid, "labels", "uint16\nendian: little", &raw)
}

/// The header of a gzip NRRD of `grid`'s samples (sizes, and its placement as
/// `space directions` and `space origin`) of `ty`, then `raw` compressed.
fn encode_gzip_nrrd(grid: &Grid, what: &str, ty: &str, raw: &[u8]) -> Vec<u8> {
    let (dims, p) = (grid.dims, &grid.placement);
    let space = match &p.space {
        Some(name) => format!("space: {name}"),
        None => "space dimension: 3".to_string(),
    };
    let text = |v: &[f64; 3]| format!("({},{},{})", v[0], v[1], v[2]);
    let mut out = format!(
        "NRRD0004\n# shapeflow segmentation {what}\ntype: {ty}\ndimension: 3\nsizes: {} {} {}\n{space}\n\
         space directions: {} {} {}\nspace origin: {}\nencoding: gzip\n\n",
        dims[0],
        dims[1],
        dims[2],
        text(&p.axes[0]),
        text(&p.axes[1]),
        text(&p.axes[2]),
        text(&p.origin)
    )
    .into_bytes();
    let mut gz = GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(raw).expect("writing to memory");
    out.extend(gz.finish().expect("writing to memory"));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(ty: &str, enc: &str) -> Vec<u8> {
        format!("NRRD0004\n# c\ntype: {ty}\ndimension: 3\nsizes: 4 5 6\nendian: little\nencoding: {enc}\n\n")
            .into_bytes()
    }

    #[test]
    fn raw_u16_and_gzip_mask_roundtrip() {
        let mut b = header("unsigned short", "raw");
        for i in 0..120u16 {
            b.extend(i.to_le_bytes());
        }
        let g = parse_nrrd("v", &b, &ImageLimits::default()).unwrap();
        assert_eq!(g.dims, [4, 5, 6]);
        assert_eq!(g.values[119], 119.0);
        let mask: Vec<bool> = (0..120).map(|i| i % 3 == 0).collect();
        let m = parse_nrrd("m", &encode_nrrd_mask(&g, &mask), &ImageLimits::default()).unwrap();
        assert_eq!(m.values.iter().filter(|&&v| v == 1.0).count(), 40);
        assert_eq!(m.kind, SampleKind::U8);
    }

    #[test]
    fn spacings_are_read_and_anisotropic_volumes_resampled() {
        let voxel_spacing = |s, d| voxel_axes(s, d).map(|axes| Placement { axes, ..Default::default() }.spacing());
        assert_eq!(voxel_spacing(Some("1 2 0.5"), None).unwrap(), [1.0, 2.0, 0.5]);
        assert_eq!(voxel_spacing(None, Some("(0.5,0,0) (0,0.5,0) (0,0,3)")).unwrap(), [0.5, 0.5, 3.0]);
        assert_eq!(voxel_spacing(Some("nan nan nan"), None).unwrap(), [1.0; 3]);
        assert_eq!(voxel_spacing(None, None).unwrap(), [1.0; 3]);
        assert!(voxel_spacing(Some("1 -2 1"), None).unwrap_err().contains("spacings"));
        assert!(voxel_spacing(Some("1 x 1"), None).unwrap_err().contains("non-numeric"));
        assert!(voxel_spacing(None, Some("(1,0,0) (0,1,0)")).unwrap_err().contains("space directions"));
        assert!(voxel_spacing(None, Some("(1,0,0) (0,0,0) (0,0,1)")).unwrap_err().contains("(0,0,0)"));
        // a 4×4×4 volume with slices twice as far apart: 4×4×8 cubic voxels
        let mut file =
            b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nspacings: 1 1 2\nencoding: raw\n\n".to_vec();
        file.extend((0..64).map(|i| if i < 32 { 0u8 } else { 200 }));
        let g = parse_nrrd("image", &file, &ImageLimits::default()).unwrap();
        assert_eq!(g.dims, [4, 4, 8]);
        // the new samples are half a new voxel in from the old volume's edge
        assert_eq!(g.placement, Placement::aligned([1.0; 3], [0.0, 0.0, -0.5]));
    }

    /// A result written on a resampled volume lies where the input did: its
    /// placement (the input's axes shortened to the new spacing, its origin moved
    /// to the new first sample, its space) reads back.
    #[test]
    fn results_carry_the_placement_of_their_volume() {
        // axes turned a quarter about z, slices three times as far apart as pixels
        let mut file = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nspace: left-posterior-superior\n\
            space directions: (0,0.5,0) (-0.5,0,0) (0,0,1.5)\nspace origin: (10,-20,30.25)\nencoding: raw\n\n"
            .to_vec();
        file.extend((0..64).map(|i| if i < 32 { 0u8 } else { 200 }));
        let g = parse_nrrd("image", &file, &ImageLimits::default()).unwrap();
        assert_eq!(g.dims, [4, 4, 12]);
        let expected = Placement {
            axes: [[0.0, 0.5, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.0, 0.5]],
            origin: [10.0, -20.0, 29.75],
            space: Some("left-posterior-superior".into()),
        };
        assert_eq!(g.placement, expected);
        let labels: Vec<u16> = (0..g.len()).map(|i| (i % 7) as u16).collect();
        for bytes in [encode_nrrd_mask(&g, &vec![true; g.len()]), encode_nrrd_labels(&g, &labels)] {
            let back = parse_nrrd("result", &bytes, &ImageLimits::default()).unwrap();
            assert_eq!((back.dims, &back.placement), (g.dims, &g.placement));
        }
        let text = String::from_utf8_lossy(&file).into_owned();
        let e = parse_nrrd("image", text.replace("30.25)", "x)").as_bytes(), &ImageLimits::default()).unwrap_err();
        assert!(e.message.contains("space origin"), "{e}");
    }

    #[test]
    fn errors_name_the_input() {
        let mut b = header("float", "raw");
        b.extend([0u8; 10]);
        let e = parse_nrrd("vol", &b, &ImageLimits::default()).unwrap_err();
        assert_eq!(e.input, "vol");
        assert!(e.message.contains("480 expected"), "{e}");
        let e = parse_nrrd("vol", &header("double", "raw"), &ImageLimits::default()).unwrap_err();
        assert!(e.message.contains("double"), "{e}");
        let mut b = header("uint8", "gzip");
        b.extend([1, 2, 3]);
        assert!(parse_nrrd("vol", &b, &ImageLimits::default()).unwrap_err().message.contains("gzip"));
    }
}
