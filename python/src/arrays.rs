//! numpy arrays as the in-memory files the library reads: a 2D image (gray or
//! RGB(A), uint8/uint16/float32) as an uncompressed TIFF, a volume `(z, y, x)`
//! (uint8/uint16/float32) as a raw NRRD with its spacing. Each is one copy of
//! the array's bytes; the library decodes them as it decodes uploaded files.

use std::io::Cursor;
use tiff::encoder::{colortype, TiffEncoder};

/// The file of a C-contiguous array of `dtype` ("uint8", "uint16", "float32"),
/// `shape` (2D `(rows, columns)` or `(rows, columns, channels)` with 3 or 4
/// channels; 3D `(planes, rows, columns)`) and raw native-endian `data`;
/// `spacing` of a volume in the array's axis order. An error names what is wrong.
pub fn array_file(dtype: &str, shape: &[usize], data: &[u8], spacing: Option<[f64; 3]>) -> Result<Vec<u8>, String> {
    let size = match dtype {
        "uint8" => 1,
        "uint16" => 2,
        "float32" => 4,
        other => return Err(format!("has dtype {other}; give uint8, uint16 or float32 samples")),
    };
    if data.len() != shape.iter().product::<usize>() * size {
        return Err(format!("has {} bytes for shape {shape:?} of {dtype}", data.len()));
    }
    match (shape.len(), spacing) {
        (2, None) => tiff_file(dtype, shape[1], shape[0], 1, data),
        (3, None) if (shape[2] == 3 || shape[2] == 4) && shape[0] > 4 && shape[1] > 4 && shape[2] < shape[0] => {
            tiff_file(dtype, shape[1], shape[0], shape[2], data)
        }
        (3, spacing) => Ok(nrrd_file(dtype, shape, data, spacing.unwrap_or([1.0; 3]))),
        (2, Some(_)) => Err("is a 2D image: a spacing is only for volumes".into()),
        (n, _) => Err(format!("has {n} dimensions: give a 2D image (rows, columns[, channels]) or a volume (z, y, x)")),
    }
}

fn samples<T: Copy>(data: &[u8], from: fn(&[u8]) -> T) -> Vec<T> {
    data.chunks_exact(std::mem::size_of::<T>()).map(from).collect()
}

fn tiff_file(dtype: &str, width: usize, height: usize, channels: usize, data: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Cursor::new(Vec::new());
    let mut tiff = TiffEncoder::new(&mut out).map_err(|e| e.to_string())?;
    let (w, h) = (width as u32, height as u32);
    let u16s = || samples(data, |b| u16::from_ne_bytes([b[0], b[1]]));
    let f32s = || samples(data, |b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]));
    let written = match (dtype, channels) {
        ("uint8", 1) => tiff.write_image::<colortype::Gray8>(w, h, data),
        ("uint8", 3) => tiff.write_image::<colortype::RGB8>(w, h, data),
        ("uint8", 4) => tiff.write_image::<colortype::RGBA8>(w, h, data),
        ("uint16", 1) => tiff.write_image::<colortype::Gray16>(w, h, &u16s()),
        ("uint16", 3) => tiff.write_image::<colortype::RGB16>(w, h, &u16s()),
        ("uint16", 4) => tiff.write_image::<colortype::RGBA16>(w, h, &u16s()),
        ("float32", 1) => tiff.write_image::<colortype::Gray32Float>(w, h, &f32s()),
        ("float32", 3) => tiff.write_image::<colortype::RGB32Float>(w, h, &f32s()),
        ("float32", 4) => tiff.write_image::<colortype::RGBA32Float>(w, h, &f32s()),
        _ => return Err(format!("has {channels} channels of {dtype}")),
    };
    written.map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

fn nrrd_file(dtype: &str, shape: &[usize], data: &[u8], spacing: [f64; 3]) -> Vec<u8> {
    let endian = if cfg!(target_endian = "little") { "little" } else { "big" };
    let [sz, sy, sx] = spacing;
    let mut out = format!(
        "NRRD0004\ntype: {dtype}\ndimension: 3\nsizes: {} {} {}\nspacings: {sx:?} {sy:?} {sz:?}\nendian: {endian}\nencoding: raw\n\n",
        shape[2], shape[1], shape[0]
    )
    .into_bytes();
    out.extend_from_slice(data);
    out
}
