//! NIfTI-1 volumes (`.nii`, gzip-compressed `.nii.gz`; single file, `n+1`), with
//! the spacing of `pixdim`.

use super::isotropic;
use crate::imaging::grid::{Grid, SampleKind};
use crate::imaging::limits::ImageLimits;
use crate::imaging::ImageError;
use std::io::Read;

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
