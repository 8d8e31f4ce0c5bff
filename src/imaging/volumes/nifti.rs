//! NIfTI-1 volumes (`.nii`, gzip-compressed `.nii.gz`; single file, `n+1`), placed
//! by their `sform` or `qform` (else spaced by `pixdim`).

use super::isotropic;
use crate::imaging::grid::{Grid, Placement, SampleKind};
use crate::imaging::limits::ImageLimits;
use crate::imaging::ImageError;
use nalgebra::{Quaternion, UnitQuaternion};
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
    // a vox_offset far beyond the file (up to f32::MAX) must not overflow the end
    let data = start.checked_add(n * size).and_then(|end| b.get(start..end)).ok_or_else(|| {
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
    let pixdim: [f64; 4] = std::array::from_fn(|k| f32_at(76 + 4 * k) as f64);
    let qform = [i16_at(252) as f64, f32_at(256) as f64, f32_at(260) as f64, f32_at(264) as f64];
    let offset = [f32_at(268) as f64, f32_at(272) as f64, f32_at(276) as f64];
    let srows: [[f64; 4]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| f32_at(280 + 16 * r + 4 * c) as f64));
    let sform = (i16_at(254) > 0).then_some(srows);
    let placement = placement(pixdim, qform, offset, sform);
    isotropic(input, Grid::new(3, dims, values, kind).placed(placement), limits)
}

/// Where a NIfTI-1 file's voxels lie: by its `sform` (`srow_*`) when
/// `sform_code > 0`, else by its `qform` (`[qform_code, b, c, d]`, the quaternion's
/// rotation of the voxel steps `pixdim`, `qfac = pixdim[0]` flipping the third,
/// from `qoffset`) when `qform_code > 0`, in RAS coordinates turned into
/// `left-posterior-superior`; else along the coordinate axes, `pixdim` apart, in no
/// named space (NIfTI's method 1). A non-finite or degenerate transform falls back
/// to the last.
fn placement(pixdim: [f64; 4], qform: [f64; 4], offset: [f64; 3], sform: Option<[[f64; 4]; 3]>) -> Placement {
    let steps: [f64; 3] = std::array::from_fn(|a| {
        let s = pixdim[a + 1].abs();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    // columns of the RAS transform, and its origin
    let ras: Option<([[f64; 3]; 3], [f64; 3])> = if let Some(rows) = sform {
        Some((std::array::from_fn(|a| std::array::from_fn(|c| rows[c][a])), std::array::from_fn(|c| rows[c][3])))
    } else if qform[0] > 0.0 {
        let [_, b, c, d] = qform;
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = UnitQuaternion::from_quaternion(Quaternion::new(a, b, c, d)).to_rotation_matrix();
        let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let scale = [steps[0], steps[1], steps[2] * qfac];
        Some((std::array::from_fn(|k| std::array::from_fn(|row| r[(row, k)] * scale[k])), offset))
    } else {
        None
    };
    let aligned = || Placement::aligned(steps, [0.0; 3]);
    let Some((axes, origin)) = ras else { return aligned() };
    let placed = Placement::from_ras(axes, origin);
    let finite = placed.axes.iter().flatten().chain(&placed.origin).all(|v| v.is_finite());
    let least = placed.spacing().iter().copied().fold(f64::INFINITY, f64::min);
    if finite && least > 0.0 && placed.matrix().determinant().abs() > 1e-6 * least.powi(3) {
        placed
    } else {
        aligned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter turn about z by the quaternion, `qfac` −1, then an `sform` that
    /// takes precedence, and a degenerate one that falls back to `pixdim`: in
    /// left-posterior-superior coordinates (RAS with x and y negated).
    #[test]
    fn the_transform_is_read_from_sform_or_qform() {
        let d = std::f64::consts::FRAC_1_SQRT_2;
        let q = placement([-1.0, 2.0, 3.0, 4.0], [1.0, 0.0, 0.0, d], [10.0, 20.0, 30.0], None);
        let close = |a: &Placement, axes: [[f64; 3]; 3], origin: [f64; 3]| {
            let near = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| (p - q).abs() < 1e-6);
            near(a.axes.as_flattened(), axes.as_flattened()) && near(&a.origin, &origin)
        };
        // RAS columns (0,2,0), (−3,0,0), (0,0,−4) from (10,20,30)
        assert!(close(&q, [[0.0, -2.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, -4.0]], [-10.0, -20.0, 30.0]), "{q:?}");
        assert_eq!(q.space.as_deref(), Some("left-posterior-superior"));
        assert!(close(
            &Placement::aligned(q.spacing(), [0.0; 3]),
            Placement::aligned([2.0, 3.0, 4.0], [0.0; 3]).axes,
            [0.0; 3]
        ));
        let rows = [[0.0, 0.0, 1.5, -7.0], [1.0, 0.0, 0.0, 8.0], [0.0, 1.0, 0.0, 9.0]];
        let s = placement([1.0, 2.0, 3.0, 4.0], [1.0, 0.0, 0.0, d], [10.0, 20.0, 30.0], Some(rows));
        assert!(close(&s, [[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.5, 0.0, 0.0]], [7.0, -8.0, 9.0]), "{s:?}");
        let flat = placement([1.0, 2.0, 3.0, 4.0], [0.0; 4], [10.0, 20.0, 30.0], Some([[0.0; 4]; 3]));
        assert_eq!(flat, Placement::aligned([2.0, 3.0, 4.0], [0.0; 3]));
        // no transform: NIfTI's method 1, along the axes in no named space
        assert_eq!(placement([1.0, 2.0, 3.0, 4.0], [0.0; 4], [1.0; 3], None), flat);
    }
}
