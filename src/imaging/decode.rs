//! Decoding input files into grids: 2D rasters (PNG, JPEG, TIFF; 8 or 16 bit; gray,
//! gray+alpha, RGB, RGBA — colour reduced to luminance), 3D NRRD volumes and stacks
//! of 2D slices. Every error names the input.

use super::grid::{Grid, SampleKind};
use super::limits::ImageLimits;
use super::nrrd::parse_nrrd;
use super::ImageError;
use image::{DynamicImage, ImageReader};
use std::io::Cursor;

/// Rec. 709 luminance of linear `(r, g, b)`.
#[inline]
fn luminance(r: f64, g: f64, b: f64) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// Decode a 2D image (PNG, JPEG or TIFF) named `input`, colour reduced to its
/// luminance. Rows are flipped so that `j = 0` is the bottom row.
pub fn decode_image(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    decode_image_channel(input, bytes, limits, None)
}

/// The samples of one pixel as the image holds them (gray; gray, alpha; red,
/// green, blue; red, green, blue, alpha): component `channel`, or without one
/// the gray value or the colour's luminance.
#[inline]
pub(super) fn pixel_value(s: &[f64], channel: Option<usize>) -> f64 {
    match channel {
        Some(c) => s[c],
        None if s.len() >= 3 => luminance(s[0], s[1], s[2]),
        None => s[0],
    }
}

/// The message for channel `c` of a file of `channels` channels, which it lacks.
pub(super) fn no_such_channel(channels: usize, c: usize) -> String {
    let s = if channels == 1 { "" } else { "s" };
    format!("has {channels} channel{s} (0 to {}); channel {c} was asked for", channels - 1)
}

/// The width and height of a 2D image (PNG, JPEG or TIFF) from its header,
/// without decoding it.
pub fn image_dimensions(input: &str, bytes: &[u8]) -> Result<(usize, usize), ImageError> {
    if bytes.is_empty() {
        return Err(ImageError::new(input, "is empty"));
    }
    let r = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| ImageError::new(input, format!("cannot be read: {e}")))?;
    match r.format() {
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::Tiff) => {}
        Some(f) => return Err(ImageError::new(input, format!("is a {f:?} image; supported are PNG, JPEG and TIFF"))),
        None => return Err(ImageError::new(input, "is not a PNG, JPEG or TIFF image (unknown format)")),
    }
    let (w, h) = r.into_dimensions().map_err(|e| ImageError::new(input, format!("has a corrupt header: {e}")))?;
    Ok((w as usize, h as usize))
}

/// As [`decode_image`], with the image's component `channel` (0-based, in the
/// order gray, alpha or red, green, blue, alpha) instead of its luminance when
/// given.
pub fn decode_image_channel(
    input: &str,
    bytes: &[u8],
    limits: &ImageLimits,
    channel: Option<usize>,
) -> Result<Grid, ImageError> {
    let fail = |m: String| ImageError::new(input, m);
    let (w, h) = image_dimensions(input, bytes)?;
    limits.check(input, &[w, h])?;
    let reader =
        ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| fail(format!("cannot be read: {e}")))?;
    let img = reader.decode().map_err(|e| fail(format!("is corrupt: {e}")))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let components = img.color().channel_count() as usize;
    if let Some(c) = channel.filter(|&c| c >= components) {
        return Err(ImageError::channel(input, no_such_channel(components, c)));
    }
    macro_rules! pick {
        ($b:expr) => {
            $b.pixels().map(|p| pixel_value(&p.0.map(|v| v as f64), channel)).collect()
        };
    }
    let (values, kind): (Vec<f64>, SampleKind) = match img {
        DynamicImage::ImageLuma8(b) => (pick!(b), SampleKind::U8),
        DynamicImage::ImageLumaA8(b) => (pick!(b), SampleKind::U8),
        DynamicImage::ImageLuma16(b) => (pick!(b), SampleKind::U16),
        DynamicImage::ImageLumaA16(b) => (pick!(b), SampleKind::U16),
        DynamicImage::ImageRgb8(b) => (pick!(b), SampleKind::U8),
        DynamicImage::ImageRgba8(b) => (pick!(b), SampleKind::U8),
        DynamicImage::ImageRgb16(b) => (pick!(b), SampleKind::U16),
        DynamicImage::ImageRgba16(b) => (pick!(b), SampleKind::U16),
        DynamicImage::ImageRgba32F(b) => (pick!(b), SampleKind::F32),
        other => (pick!(other.to_rgb32f()), SampleKind::F32),
    };
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(fail(format!("pixel {} of row {} is not a finite number", i % w, i / w)));
    }
    // flip rows: file row r becomes grid row h - 1 - r
    let mut flipped = vec![0.0; w * h];
    for r in 0..h {
        flipped[(h - 1 - r) * w..(h - r) * w].copy_from_slice(&values[r * w..(r + 1) * w]);
    }
    Ok(Grid::new(2, [w, h, 1], flipped, kind))
}

/// Decode a 3D volume: an NRRD file (attached data; raw or gzip).
pub fn decode_volume(input: &str, bytes: &[u8], limits: &ImageLimits) -> Result<Grid, ImageError> {
    if !bytes.starts_with(b"NRRD") {
        return Err(ImageError::new(input, "is not an NRRD volume (no `NRRD000x` magic line)"));
    }
    parse_nrrd(input, bytes, limits)
}

/// A volume from a stack of 2D slices (`z` = slice index), all of one size.
pub fn decode_slices(
    slices: &[(&str, &[u8])],
    limits: &ImageLimits,
    channel: Option<usize>,
) -> Result<Grid, ImageError> {
    let Some(((first, _), _)) = slices.split_first() else {
        return Err(ImageError::new("(slices)", "a slice stack needs at least one slice"));
    };
    // the stack's size from the slices' headers, before any slice is decoded: a
    // small file may decode to many samples, and the stack to as many times that
    let (w, h) = image_dimensions(first, slices[0].1)?;
    for (name, bytes) in &slices[1..] {
        let (sw, sh) = image_dimensions(name, bytes)?;
        if (sw, sh) != (w, h) {
            return Err(ImageError::new(name, format!("is {sw}×{sh}, but slice `{first}` is {w}×{h}")));
        }
    }
    limits.check(first, &[w, h, slices.len()])?;
    let relaxed = ImageLimits { max_pixels: limits.max_voxels, ..*limits };
    let mut values = Vec::with_capacity(w * h * slices.len());
    let mut dims = [0, 0];
    let mut kind = SampleKind::U8;
    for (k, (name, bytes)) in slices.iter().enumerate() {
        let g = decode_image_channel(name, bytes, &relaxed, channel)?;
        if k == 0 {
            dims = [g.dims[0], g.dims[1]];
            kind = g.kind;
        }
        values.extend_from_slice(&g.values);
    }
    limits.check(first, &[dims[0], dims[1], slices.len()])?;
    Ok(Grid::new(3, [dims[0], dims[1], slices.len()], values, kind).rows_flipped())
}
