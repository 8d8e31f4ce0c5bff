//! NIfTI volumes (`.nii`, gzip-compressed `.nii.gz`; single file, NIfTI-1 `n+1`
//! or NIfTI-2 `n+2`), placed by their `sform` or `qform` (else spaced by `pixdim`).

mod header;

use super::isotropic;
use crate::imaging::grid::{Grid, Placement, SampleKind};
use crate::imaging::limits::ImageLimits;
use crate::imaging::ImageError;
use header::{NIFTI1, NIFTI2};
use nalgebra::{Quaternion, UnitQuaternion};
use std::borrow::Cow;
use std::io::Read;

/// Whether `bytes`, plain or gzip-compressed, begin with a NIfTI-1 or NIfTI-2
/// header (`sizeof_hdr` 348 or 540 in either byte order): [`decode_nifti`] reads
/// the single-file ones and says what is wrong with the others (a `.hdr` of a
/// `.hdr`/`.img` pair).
pub fn is_nifti(bytes: &[u8]) -> bool {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut head = Vec::with_capacity(4);
        let ok = flate2::read::GzDecoder::new(bytes).take(4).read_to_end(&mut head).is_ok();
        return ok && header::is_header(&head);
    }
    header::is_header(bytes)
}

/// A NIfTI-1 or NIfTI-2 volume (either byte order, gzip or not; 3D, or 4D with
/// one time point), scaled by `scl_slope`/`scl_inter`.
pub fn decode_nifti(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    decode_nifti_time_point(input, bytes, limits, None)
}

/// As [`decode_nifti`], the volume of time point `time_point` (0-based) of a
/// 4D series; a series of several needs one. Of a gzip-compressed file only
/// what comes before that volume's end is decompressed, and only that volume
/// kept.
pub fn decode_nifti_time_point(
    input: &str,
    bytes: &[u8],
    limits: &ImageLimits,
    time_point: Option<usize>,
) -> Result<Grid, ImageError> {
    let fail = |m: String| ImageError::new(input, m);
    let mut source = Source::new(bytes);
    let head = source.head().map_err(&fail)?;
    let h = header::parse(&head).map_err(&fail)?;
    let little = h.little;
    let ndim = h.dim[0];
    let dim = &h.dim[1..];
    if !(2..=4).contains(&ndim) {
        return Err(fail(format!(
            "has {ndim} dimensions (sizes {:?}); a 3D volume is needed",
            &dim[..ndim.clamp(0, 7) as usize]
        )));
    }
    if dim[..3].iter().any(|&n| n < 1) || (ndim == 4 && dim[3] < 1) {
        return Err(fail(format!("has sizes {:?}", &dim[..ndim as usize])));
    }
    let size_of = |n: i64| usize::try_from(n).unwrap_or(usize::MAX);
    let dims = [size_of(dim[0]), size_of(dim[1]), if ndim >= 3 { size_of(dim[2]) } else { 1 }];
    let frames = if ndim == 4 { size_of(dim[3]) } else { 1 };
    let t = match time_point {
        None if frames > 1 => {
            return Err(ImageError::time_point(
                input,
                format!(
                    "is a series of {frames} time points (sizes {:?}); choose the time point to segment with \
                     `problem.time_point` (0 to {})",
                    &dim[..4],
                    frames - 1
                ),
            ))
        }
        Some(t) if t >= frames => {
            return Err(ImageError::time_point(
                input,
                format!(
                    "is a series of {frames} time point{}; time point {t} was asked for",
                    if frames == 1 { "" } else { "s" }
                ),
            ))
        }
        t => t.unwrap_or(0),
    };
    limits.check(input, &dims)?;
    let (datatype, bitpix) = (h.datatype, h.bitpix);
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
    let least = if h.version == 1 { NIFTI1 } else { NIFTI2 } as f64;
    let offset = h.vox_offset;
    if !(offset.is_finite() && offset >= least) {
        return Err(fail(format!("has vox_offset {offset}")));
    }
    let n = dims[0] * dims[1] * dims[2];
    // a vox_offset far beyond the file (up to f32::MAX or i64::MAX) must not
    // overflow the end
    let start = (offset.min(usize::MAX as f64) as usize).saturating_add(t.saturating_mul(n * size));
    let data = source.range(start, n * size).map_err(&fail)?;
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
    let (slope, inter) = (h.scl_slope, h.scl_inter);
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
    let [b, c, d] = h.quatern;
    let qform = [h.qform_code as f64, b, c, d];
    let sform = (h.sform_code > 0).then_some(h.srow);
    let placement = placement(h.pixdim, qform, h.qoffset, sform);
    isotropic(input, Grid::new(3, dims, values, kind).placed(placement), limits)
}

/// The most bytes of a gzip-compressed file decompressed to reach a time
/// point's volume (4 GiB: a series of 1,200 volumes of 128×128×64 int16).
const MAX_SKIP: u64 = 1 << 32;

/// A NIfTI file's bytes, plain or gzip-compressed: its header, then the bytes
/// of one range, decompressing no further than that range's end.
enum Source<'a> {
    Plain(&'a [u8]),
    Gzip { reader: Box<flate2::read::GzDecoder<&'a [u8]>>, read: Vec<u8> },
}

impl<'a> Source<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        if bytes.starts_with(&[0x1f, 0x8b]) {
            Source::Gzip { reader: Box::new(flate2::read::GzDecoder::new(bytes)), read: Vec::new() }
        } else {
            Source::Plain(bytes)
        }
    }

    /// The first bytes, enough for either header (fewer if the file is shorter).
    fn head(&mut self) -> Result<Vec<u8>, String> {
        match self {
            Source::Plain(b) => Ok(b[..b.len().min(NIFTI2 + 4)].to_vec()),
            Source::Gzip { reader, read } => {
                Read::take(&mut **reader, (NIFTI2 + 4) as u64).read_to_end(read).map_err(corrupt)?;
                Ok(read.clone())
            }
        }
    }

    /// The `len` bytes from byte `start` (called once, after [`Source::head`]);
    /// of a plain file, borrowed.
    fn range(&mut self, start: usize, len: usize) -> Result<Cow<'a, [u8]>, String> {
        let truncated =
            |total: String| format!("is truncated: {} bytes wanted from byte {start}, {total} bytes in all", len);
        match self {
            Source::Plain(b) => {
                let b: &'a [u8] = b;
                let end = start.checked_add(len).filter(|&e| e <= b.len());
                end.map(|e| Cow::Borrowed(&b[start..e])).ok_or_else(|| truncated(b.len().to_string()))
            }
            Source::Gzip { reader, read } => {
                // skip what lies between the header and `start`, then keep `len` bytes
                let have = read.len();
                let mut out = read.get(start.min(have)..).unwrap_or_default().to_vec();
                out.truncate(len);
                let skip = start.saturating_sub(have) as u64;
                if skip > MAX_SKIP {
                    return Err(format!(
                        "has its volume {start} bytes into the decompressed file, beyond the {MAX_SKIP} bytes read"
                    ));
                }
                let skipped =
                    std::io::copy(&mut Read::take(&mut **reader, skip), &mut std::io::sink()).map_err(corrupt)?;
                let want = (len - out.len()) as u64;
                let got = Read::take(&mut **reader, want).read_to_end(&mut out).map_err(corrupt)? as u64;
                if skipped < skip || got < want {
                    let total = have as u64 + skipped + got;
                    return Err(truncated(format!("{total} decompressed")));
                }
                Ok(Cow::Owned(out))
            }
        }
    }
}

fn corrupt(e: std::io::Error) -> String {
    format!("is a corrupt gzip stream: {e}")
}

/// Where a NIfTI file's voxels lie: by its `sform` (`srow_*`) when
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

    /// The same volume written by nibabel as NIfTI-1, gzip NIfTI-2 and big-endian
    /// float32 NIfTI-2 (`scripts/make_volume_samples.py`): the same grid and
    /// placement from all three.
    #[test]
    fn nifti1_and_nifti2_files_of_nibabel_read_alike() {
        let limits = ImageLimits::default();
        let read = |bytes: &[u8]| {
            assert!(is_nifti(bytes));
            decode_nifti("v", bytes, &limits).unwrap()
        };
        let one = read(include_bytes!("../../../../tests/data/ramp_nifti1.nii"));
        // voxel steps 2, 3, 4 (along RAS y, −x and z by the sform): resampled to
        // cubic voxels of 2, the linear ramp i + 10 j + 100 k kept
        assert_eq!(one.dims, [7, 8, 8]);
        // new sample n at old index (n + ½)·2/step − ½, clamped to the old grid
        let old = |n: usize, step: f64, last: f64| ((n as f64 + 0.5) * 2.0 / step - 0.5).clamp(0.0, last);
        for (i, j, k) in [(0, 0, 0), (6, 7, 7), (3, 2, 1), (5, 4, 6)] {
            let want = i as f64 + 10.0 * old(j, 3.0, 4.0) + 100.0 * old(k, 4.0, 3.0);
            assert!((one.values[one.index(i, j, k)] - want).abs() < 1e-9, "{i} {j} {k}");
        }
        assert_eq!(one.placement.space.as_deref(), Some("left-posterior-superior"));
        for two in [
            read(include_bytes!("../../../../tests/data/ramp_nifti2.nii.gz")),
            read(include_bytes!("../../../../tests/data/ramp_nifti2_be.nii")),
        ] {
            assert_eq!((two.dims, &two.values), (one.dims, &one.values));
            assert_eq!(two.placement, one.placement);
        }
    }

    /// NIfTI-2 headers that are cut short, of another layout or pointing past the
    /// file: errors naming the input.
    #[test]
    fn broken_nifti2_headers_are_refused() {
        let limits = ImageLimits::default();
        let b = include_bytes!("../../../../tests/data/ramp_nifti2_be.nii");
        let error = |bytes: &[u8]| decode_nifti("vol", bytes, &limits).unwrap_err().to_string();
        let e = error(&b[..500]);
        assert!(e.contains("`vol`") && e.contains("shorter than a NIfTI-2 header (540)"), "{e}");
        let e = error(&b[..900]);
        assert!(e.contains("truncated"), "{e}");
        let mut pair = b.to_vec();
        pair[4..8].copy_from_slice(b"ni2\0");
        assert!(is_nifti(&pair));
        assert!(error(&pair).contains(".hdr/.img pairs are not read"));
        let mut far = b.to_vec();
        far[168..176].copy_from_slice(&i64::MAX.to_be_bytes());
        assert!(error(&far).contains("truncated"));
        let mut negative = b.to_vec();
        negative[168..176].copy_from_slice(&(-8i64).to_be_bytes());
        assert!(error(&negative).contains("vox_offset -8"));
        let mut huge = b.to_vec();
        huge[24..32].copy_from_slice(&(1i64 << 40).to_be_bytes());
        assert!(error(&huge).contains("limit"), "{}", error(&huge));
        assert!(error(&[0u8; 600]).contains("is not NIfTI"));
    }

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
