//! Volumes in the formats microscopy and medical imaging use: multi-page TIFF
//! stacks (one page per slice, the first at the bottom; OME-TIFF and ImageJ
//! descriptions read for their spacing and for the pages of one channel and
//! time point, `tiff_meta`) and NIfTI-1 or NIfTI-2 (one time point of a series)
//! (`.nii`, gzip-compressed `.nii.gz`; single file, `n+1` or `n+2`). Voxel spacing is honoured: an
//! anisotropic volume (OME-XML's physical sizes, or ImageJ's `spacing=` and the X
//! resolution, of a TIFF stack;
//! the sform, qform or `pixdim` of NIfTI) is resampled by trilinear interpolation
//! to cubic voxels of its smallest spacing, so that lengths, areas and volumes in
//! the unit box are physical, and placed where its samples lie. Results are
//! written back as NIfTI-1 with that placement (`nifti_out`). The same limits and
//! errors as the other readers: every error names the input.

mod nifti;
mod nifti_out;
mod tiff_meta;
mod tiff_stack;

pub use nifti::{decode_nifti, decode_nifti_time_point, is_nifti};
pub use nifti_out::{encode_nifti_labels, encode_nifti_mask};
pub use tiff_stack::{decode_tiff_stack, decode_tiff_stack_plane, is_tiff, tiff_pages};

use super::grid::{ArrayLayout, Grid};
use super::limits::ImageLimits;
use super::ImageError;

/// `grid` resampled (trilinear) to cubic voxels of its smallest spacing (its
/// placement's) when its spacings differ by more than 1 %, placed where the new
/// samples lie: the axes shortened to that spacing, the first sample half a new
/// voxel in from the old volume's edge; its layout maps the old samples onto the
/// new ones. Unchanged otherwise.
pub fn isotropic(input: &str, grid: Grid, limits: &ImageLimits) -> Result<Grid, ImageError> {
    let spacing = grid.placement.spacing();
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
    // sample i lies at the old index (i + ½) h/s − ½ along each axis
    let old = &grid.placement;
    let mut placed = old.clone();
    for a in 0..3 {
        let shift = 0.5 * h / spacing[a] - 0.5;
        for c in 0..3 {
            placed.axes[a][c] *= h / spacing[a];
            placed.origin[c] += shift * old.axes[a][c];
        }
    }
    let mut resampled = Grid::new(3, dims, values, grid.kind).placed(placed);
    // old sample m has its centre at new coordinate (m + ½) s/h − ½
    resampled.layout =
        ArrayLayout { per_input: std::array::from_fn(|a| grid.layout.per_input[a] * spacing[a] / h), ..grid.layout };
    Ok(resampled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::{Plane, Subject};
    use std::io::{Cursor, Read, Write};

    fn channel(c: usize) -> Plane {
        Plane { channel: Some(c), time_point: None }
    }

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
        // a vox_offset of f32::MAX (found by fuzzing: the data's end overflowed)
        let mut far = b.clone();
        far[108..112].copy_from_slice(&f32::MAX.to_le_bytes());
        assert!(decode_nifti("vol", &far, &limits).unwrap_err().to_string().contains("truncated"));
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
        // colour stored plane by plane (tests/data/planar_rgb_stack.tif: 2 pages of
        // 5×6 RGB, written by tifffile with `planarconfig="separate"`): a clear error
        let planar = include_bytes!("../../../tests/data/planar_rgb_stack.tif");
        let e = decode_tiff_stack("stack", planar, &limits).unwrap_err().to_string();
        assert!(e.contains("`stack`") && e.contains("plane by plane"), "{e}");
    }

    /// Stacks written by tifffile (`scripts/make_volume_samples.py`): an OME-TIFF's
    /// physical sizes (x, y 0.5 µm; z 1500 nm) give 3 slices per page; stacks of
    /// two channels, by OME-XML or as an ImageJ hyperstack, are refused with their
    /// layout named, not read as eight slices; with a channel chosen, its four.
    #[test]
    fn ome_and_imagej_stacks() {
        let limits = ImageLimits::default();
        let ome = include_bytes!("../../../tests/data/ome_stack.ome.tif");
        assert_eq!(tiff_pages(ome, 10), 4);
        let g = decode_tiff_stack("stack", ome, &limits).unwrap();
        assert_eq!(g.dims, [6, 5, 12]);
        assert_eq!(g.placement.spacing(), [0.5, 0.5, 0.5]);
        // value 10 z + x of page z (rows flipped: any row), the ramp kept in z
        assert_eq!(g.values[g.index(4, 0, 1)], 4.0);
        assert_eq!(g.values[g.index(2, 3, 10)], 10.0 * ((10.5 / 3.0) - 0.5) + 2.0);
        for (file, source) in [
            (&include_bytes!("../../../tests/data/ome_channels.ome.tif")[..], "OME"),
            (&include_bytes!("../../../tests/data/imagej_channels.tif")[..], "ImageJ"),
        ] {
            let e = decode_tiff_stack("two", file, &limits).unwrap_err();
            assert_eq!(e.subject, Subject::Channel, "{e}");
            let e = e.to_string();
            assert!(e.contains("`two`") && e.contains("2 channels") && e.contains(source), "{e}");
            let second = decode_tiff_stack_plane("two", file, &limits, channel(1)).unwrap();
            assert_eq!(second.dims, [6, 5, 4]);
            assert_eq!(second.values[second.index(4, 2, 3)], 255.0 - 34.0);
        }
        // a 2D image of three channels stored as pages: one page each, a 2D grid
        let flat = imagej_pages("ImageJ=1.54f\nimages=3\nchannels=3\nmode=composite\n", &[1, 41, 81]);
        let g = decode_tiff_stack_plane("rgb", &flat, &limits, channel(2)).unwrap();
        assert_eq!((g.dimension, g.dims), (2, [6, 5, 1]));
        assert!(g.values.iter().all(|&v| v == 81.0));
        // a 2D time series (one page per time point): the time point's page
        let frames = imagej_pages("ImageJ=1.54f\nimages=4\nframes=4\n", &[1, 11, 21, 31]);
        let e = decode_tiff_stack("movie", &frames, &limits).unwrap_err();
        assert!(e.subject == Subject::TimePoint && e.message.contains("`problem.time_point` (0 to 3)"), "{e}");
        let g = decode_tiff_stack_plane("movie", &frames, &limits, Plane { channel: None, time_point: Some(3) });
        let g = g.unwrap();
        assert_eq!((g.dimension, g.dims), (2, [6, 5, 1]));
        assert!(g.values.iter().all(|&v| v == 31.0));
        // three pages without a description: a volume too thin, and why it is one
        use tiff::encoder::{colortype::Gray8, TiffEncoder};
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        for c in 0..3u8 {
            enc.write_image::<Gray8>(6, 5, &[c; 30]).unwrap();
        }
        let e = decode_tiff_stack("p", &out.into_inner(), &limits).unwrap_err().to_string();
        assert!(e.contains("at least 4") && e.contains("a slice per page"), "{e}");
    }

    /// Time series written by tifffile (OME-XML with `DimensionOrder` XYCZT, and
    /// an ImageJ hyperstack) and nibabel (a 4D NIfTI-1, gzip): refused without a
    /// time point (and a channel) chosen, naming what to choose; with them, the
    /// volume of that channel and time point. `scripts/make_volume_samples.py`.
    #[test]
    fn time_points_of_series() {
        let limits = ImageLimits::default();
        let at = |c, t| Plane { channel: Some(c), time_point: Some(t) };
        for (file, source) in [
            (&include_bytes!("../../../tests/data/ome_series.ome.tif")[..], "OME"),
            (&include_bytes!("../../../tests/data/imagej_series.tif")[..], "ImageJ"),
        ] {
            let e = decode_tiff_stack("s", file, &limits).unwrap_err();
            assert_eq!(e.subject, Subject::Channel, "{e}");
            assert!(e.message.contains(&format!("2 channels at 3 time points ({source}")), "{e}");
            let e = decode_tiff_stack_plane("s", file, &limits, channel(0)).unwrap_err();
            assert!(e.subject == Subject::TimePoint && e.message.contains("(0 to 2)"), "{e}");
            let e = decode_tiff_stack_plane("s", file, &limits, at(0, 3)).unwrap_err();
            assert!(e.subject == Subject::TimePoint && e.message.contains("time point 3 was asked for"), "{e}");
            for (c, t) in [(0, 0), (0, 2), (1, 1)] {
                let g = decode_tiff_stack_plane("s", file, &limits, at(c, t)).unwrap();
                assert_eq!(g.dims, [6, 5, 4], "{source}");
                for (x, z) in [(0, 0), (5, 3), (2, 1)] {
                    let v = (10 * z + x + 60 * t) as f64;
                    let want = if c == 0 { v } else { 255.0 - v };
                    assert_eq!(g.values[g.index(x, 2, z)], want, "{source} channel {c} time point {t}");
                }
            }
        }
        let series = include_bytes!("../../../tests/data/series_nifti1.nii.gz");
        let e = decode_nifti("n", series, &limits).unwrap_err();
        assert_eq!(e.subject, Subject::TimePoint);
        assert!(e.message.contains("series of 3 time points") && e.message.contains("(0 to 2)"), "{e}");
        let e = decode_nifti_time_point("n", series, &limits, Some(3)).unwrap_err();
        assert!(e.subject == Subject::TimePoint && e.message.contains("time point 3 was asked for"), "{e}");
        let one = decode_nifti("r", include_bytes!("../../../tests/data/ramp_nifti1.nii"), &limits).unwrap();
        for t in 0..3 {
            let g = decode_nifti_time_point("n", series, &limits, Some(t)).unwrap();
            assert_eq!((g.dims, &g.placement), (one.dims, &one.placement));
            let shifted: Vec<f64> = one.values.iter().map(|v| v + 1000.0 * t as f64).collect();
            assert_eq!(g.values, shifted, "time point {t}");
        }
        // the same series uncompressed, and cut short inside its last volume
        let mut plain = Vec::new();
        flate2::read::GzDecoder::new(&series[..]).read_to_end(&mut plain).unwrap();
        let g = decode_nifti_time_point("n", &plain, &limits, Some(2)).unwrap();
        assert_eq!(g.values[0], 2000.0);
        let e = decode_nifti_time_point("n", &plain[..plain.len() - 1], &limits, Some(2)).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        assert!(decode_nifti_time_point("n", &plain[..plain.len() - 1], &limits, Some(1)).is_ok());
        let cut = gzip(&plain[..plain.len() - 1]);
        let e = decode_nifti_time_point("n", &cut, &limits, Some(2)).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        assert_eq!(decode_nifti_time_point("n", &cut, &limits, Some(1)).unwrap().values[0], 1000.0);
    }

    /// A TIFF of 6×5 gray pages, page `k` filled with `values[k]`, each with the
    /// image description `description`.
    fn imagej_pages(description: &str, values: &[u8]) -> Vec<u8> {
        use tiff::encoder::{colortype::Gray8, TiffEncoder};
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        for &v in values {
            let mut image = enc.new_image::<Gray8>(6, 5).unwrap();
            image.encoder().write_tag(tiff::tags::Tag::ImageDescription, description).unwrap();
            image.write_data(&[v; 30]).unwrap();
        }
        out.into_inner()
    }

    fn gzip(b: &[u8]) -> Vec<u8> {
        let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(b).unwrap();
        z.finish().unwrap()
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

    /// The array of a resampled TIFF stack is the file's: page p, row r, column c
    /// of `tiff_stack` hold 10 p + c (rows alike), and a grid of each sample's row
    /// from the top as the file counts it maps back to that row.
    #[test]
    fn arrays_are_the_files_pages_rows_and_columns() {
        let g = decode_tiff_stack("stack", &tiff_stack(4, 3.0, 1), &ImageLimits::default()).unwrap();
        assert_eq!((g.dims, g.array_shape()), ([6, 5, 12], vec![4, 5, 6]));
        assert_eq!(g.layout.per_input, [1.0, 1.0, 3.0]);
        let array = g.to_array(&g.values);
        for (n, v) in array.iter().enumerate() {
            let (p, c) = (n / 30, n % 6);
            assert!((v - (10 * p + c) as f64).abs() < 1e-9, "sample {n}: {v}");
        }
        let rows: Vec<usize> = (0..g.len()).map(|n| 4 - (n / 6) % 5).collect();
        let back = g.to_array(&rows);
        assert!(back.iter().enumerate().all(|(n, &r)| r == (n / 6) % 5));
        assert_eq!(g.input_spacing(), [1.0, 1.0, 3.0]);
    }
}
