//! Volumes in the formats microscopy and medical imaging use: multi-page TIFF
//! stacks (one page per slice, the first at the bottom) and NIfTI-1 (`.nii`,
//! gzip-compressed `.nii.gz`; single file, `n+1`). Voxel spacing is honoured: an
//! anisotropic volume (ImageJ's `spacing=` and the X resolution of a TIFF stack;
//! `pixdim` of NIfTI) is resampled by trilinear interpolation to cubic voxels of
//! its smallest spacing, so that lengths, areas and volumes in the unit box are
//! physical. The same limits and errors as the other readers: every error names
//! the input.

use super::grid::{Grid, SampleKind};
use super::limits::ImageLimits;
use super::ImageError;
use std::io::{Cursor, Read};

/// Whether `bytes` start like a TIFF file.
pub fn is_tiff(bytes: &[u8]) -> bool {
    bytes.starts_with(b"II*\0") || bytes.starts_with(b"MM\0*")
}

/// Whether `bytes` are a NIfTI-1 file, plain or gzip-compressed.
pub fn is_nifti(bytes: &[u8]) -> bool {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut head = Vec::with_capacity(348);
        let ok = flate2::read::GzDecoder::new(bytes).take(348).read_to_end(&mut head).is_ok();
        return ok && nifti_magic(&head);
    }
    nifti_magic(bytes)
}

fn nifti_magic(b: &[u8]) -> bool {
    b.len() >= 348 && &b[344..348] == b"n+1\0"
}

/// The number of pages of a TIFF file, counted up to `cap`.
pub fn tiff_pages(bytes: &[u8], cap: usize) -> usize {
    let Ok(mut d) = tiff::decoder::Decoder::new(Cursor::new(bytes)) else { return 0 };
    let mut n = 1;
    while n < cap && d.more_images() {
        if d.next_image().is_err() {
            break;
        }
        n += 1;
    }
    n
}

/// A multi-page TIFF as a volume (gray, or colour reduced to luminance; 8, 16 or
/// 32-bit integer or float samples).
pub fn decode_tiff_stack(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    let fail = |m: String| ImageError::new(input, m);
    let mut limits_tiff = tiff::decoder::Limits::default();
    limits_tiff.decoding_buffer_size = limits.max_voxels.saturating_mul(16);
    let mut d = tiff::decoder::Decoder::new(Cursor::new(bytes))
        .map_err(|e| fail(format!("is not a readable TIFF: {e}")))?
        .with_limits(limits_tiff);
    let description = d.get_tag_ascii_string(tiff::tags::Tag::ImageDescription).unwrap_or_default();
    // XResolution is a rational (pixels per unit)
    let xy_spacing = match d.get_tag(tiff::tags::Tag::XResolution) {
        Ok(tiff::decoder::ifd::Value::Rational(n, q)) if n > 0 && q > 0 => q as f64 / n as f64,
        Ok(v) => v.into_f64().ok().filter(|r| r.is_finite() && *r > 0.0).map_or(1.0, |r| 1.0 / r),
        Err(_) => 1.0,
    };
    let z_spacing = imagej_value(&description, "spacing").unwrap_or(xy_spacing);
    let (mut values, mut dims) = (Vec::new(), [0usize; 2]);
    let mut kind;
    let mut page = 0usize;
    loop {
        let (w, h) = d.dimensions().map_err(|e| fail(format!("page {page}: {e}")))?;
        let (w, h) = (w as usize, h as usize);
        if page == 0 {
            dims = [w, h];
            limits.check(input, &[w, h])?;
        } else if [w, h] != dims {
            return Err(fail(format!("page {page} is {w}×{h}, but page 0 is {}×{}", dims[0], dims[1])));
        }
        if (page + 1).saturating_mul(w * h) > limits.max_voxels {
            return Err(fail(format!("has more than {} voxels, the limit", limits.max_voxels)));
        }
        let channels = match d.colortype().map_err(|e| fail(format!("page {page}: {e}")))? {
            tiff::ColorType::Gray(_) => 1,
            tiff::ColorType::GrayA(_) => 2,
            tiff::ColorType::RGB(_) => 3,
            tiff::ColorType::RGBA(_) => 4,
            other => return Err(fail(format!("page {page}: unsupported colour type {other:?}"))),
        };
        let (samples, k) = samples(d.read_image().map_err(|e| fail(format!("page {page}: {e}")))?)
            .ok_or_else(|| fail(format!("page {page}: unsupported sample type")))?;
        kind = k;
        if samples.len() != w * h * channels {
            return Err(fail(format!("page {page}: {} samples for {w}×{h}×{channels}", samples.len())));
        }
        // rows flipped (j = 0 at the bottom, as 2D images); colour to luminance
        for j in (0..h).rev() {
            for i in 0..w {
                let s = &samples[(i + w * j) * channels..][..channels];
                values.push(if channels >= 3 { 0.2126 * s[0] + 0.7152 * s[1] + 0.0722 * s[2] } else { s[0] });
            }
        }
        page += 1;
        if !d.more_images() {
            break;
        }
        d.next_image().map_err(|e| fail(format!("page {page}: {e}")))?;
    }
    limits.check(input, &[dims[0], dims[1], page])?;
    let grid = Grid::new(3, [dims[0], dims[1], page], values, kind);
    isotropic(input, grid, [xy_spacing, xy_spacing, z_spacing], limits)
}

/// A `key=value` number of an ImageJ image description.
fn imagej_value(description: &str, key: &str) -> Option<f64> {
    description
        .lines()
        .find_map(|l| l.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .and_then(|v| v.trim().parse().ok())
        .filter(|v: &f64| v.is_finite() && *v > 0.0)
}

/// The samples of one page as `f64`, and their kind.
fn samples(r: tiff::decoder::DecodingResult) -> Option<(Vec<f64>, SampleKind)> {
    use tiff::decoder::DecodingResult as R;
    Some(match r {
        R::U8(v) => (v.into_iter().map(f64::from).collect(), SampleKind::U8),
        R::U16(v) => (v.into_iter().map(f64::from).collect(), SampleKind::U16),
        R::U32(v) => (v.into_iter().map(f64::from).collect(), SampleKind::F32),
        R::I8(v) => (v.into_iter().map(f64::from).collect(), SampleKind::U8),
        R::I16(v) => (v.into_iter().map(f64::from).collect(), SampleKind::U16),
        R::I32(v) => (v.into_iter().map(f64::from).collect(), SampleKind::F32),
        R::F32(v) => (v.into_iter().map(f64::from).collect(), SampleKind::F32),
        R::F64(v) => (v, SampleKind::F32),
        _ => return None,
    })
}

/// A NIfTI-1 volume (`n+1`, either byte order, gzip or not; 3D, or 4D with one
/// time point), scaled by `scl_slope`/`scl_inter`.
pub fn decode_nifti(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    let fail = |m: String| ImageError::new(input, m);
    let raw;
    let b: &[u8] = if bytes.starts_with(&[0x1f, 0x8b]) {
        // at most the largest volume allowed, in 8-byte samples, plus the header
        let cap = (limits.max_voxels as u64).saturating_mul(8) + 352 + 1;
        let mut out = Vec::new();
        flate2::read::GzDecoder::new(bytes)
            .take(cap)
            .read_to_end(&mut out)
            .map_err(|e| fail(format!("is a corrupt gzip stream: {e}")))?;
        if out.len() as u64 >= cap {
            return Err(fail(format!("decompresses to more than a volume of {} voxels", limits.max_voxels)));
        }
        raw = out;
        &raw
    } else {
        bytes
    };
    if b.len() < 348 {
        return Err(fail(format!("is {} bytes, shorter than a NIfTI-1 header (348)", b.len())));
    }
    let little = i32::from_le_bytes(b[0..4].try_into().unwrap()) == 348;
    if !little && i32::from_be_bytes(b[0..4].try_into().unwrap()) != 348 {
        return Err(fail("is not NIfTI-1 (sizeof_hdr is not 348)".into()));
    }
    if !nifti_magic(b) {
        return Err(fail("is not a single-file NIfTI-1 (`n+1` magic); .hdr/.img pairs are not read".into()));
    }
    let i16_at = |o: usize| {
        let a = [b[o], b[o + 1]];
        if little {
            i16::from_le_bytes(a)
        } else {
            i16::from_be_bytes(a)
        }
    };
    let f32_at = |o: usize| {
        let a = [b[o], b[o + 1], b[o + 2], b[o + 3]];
        if little {
            f32::from_le_bytes(a)
        } else {
            f32::from_be_bytes(a)
        }
    };
    let ndim = i16_at(40);
    let dim: Vec<i16> = (1..=7).map(|k| i16_at(40 + 2 * k)).collect();
    if !(2..=4).contains(&ndim) || (ndim == 4 && dim[3] != 1) {
        return Err(fail(format!(
            "has {ndim} dimensions (sizes {:?}); a 3D volume is needed",
            &dim[..ndim.clamp(0, 7) as usize]
        )));
    }
    if dim[..3].iter().any(|&n| n < 1) {
        return Err(fail(format!("has sizes {:?}", &dim[..3])));
    }
    let dims = [dim[0] as usize, dim[1] as usize, if ndim >= 3 { dim[2] as usize } else { 1 }];
    limits.check(input, &dims)?;
    let (datatype, bitpix) = (i16_at(70), i16_at(72));
    let size = match datatype {
        2 | 256 => 1,
        4 | 512 => 2,
        8 | 16 | 768 => 4,
        64 => 8,
        _ => {
            return Err(fail(format!(
                "has datatype {datatype}; uint8, int8, (u)int16, (u)int32, float32 and float64 are read"
            )))
        }
    };
    if bitpix as usize != 8 * size {
        return Err(fail(format!("has bitpix {bitpix} for datatype {datatype}")));
    }
    let offset = f32_at(108);
    if !(offset.is_finite() && offset >= 348.0) {
        return Err(fail(format!("has vox_offset {offset}")));
    }
    let n = dims[0] * dims[1] * dims[2];
    let start = offset as usize;
    let data = b.get(start..start + n * size).ok_or_else(|| {
        fail(format!("is truncated: {} voxels of {size} bytes from byte {start}, {} bytes in all", n, b.len()))
    })?;
    let value = |c: &[u8]| -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = c.try_into().unwrap();
                (if little { <$t>::from_le_bytes(a) } else { <$t>::from_be_bytes(a) }) as f64
            }};
        }
        match datatype {
            2 => c[0] as f64,
            256 => c[0] as i8 as f64,
            4 => num!(i16, 2),
            512 => num!(u16, 2),
            8 => num!(i32, 4),
            768 => num!(u32, 4),
            16 => num!(f32, 4),
            _ => num!(f64, 8),
        }
    };
    let (slope, inter) = (f32_at(112) as f64, f32_at(116) as f64);
    let scale = |v: f64| {
        if slope.is_finite() && slope != 0.0 {
            v * slope + if inter.is_finite() { inter } else { 0.0 }
        } else {
            v
        }
    };
    let mut values = Vec::with_capacity(n);
    for c in data.chunks_exact(size) {
        let v = scale(value(c));
        if !v.is_finite() {
            return Err(fail(format!("has a non-finite voxel at index {}", values.len())));
        }
        values.push(v);
    }
    let kind = match size {
        1 => SampleKind::U8,
        2 => SampleKind::U16,
        _ => SampleKind::F32,
    };
    let spacing: [f64; 3] = std::array::from_fn(|a| {
        let s = (f32_at(80 + 4 * a) as f64).abs();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    isotropic(input, Grid::new(3, dims, values, kind), spacing, limits)
}

/// `grid` resampled (trilinear) to cubic voxels of its smallest spacing when its
/// spacings differ by more than 1 %; unchanged otherwise.
pub fn isotropic(input: &str, grid: Grid, spacing: [f64; 3], limits: &ImageLimits) -> Result<Grid, ImageError> {
    let h = spacing.iter().copied().fold(f64::INFINITY, f64::min);
    if spacing.iter().all(|&s| s <= 1.01 * h) {
        return Ok(grid);
    }
    let dims: [usize; 3] = std::array::from_fn(|a| ((grid.dims[a] as f64 * spacing[a] / h).round() as usize).max(1));
    limits.check(input, &dims).map_err(|e| {
        ImageError::new(input, format!("resampled to cubic voxels of its spacing {h} ({spacing:?}): {}", e.message))
    })?;
    let at = |a: usize, i: usize| {
        // the new sample centre in old sample coordinates, clamped to the grid
        (((i as f64 + 0.5) * h / spacing[a]) - 0.5).clamp(0.0, (grid.dims[a] - 1) as f64)
    };
    let mut values = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] {
        let z = at(2, k);
        for j in 0..dims[1] {
            let y = at(1, j);
            for i in 0..dims[0] {
                let x = at(0, i);
                let (x0, y0, z0) = (x.floor() as usize, y.floor() as usize, z.floor() as usize);
                let (x1, y1, z1) =
                    ((x0 + 1).min(grid.dims[0] - 1), (y0 + 1).min(grid.dims[1] - 1), (z0 + 1).min(grid.dims[2] - 1));
                let (fx, fy, fz) = (x - x0 as f64, y - y0 as f64, z - z0 as f64);
                let v = |i, j, k| grid.values[grid.index(i, j, k)];
                let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
                let c00 = lerp(v(x0, y0, z0), v(x1, y0, z0), fx);
                let c10 = lerp(v(x0, y1, z0), v(x1, y1, z0), fx);
                let c01 = lerp(v(x0, y0, z1), v(x1, y0, z1), fx);
                let c11 = lerp(v(x0, y1, z1), v(x1, y1, z1), fx);
                values.push(lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz));
            }
        }
    }
    Ok(Grid::new(3, dims, values, grid.kind))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NIfTI-1 header for `dims`, float32, spacing `pixdim`.
    fn nifti(dims: [i16; 3], pixdim: [f32; 3], data: &[f32], big_endian: bool) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        let put_i32 = |h: &mut Vec<u8>, o: usize, v: i32| {
            h[o..o + 4].copy_from_slice(&if big_endian { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        let put_i16 = |h: &mut Vec<u8>, o: usize, v: i16| {
            h[o..o + 2].copy_from_slice(&if big_endian { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        let put_f32 = |h: &mut Vec<u8>, o: usize, v: f32| {
            h[o..o + 4].copy_from_slice(&if big_endian { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        put_i32(&mut h, 0, 348);
        put_i16(&mut h, 40, 3);
        for a in 0..3 {
            put_i16(&mut h, 42 + 2 * a, dims[a]);
            put_f32(&mut h, 80 + 4 * a, pixdim[a]);
        }
        put_i16(&mut h, 70, 16);
        put_i16(&mut h, 72, 32);
        put_f32(&mut h, 108, 352.0);
        h[344..348].copy_from_slice(b"n+1\0");
        for v in data {
            h.extend(if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
        }
        h
    }

    #[test]
    fn nifti_plain_gzip_and_big_endian() {
        let data: Vec<f32> = (0..4 * 5 * 6).map(|i| i as f32).collect();
        let limits = ImageLimits::default();
        for be in [false, true] {
            let b = nifti([4, 5, 6], [1.0, 1.0, 1.0], &data, be);
            assert!(is_nifti(&b));
            let g = decode_nifti("v", &b, &limits).unwrap();
            assert_eq!(g.dims, [4, 5, 6]);
            assert_eq!(g.values[g.index(3, 4, 5)], 119.0);
        }
        let b = nifti([4, 5, 6], [1.0, 1.0, 1.0], &data, false);
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut gz, &b).unwrap();
        let gz = gz.finish().unwrap();
        assert!(is_nifti(&gz));
        assert_eq!(decode_nifti("v", &gz, &limits).unwrap().values, decode_nifti("v", &b, &limits).unwrap().values);
        // truncated, wrong type, not NIfTI: errors naming the input
        let e = decode_nifti("vol", &b[..400], &limits).unwrap_err();
        assert!(e.to_string().contains("`vol`") && e.to_string().contains("truncated"), "{e}");
        let mut bad = b.clone();
        bad[70] = 99;
        assert!(decode_nifti("vol", &bad, &limits).unwrap_err().to_string().contains("datatype 99"));
        assert!(!is_nifti(b"NRRD0004\n"));
    }

    /// A stack of `pages` gray 8-bit pages of 6×5, value `10·page + column`, with
    /// ImageJ's `spacing` and an X resolution.
    fn tiff_stack(pages: usize, spacing: f64, resolution: u32) -> Vec<u8> {
        use tiff::encoder::{colortype::Gray8, Rational, TiffEncoder};
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        for p in 0..pages {
            let mut image = enc.new_image::<Gray8>(6, 5).unwrap();
            image
                .encoder()
                .write_tag(
                    tiff::tags::Tag::ImageDescription,
                    format!("ImageJ=1.11a\nimages={pages}\nspacing={spacing}\n").as_str(),
                )
                .unwrap();
            image.resolution(tiff::tags::ResolutionUnit::None, Rational { n: resolution, d: 1 });
            let data: Vec<u8> = (0..30).map(|i| (10 * p + i % 6) as u8).collect();
            image.write_data(&data).unwrap();
        }
        out.into_inner()
    }

    #[test]
    fn tiff_stacks() {
        let limits = ImageLimits::default();
        let b = tiff_stack(4, 1.0, 1);
        assert!(is_tiff(&b));
        assert_eq!(tiff_pages(&b, 10), 4);
        let g = decode_tiff_stack("stack", &b, &limits).unwrap();
        assert_eq!(g.dims, [6, 5, 4]);
        assert_eq!(g.values[g.index(3, 0, 2)], 23.0);
        // slices 3 pixels apart: 12 slices after resampling
        let g = decode_tiff_stack("stack", &tiff_stack(4, 3.0, 1), &limits).unwrap();
        assert_eq!(g.dims, [6, 5, 12]);
        // pixels 0.5 apart (resolution 2 per unit), slices 1 apart: twice the slices
        let g = decode_tiff_stack("stack", &tiff_stack(4, 1.0, 2), &limits).unwrap();
        assert_eq!(g.dims, [6, 5, 8]);
        let e = decode_tiff_stack("stack", &b[..b.len() / 2], &limits).unwrap_err();
        assert!(e.to_string().contains("`stack`"), "{e}");
        let small = ImageLimits { max_voxels: 100, ..limits };
        assert!(decode_tiff_stack("stack", &b, &small).unwrap_err().to_string().contains("limit"));
    }

    /// Slices 2 apart with pixels 1 apart: resampled to twice the slices, a linear
    /// ramp in z kept exactly.
    #[test]
    fn anisotropic_spacing_is_resampled() {
        let data: Vec<f32> = (0..4 * 4 * 5).map(|i| (i / 16) as f32 * 10.0).collect();
        let b = nifti([4, 4, 5], [1.0, 1.0, 2.0], &data, false);
        let g = decode_nifti("v", &b, &ImageLimits::default()).unwrap();
        assert_eq!(g.dims, [4, 4, 10]);
        // new slice k has its centre at old z = (k + ½)/2 − ½ (clamped), value 10 z
        for k in 1..9 {
            let z = ((k as f64 + 0.5) / 2.0 - 0.5).clamp(0.0, 4.0);
            assert!((g.values[g.index(1, 2, k)] - 10.0 * z).abs() < 1e-9);
        }
    }
}
