//! Volume results as NIfTI-1 (`.nii.gz`): a mask or a label volume on a grid's
//! samples, placed by its [`Placement`] in the RAS coordinates NIfTI uses, as
//! both the `sform` and the `qform`, so that FSL, ITK-SNAP, 3D Slicer and
//! SimpleITK put it over the input.

use crate::imaging::grid::{Grid, Placement};
use flate2::write::GzEncoder;
use nalgebra::{Rotation3, UnitQuaternion};
use std::io::Write;

/// A 0/1 uint8 mask on the samples of `grid` as a gzip NIfTI-1 file.
pub fn encode_nifti_mask(grid: &Grid, mask: &[bool]) -> Vec<u8> {
    let raw: Vec<u8> = mask.iter().map(|&m| m as u8).collect();
    encode_gzip_nifti(grid, "shapeflow segmentation mask", 2, &raw)
}

/// A label volume on the samples of `grid` as uint16, gzip NIfTI-1.
pub fn encode_nifti_labels(grid: &Grid, labels: &[u16]) -> Vec<u8> {
    let raw: Vec<u8> = labels.iter().flat_map(|l| l.to_le_bytes()).collect();
    encode_gzip_nifti(grid, "shapeflow segmentation labels", 512, &raw)
}

/// The quaternion `(b, c, d)` (with `a ≥ 0`) and `qfac` of the rotation nearest
/// to the directions of `axes` (a left-handed set flips its third column, `qfac =
/// −1`), as NIfTI's qform holds them.
fn quaternion(axes: &[[f64; 3]; 3]) -> ([f64; 3], f64) {
    let mut r = Placement { axes: *axes, origin: [0.0; 3], space: None }.matrix();
    for mut column in r.column_iter_mut() {
        column.normalize_mut();
    }
    let qfac = if r.determinant() < 0.0 { -1.0 } else { 1.0 };
    r.column_mut(2).scale_mut(qfac);
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    ([sign * q.i, sign * q.j, sign * q.k], qfac)
}

/// The 348-byte header (and the empty extension) of `grid`'s samples as
/// `datatype` (2 uint8, 512 uint16), then `raw`, gzip-compressed.
fn encode_gzip_nifti(grid: &Grid, description: &str, datatype: i16, raw: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let mut put = |o: usize, bytes: &[u8]| h[o..o + bytes.len()].copy_from_slice(bytes);
    put(0, &348i32.to_le_bytes());
    put(40, &3i16.to_le_bytes());
    for (a, &n) in grid.dims.iter().enumerate() {
        put(42 + 2 * a, &(n as i16).to_le_bytes());
    }
    for k in 3..7 {
        put(42 + 2 * k, &1i16.to_le_bytes());
    }
    put(70, &datatype.to_le_bytes());
    put(72, &(if datatype == 2 { 8i16 } else { 16 }).to_le_bytes());
    let p = &grid.placement;
    let spacing = p.spacing();
    let mut pixdim = [1.0f32, spacing[0] as f32, spacing[1] as f32, spacing[2] as f32, 0.0, 0.0, 0.0, 0.0];
    put(108, &352f32.to_le_bytes());
    put(112, &1f32.to_le_bytes());
    let text = description.as_bytes();
    put(148, &text[..text.len().min(79)]);
    if let Some((axes, origin)) = p.to_ras() {
        let ([b, c, d], qfac) = quaternion(&axes);
        pixdim[0] = qfac as f32;
        put(252, &1i16.to_le_bytes());
        put(254, &1i16.to_le_bytes());
        for (k, v) in [b, c, d, origin[0], origin[1], origin[2]].iter().enumerate() {
            put(256 + 4 * k, &(*v as f32).to_le_bytes());
        }
        for row in 0..3 {
            for col in 0..3 {
                put(280 + 16 * row + 4 * col, &(axes[col][row] as f32).to_le_bytes());
            }
            put(280 + 16 * row + 12, &(origin[row] as f32).to_le_bytes());
        }
    }
    for (k, v) in pixdim.iter().enumerate() {
        put(76 + 4 * k, &v.to_le_bytes());
    }
    put(344, b"n+1\0");
    let mut gz = GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&h).expect("writing to memory");
    gz.write_all(raw).expect("writing to memory");
    gz.finish().expect("writing to memory")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::grid::SampleKind;
    use crate::imaging::limits::ImageLimits;
    use crate::imaging::volumes::decode_nifti;

    /// A result written on a rotated, left-handed placement reads back with the
    /// same samples and the same placement: through the `sform` and, with the
    /// `sform` cleared, through the `qform`.
    #[test]
    fn results_read_back_with_their_placement() {
        let dims = [4, 5, 6];
        let n = dims.iter().product::<usize>();
        let (c, s) = (0.6, 0.8);
        let placement = Placement {
            // a turn about z, the third axis flipped (left-handed), 0.5 apart
            axes: [[0.5 * c, 0.5 * s, 0.0], [-0.5 * s, 0.5 * c, 0.0], [0.0, 0.0, -0.5]],
            origin: [3.0, -4.0, 5.5],
            space: Some("left-posterior-superior".into()),
        };
        let grid = Grid::new(3, dims, vec![0.0; n], SampleKind::U8).placed(placement.clone());
        let labels: Vec<u16> = (0..n).map(|i| (i % 300) as u16).collect();
        let limits = ImageLimits { min_side: 1, ..Default::default() };
        let near = |a: &Placement| {
            let pairs = a
                .axes
                .as_flattened()
                .iter()
                .chain(&a.origin)
                .zip(placement.axes.as_flattened().iter().chain(&placement.origin));
            pairs.into_iter().all(|(x, y)| (x - y).abs() < 1e-6) && a.space == placement.space
        };
        let bytes = encode_nifti_labels(&grid, &labels);
        let back = decode_nifti("labels", &bytes, &limits).unwrap();
        assert_eq!(back.dims, dims);
        assert!(back.values.iter().zip(&labels).all(|(v, &l)| *v == l as f64));
        assert!(near(&back.placement), "{:?}", back.placement);
        // the qform alone
        let mut raw = Vec::new();
        std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(&bytes[..]), &mut raw).unwrap();
        raw[254..256].copy_from_slice(&0i16.to_le_bytes());
        let back = decode_nifti("labels", &raw, &limits).unwrap();
        assert!(near(&back.placement), "{:?}", back.placement);
        let mask = decode_nifti("mask", &encode_nifti_mask(&grid, &vec![true; n]), &limits).unwrap();
        assert!(mask.values.iter().all(|&v| v == 1.0) && near(&mask.placement));
        // an unnamed space: spacing only
        let plain = Grid::new(3, dims, vec![0.0; n], SampleKind::U8).placed(Placement::aligned([2.0; 3], [1.0; 3]));
        let back = decode_nifti("mask", &encode_nifti_mask(&plain, &vec![false; n]), &limits).unwrap();
        assert_eq!(back.placement, Placement::aligned([2.0; 3], [0.0; 3]));
    }
}
