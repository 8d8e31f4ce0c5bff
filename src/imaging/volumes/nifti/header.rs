//! The fields of a NIfTI header that reading a volume needs, from either version:
//! NIfTI-1 (348 bytes, magic `n+1` at byte 344, 16-bit sizes and 32-bit floats)
//! and NIfTI-2 (540 bytes, magic `n+2\0\r\n\x1a\n` at byte 4, 64-bit sizes and
//! floats), in either byte order, told apart by `sizeof_hdr`.

/// The header size of NIfTI-1 and of NIfTI-2.
pub(super) const NIFTI1: usize = 348;
pub(super) const NIFTI2: usize = 540;
const MAGIC2: &[u8; 8] = b"n+2\0\r\n\x1a\n";

/// A NIfTI header's fields, widened to the NIfTI-2 types.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Header {
    /// 1 or 2.
    pub version: u8,
    pub little: bool,
    /// `dim[0]` (the number of dimensions), then the sizes `dim[1..=7]`.
    pub dim: [i64; 8],
    pub datatype: i16,
    pub bitpix: i16,
    /// `pixdim[0]` (`qfac`) and the three voxel steps.
    pub pixdim: [f64; 4],
    pub vox_offset: f64,
    pub scl_slope: f64,
    pub scl_inter: f64,
    pub qform_code: i32,
    pub sform_code: i32,
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f64; 3],
    pub qoffset: [f64; 3],
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f64; 4]; 3],
}

/// Numbers at byte offsets of a header in one byte order.
struct Fields<'a> {
    b: &'a [u8],
    little: bool,
}

macro_rules! field {
    ($name:ident, $t:ty, $n:expr) => {
        fn $name(&self, o: usize) -> $t {
            let a: [u8; $n] = self.b[o..o + $n].try_into().unwrap();
            if self.little {
                <$t>::from_le_bytes(a)
            } else {
                <$t>::from_be_bytes(a)
            }
        }
    };
}

impl Fields<'_> {
    field!(i16, i16, 2);
    field!(i32, i32, 4);
    field!(i64, i64, 8);
    field!(f32, f32, 4);
    field!(f64, f64, 8);
}

/// The header size that `sizeof_hdr` (the first four bytes, in either byte order)
/// announces, if it is one of NIfTI's, and whether it is little-endian.
fn sizeof_hdr(b: &[u8]) -> Option<(usize, bool)> {
    let first: [u8; 4] = b.get(0..4)?.try_into().ok()?;
    [(i32::from_le_bytes(first), true), (i32::from_be_bytes(first), false)]
        .into_iter()
        .find_map(|(n, little)| [NIFTI1, NIFTI2].contains(&(n as usize)).then_some((n as usize, little)))
}

/// Whether `b` begins with the `sizeof_hdr` of a NIfTI-1 or NIfTI-2 header.
pub(super) fn is_header(b: &[u8]) -> bool {
    sizeof_hdr(b).is_some()
}

/// Whether `b` begins with a single-file NIfTI-1 or NIfTI-2 header.
fn is_single_file(b: &[u8]) -> bool {
    match sizeof_hdr(b) {
        Some((NIFTI1, _)) => b.len() >= NIFTI1 && &b[344..348] == b"n+1\0",
        Some((_, _)) => b.len() >= NIFTI2 && &b[4..12] == MAGIC2,
        None => false,
    }
}

/// The header of `b`, or what is wrong with it.
pub(super) fn parse(b: &[u8]) -> Result<Header, String> {
    let Some((size, little)) = sizeof_hdr(b) else {
        return Err(format!("is not NIfTI (sizeof_hdr is neither {NIFTI1} nor {NIFTI2})"));
    };
    let v = if size == NIFTI1 { 1 } else { 2 };
    if b.len() < size {
        return Err(format!("is {} bytes, shorter than a NIfTI-{v} header ({size})", b.len()));
    }
    if !is_single_file(b) {
        return Err(format!("is not a single-file NIfTI-{v} (`n+{v}` magic); .hdr/.img pairs are not read"));
    }
    let f = Fields { b, little };
    Ok(if size == NIFTI1 {
        Header {
            version: 1,
            little,
            dim: std::array::from_fn(|k| f.i16(40 + 2 * k) as i64),
            datatype: f.i16(70),
            bitpix: f.i16(72),
            pixdim: std::array::from_fn(|k| f.f32(76 + 4 * k) as f64),
            vox_offset: f.f32(108) as f64,
            scl_slope: f.f32(112) as f64,
            scl_inter: f.f32(116) as f64,
            qform_code: f.i16(252) as i32,
            sform_code: f.i16(254) as i32,
            quatern: std::array::from_fn(|k| f.f32(256 + 4 * k) as f64),
            qoffset: std::array::from_fn(|k| f.f32(268 + 4 * k) as f64),
            srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f32(280 + 16 * r + 4 * c) as f64)),
        }
    } else {
        Header {
            version: 2,
            little,
            dim: std::array::from_fn(|k| f.i64(16 + 8 * k)),
            datatype: f.i16(12),
            bitpix: f.i16(14),
            pixdim: std::array::from_fn(|k| f.f64(104 + 8 * k)),
            vox_offset: f.i64(168) as f64,
            scl_slope: f.f64(176),
            scl_inter: f.f64(184),
            qform_code: f.i32(344),
            sform_code: f.i32(348),
            quatern: std::array::from_fn(|k| f.f64(352 + 8 * k)),
            qoffset: std::array::from_fn(|k| f.f64(376 + 8 * k)),
            srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f64(400 + 32 * r + 8 * c))),
        }
    })
}
