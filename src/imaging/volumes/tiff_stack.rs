//! Multi-page TIFF stacks (one page per slice, the first at the bottom), with the
//! spacing of their OME-XML or ImageJ description and the X resolution
//! ([`super::tiff_meta`]).

use super::isotropic;
use super::tiff_meta::StackMeta;
use crate::imaging::decode::{no_such_channel, pixel_value};
use crate::imaging::grid::Placement;
use crate::imaging::grid::{Grid, SampleKind};
use crate::imaging::limits::ImageLimits;
use crate::imaging::{ImageError, Plane};
use std::io::Cursor;

/// Whether `bytes` start like a TIFF file.
pub fn is_tiff(bytes: &[u8]) -> bool {
    bytes.starts_with(b"II*\0") || bytes.starts_with(b"MM\0*")
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
    decode_tiff_stack_plane(input, bytes, limits, Plane::default())
}

/// As [`decode_tiff_stack`], the pages of `plane`: of a stack of several
/// channels or time points (OME-XML, ImageJ hyperstack), those of the channel
/// and time point it names (a 2D image when they are one page); a channel of a
/// stack of one is that component of colour interleaved in each page instead
/// of its luminance.
pub fn decode_tiff_stack_plane(
    input: &str,
    bytes: &[u8],
    limits: &ImageLimits,
    plane: Plane,
) -> Result<Grid, ImageError> {
    let channel = plane.channel;
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
    let meta = StackMeta::parse(&description).map_err(&fail)?;
    if let Some((subject, refusal)) = meta.as_ref().and_then(|m| m.refusal(plane)) {
        return Err(ImageError::about(subject, input, refusal));
    }
    if let Some(t) = plane.time_point.filter(|&t| t > 0 && meta.is_none()) {
        return Err(ImageError::time_point(
            input,
            format!(
                "is a stack of slices of one time point (no OME or ImageJ description); time point {t} was asked for"
            ),
        ));
    }
    // a channel of several stored as pages, or else a component of each page
    let pages_of = meta.as_ref().filter(|m| m.channels > 1).zip(channel);
    if let Some((m, c)) = pages_of.filter(|(m, c)| *c >= m.channels) {
        return Err(ImageError::channel(input, no_such_channel(m.channels, c)));
    }
    let component = if pages_of.is_some() { None } else { channel };
    // the pages of that channel and time point (a time point of a stack of one
    // channel, too)
    let wanted = |page: usize| {
        meta.as_ref().is_none_or(|m| {
            let (c, t) = m.plane_of(page);
            (m.channels == 1 || Some(c) == channel) && (m.frames == 1 || Some(t) == plane.time_point)
        })
    };
    let planes_of = meta.as_ref().is_some_and(|m| pages_of.is_some() || m.frames > 1);
    let declared = meta.as_ref().map_or([None; 3], |m| m.spacing);
    // OME's physical sizes where it gives them, else the X resolution; z by
    // ImageJ's `spacing=` or OME's PhysicalSizeZ, else as x
    let (x_spacing, y_spacing) = (declared[0].unwrap_or(xy_spacing), declared[1].or(declared[0]).unwrap_or(xy_spacing));
    let z_spacing = declared[2].unwrap_or(x_spacing);
    let (mut values, mut dims) = (Vec::new(), [0usize; 2]);
    let mut kind = None;
    let (mut page, mut slices) = (0usize, 0usize);
    loop {
        if !wanted(page) {
            page += 1;
            if !d.more_images() {
                break;
            }
            d.next_image().map_err(|e| fail(format!("page {page}: {e}")))?;
            continue;
        }
        let (w, h) = d.dimensions().map_err(|e| fail(format!("page {page}: {e}")))?;
        let (w, h) = (w as usize, h as usize);
        if slices == 0 {
            dims = [w, h];
            limits.check(input, &[w, h])?;
        } else if [w, h] != dims {
            return Err(fail(format!("page {page} is {w}×{h}, but the first is {}×{}", dims[0], dims[1])));
        }
        if (slices + 1).saturating_mul(w * h) > limits.max_voxels {
            return Err(fail(format!("has more than {} voxels, the limit", limits.max_voxels)));
        }
        let channels = match d.colortype().map_err(|e| fail(format!("page {page}: {e}")))? {
            tiff::ColorType::Gray(_) => 1,
            tiff::ColorType::GrayA(_) => 2,
            tiff::ColorType::RGB(_) => 3,
            tiff::ColorType::RGBA(_) => 4,
            other => return Err(fail(format!("page {page}: unsupported colour type {other:?}"))),
        };
        if let Some(c) = component.filter(|&c| c >= channels) {
            return Err(ImageError::channel(input, format!("page {page} {}", no_such_channel(channels, c))));
        }
        // the tiff crate reads the first plane only of colour stored plane by plane
        let planar = matches!(d.get_tag_u32(tiff::tags::Tag::PlanarConfiguration), Ok(2));
        if planar && channels > 1 {
            return Err(fail(format!(
                "page {page}: colour stored plane by plane (TIFF PlanarConfiguration 2) is not \
                 supported; save the stack as grey or as interleaved (chunky) colour"
            )));
        }
        let (samples, k) = samples(d.read_image().map_err(|e| fail(format!("page {page}: {e}")))?)
            .ok_or_else(|| fail(format!("page {page}: unsupported sample type")))?;
        kind = Some(k);
        if samples.len() != w * h * channels {
            return Err(fail(format!("page {page}: {} samples for {w}×{h}×{channels}", samples.len())));
        }
        // rows flipped (j = 0 at the bottom, as 2D images); colour to luminance,
        // or the component asked for
        for j in (0..h).rev() {
            for i in 0..w {
                let s = &samples[(i + w * j) * channels..][..channels];
                values.push(pixel_value(s, component));
            }
        }
        page += 1;
        slices += 1;
        if !d.more_images() {
            break;
        }
        d.next_image().map_err(|e| fail(format!("page {page}: {e}")))?;
    }
    if let Some((planes, source)) = meta.as_ref().and_then(|m| Some((m.planes?, m.source))) {
        if planes != page {
            return Err(fail(format!(
                "holds {page} pages where its {source} metadata describes {planes} planes (a stack split over \
                 several files is not read)"
            )));
        }
    }
    let Some(kind) = kind else {
        let (c, t) = (channel.unwrap_or(0), plane.time_point.unwrap_or(0));
        return Err(fail(format!("holds no page of channel {c} at time point {t}")));
    };
    if slices == 1 && (planes_of || page == 1) {
        // one page of the channel and time point chosen, or a file of one page
        // (a float TIFF, which the 2D image reader does not take): a 2D image
        return Ok(Grid::new(2, [dims[0], dims[1], 1], values, kind));
    }
    limits.check(input, &[dims[0], dims[1], slices]).map_err(|e| match &meta {
        None if slices < limits.min_side => ImageError::new(
            input,
            format!(
                "{} (a TIFF of several pages is read as a volume, a slice per page; channels stored as pages \
                 need the OME or ImageJ description that says so)",
                e.message
            ),
        ),
        _ => e,
    })?;
    let grid = Grid::new(3, [dims[0], dims[1], slices], values, kind).rows_flipped();
    isotropic(input, grid.placed(Placement::aligned([x_spacing, y_spacing, z_spacing], [0.0; 3])), limits)
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
