//! What a TIFF stack's first image description says of its layout and voxel
//! spacing: ImageJ's `key=value` lines (`channels=`, `slices=`, `frames=`,
//! `spacing=`) or OME-XML's `Pixels` element (`SizeC`, `SizeZ`, `SizeT`,
//! `PhysicalSize{X,Y,Z}` with their units, the `SamplesPerPixel` of its first
//! `Channel`). A volume is one channel at one time point: of a stack of several
//! channels or time points the one asked for is read (`problem.channel`,
//! `problem.time_point`); a stack of several without a choice is refused with
//! its layout named, never read as slices.

use crate::imaging::{Plane, Subject};
use quick_xml::events::Event;
use quick_xml::XmlVersion;

/// The layout and spacing a description declares.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct StackMeta {
    /// Channels stored as separate pages (colour interleaved within a page is one).
    pub channels: usize,
    /// Time points.
    pub frames: usize,
    /// Consecutive pages of one channel, and of one time point: the pages of the
    /// dimensions stored faster (ImageJ: channels fastest, then slices, then
    /// time points; OME: by its `DimensionOrder`).
    pub channel_stride: usize,
    pub frame_stride: usize,
    /// The pages the metadata accounts for, when it says.
    pub planes: Option<usize>,
    /// Voxel steps along x, y and z, each when given (OME: in micrometres).
    pub spacing: [Option<f64>; 3],
    /// `"ImageJ"` or `"OME"`, for messages.
    pub source: &'static str,
}

impl StackMeta {
    /// What the description `text` declares; `Ok(None)` for a description of
    /// neither kind, an error for OME-XML that cannot be read.
    pub(super) fn parse(text: &str) -> Result<Option<StackMeta>, String> {
        if text.starts_with("ImageJ=") {
            return Ok(Some(imagej(text)));
        }
        if text.trim_start().starts_with('<') && text.contains("OME") {
            return ome(text).map(Some);
        }
        Ok(None)
    }

    /// What keeps this stack from being read as the volume of `plane`, if
    /// anything: several channels or time points and none chosen (an error of
    /// the channel when it lacks one, else of the time point), or one asked for
    /// that it does not have.
    pub(super) fn refusal(&self, plane: Plane) -> Option<(Subject, String)> {
        let count = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        let layout = format!(
            "is a stack of {} at {} ({} metadata)",
            count(self.channels, "channel"),
            count(self.frames, "time point"),
            self.source
        );
        let needs_channel = self.channels > 1 && plane.channel.is_none();
        let needs_time = self.frames > 1 && plane.time_point.is_none();
        let choose =
            |what: &str, field: &str, n: usize| format!("the {what} to segment with `{field}` (0 to {})", n - 1);
        let (channel, time) = (
            choose("channel", "problem.channel", self.channels),
            choose("time point", "problem.time_point", self.frames),
        );
        match (needs_channel, needs_time) {
            (true, true) => return Some((Subject::Channel, format!("{layout}; choose {channel} and {time}"))),
            (true, false) => return Some((Subject::Channel, format!("{layout}; choose {channel}"))),
            (false, true) => return Some((Subject::TimePoint, format!("{layout}; choose {time}"))),
            (false, false) => {}
        }
        match plane.time_point {
            Some(t) if t >= self.frames => {
                Some((Subject::TimePoint, format!("{layout}; time point {t} was asked for (0 to {})", self.frames - 1)))
            }
            _ => None,
        }
    }

    /// The channel and the time point that page `page` belongs to.
    pub(super) fn plane_of(&self, page: usize) -> (usize, usize) {
        let along = |stride: usize, n: usize| (page / stride.max(1)) % n.max(1);
        (along(self.channel_stride, self.channels), along(self.frame_stride, self.frames))
    }
}

/// A positive finite number.
fn positive(v: &str) -> Option<f64> {
    v.trim().parse().ok().filter(|v: &f64| v.is_finite() && *v > 0.0)
}

/// ImageJ's description: `images=`, `channels=`, `slices=`, `frames=`,
/// `spacing=` (the z step in the unit of the x resolution). Pages go through
/// the channels fastest, then the slices, then the time points; without
/// `slices=`, the slices are the images left for each channel and time point.
fn imagej(text: &str) -> StackMeta {
    let value = |key: &str| text.lines().find_map(|l| l.strip_prefix(key)?.strip_prefix('=')).and_then(positive);
    let count = |key: &str| value(key).map_or(1, |v| v as usize);
    let (channels, frames) = (count("channels"), count("frames"));
    let slices = value("slices")
        .map(|v| v as usize)
        .unwrap_or_else(|| value("images").map_or(1, |v| (v as usize / channels.saturating_mul(frames).max(1)).max(1)));
    StackMeta {
        channels,
        frames,
        channel_stride: 1,
        frame_stride: channels.saturating_mul(slices),
        planes: value("images").map(|v| v as usize),
        spacing: [None, None, value("spacing")],
        source: "ImageJ",
    }
}

/// Micrometres per unit of an OME length unit symbol.
fn micrometres(unit: &str) -> Option<f64> {
    Some(match unit {
        "m" => 1e6,
        "cm" => 1e4,
        "mm" => 1e3,
        "µm" | "um" | "μm" => 1.0,
        "nm" => 1e-3,
        "pm" => 1e-6,
        "Å" => 1e-4,
        _ => return None,
    })
}

/// The first image's `Pixels` element of OME-XML.
fn ome(text: &str) -> Result<StackMeta, String> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut pixels: Option<Vec<(String, String)>> = None;
    let mut samples_per_pixel = 1usize;
    loop {
        match reader.read_event() {
            Ok(Event::Start(e) | Event::Empty(e)) => {
                let name = e.local_name();
                let attributes = || -> Result<Vec<(String, String)>, String> {
                    e.attributes()
                        .map(|a| {
                            let a = a.map_err(|e| e.to_string())?;
                            let key = String::from_utf8_lossy(a.key.local_name().as_ref()).into_owned();
                            let value =
                                a.normalized_value(XmlVersion::Implicit1_0).map_err(|e| e.to_string())?.into_owned();
                            Ok((key, value))
                        })
                        .collect()
                };
                match name.as_ref() {
                    b"Pixels" if pixels.is_none() => pixels = Some(attributes()?),
                    b"Channel" if pixels.is_some() => {
                        let spp = attributes()?.into_iter().find(|(k, _)| k == "SamplesPerPixel");
                        samples_per_pixel = spp.and_then(|(_, v)| positive(&v)).map_or(1, |v| v as usize);
                        break;
                    }
                    _ => {}
                }
            }
            Ok(Event::End(e)) if e.local_name().as_ref() == b"Pixels" => break,
            Ok(Event::Eof) => break,
            Err(e) => return Err(format!("has OME-XML that cannot be read: {e}")),
            _ => {}
        }
    }
    let Some(pixels) = pixels else { return Err("has OME-XML without a Pixels element".into()) };
    let get = |key: &str| pixels.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str());
    let size = |key: &str| get(key).and_then(positive).map_or(1, |v| v as usize);
    let length = |axis: &str| -> Result<Option<f64>, String> {
        let Some(v) = get(&format!("PhysicalSize{axis}")) else { return Ok(None) };
        let unit = get(&format!("PhysicalSize{axis}Unit")).unwrap_or("µm");
        let scale = micrometres(unit).ok_or_else(|| format!("has OME PhysicalSize{axis}Unit {unit:?}"))?;
        Ok(positive(v).map(|v| v * scale))
    };
    let channels = size("SizeC").div_ceil(samples_per_pixel.max(1));
    let (slices, frames) = (size("SizeZ"), size("SizeT"));
    // the pages of the dimensions stored faster than C and than T, from `XY` +
    // the order of Z, C and T (sizes as written, however large: saturated,
    // never overflowed)
    let order = get("DimensionOrder").unwrap_or("XYCZT");
    let stride = |of: char| {
        let faster = order.get(2..).and_then(|o| o.split_once(of)).map_or("", |(before, _)| before);
        faster.chars().fold(1usize, |p, d| {
            p.saturating_mul(match d {
                'Z' => slices,
                'C' => channels,
                _ => frames,
            })
        })
    };
    Ok(StackMeta {
        channels,
        frames,
        channel_stride: stride('C'),
        frame_stride: stride('T'),
        planes: Some(slices.saturating_mul(channels).saturating_mul(frames)),
        spacing: [length("X")?, length("Y")?, length("Z")?],
        source: "OME",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imagej_descriptions() {
        let m = StackMeta::parse("ImageJ=1.53t\nimages=60\nchannels=2\nslices=30\nhyperstack=true\nspacing=0.25\n");
        let m = m.unwrap().unwrap();
        assert_eq!((m.channels, m.frames, m.planes), (2, 1, Some(60)));
        assert_eq!(m.spacing, [None, None, Some(0.25)]);
        let (subject, e) = m.refusal(Plane::default()).unwrap();
        assert!(e.contains("2 channels at 1 time point (ImageJ") && e.contains("`problem.channel` (0 to 1)"), "{e}");
        assert_eq!(subject, Subject::Channel);
        assert_eq!(m.refusal(Plane { channel: Some(1), time_point: None }), None);
        assert_eq!((m.plane_of(0), m.plane_of(1), m.plane_of(2)), ((0, 0), (1, 0), (0, 0)));
        let one = StackMeta::parse("ImageJ=1.11a\nimages=4\nspacing=2\n").unwrap().unwrap();
        assert_eq!(one.refusal(Plane::default()), None);
        let (subject, e) = one.refusal(Plane { channel: None, time_point: Some(1) }).unwrap();
        assert!(subject == Subject::TimePoint && e.contains("time point 1 was asked for (0 to 0)"), "{e}");
        // a time series of 3 time points of 2 channels of 5 slices: channels
        // fastest, then slices; without `slices=`, the images left over
        for text in [
            "ImageJ=1.54f\nimages=30\nchannels=2\nslices=5\nframes=3\n",
            "ImageJ=1.54f\nimages=30\nchannels=2\nframes=3\n",
        ] {
            let m = StackMeta::parse(text).unwrap().unwrap();
            assert_eq!((m.channel_stride, m.frame_stride), (1, 10), "{text}");
            assert_eq!((m.plane_of(9), m.plane_of(10), m.plane_of(29)), ((1, 0), (0, 1), (1, 2)));
            let (subject, e) = m.refusal(Plane::default()).unwrap();
            assert_eq!(subject, Subject::Channel);
            assert!(e.contains("(0 to 1) and the time point to segment with `problem.time_point` (0 to 2)"), "{e}");
            let (subject, e) = m.refusal(Plane { channel: Some(0), time_point: None }).unwrap();
            assert!(subject == Subject::TimePoint && e.contains("2 channels at 3 time points"), "{e}");
            assert_eq!(m.refusal(Plane { channel: Some(0), time_point: Some(2) }), None);
            let (_, e) = m.refusal(Plane { channel: Some(0), time_point: Some(3) }).unwrap();
            assert!(e.contains("time point 3 was asked for (0 to 2)"), "{e}");
        }
        assert_eq!(StackMeta::parse("made by a scanner").unwrap(), None);
    }

    /// Units converted to micrometres; colour interleaved in a page (three
    /// samples per pixel) is one channel; XML that breaks off is an error.
    #[test]
    fn ome_pixels() {
        let xml = |attrs: &str, spp: usize| {
            format!(
                r#"<?xml version="1.0"?><OME xmlns="http://www.openmicroscopy.org/Schemas/OME/2016-06"><Image ID="Image:0"><Pixels ID="Pixels:0" Type="uint8" SizeX="6" SizeY="5" {attrs}><Channel ID="Channel:0:0" SamplesPerPixel="{spp}"/><TiffData/></Pixels></Image></OME>"#
            )
        };
        let m = StackMeta::parse(&xml(
            r#"SizeC="1" SizeZ="8" SizeT="1" PhysicalSizeX="0.2" PhysicalSizeY="200" PhysicalSizeYUnit="nm" PhysicalSizeZ="0.001" PhysicalSizeZUnit="mm""#,
            1,
        ));
        let m = m.unwrap().unwrap();
        assert_eq!((m.channels, m.frames, m.planes, m.source), (1, 1, Some(8), "OME"));
        let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 1e-12;
        assert!(close(m.spacing[0], 0.2) && close(m.spacing[1], 0.2) && close(m.spacing[2], 1.0), "{m:?}");
        let rgb = StackMeta::parse(&xml(r#"SizeC="3" SizeZ="4" SizeT="1""#, 3)).unwrap().unwrap();
        assert_eq!((rgb.channels, rgb.planes, rgb.spacing), (1, Some(4), [None; 3]));
        let series = StackMeta::parse(&xml(r#"SizeC="1" SizeZ="4" SizeT="5""#, 1)).unwrap().unwrap();
        let (subject, e) = series.refusal(Plane { channel: Some(0), time_point: None }).unwrap();
        assert!(subject == Subject::TimePoint && e.contains("1 channel at 5 time points (OME"), "{e}");
        assert_eq!(series.refusal(Plane { channel: None, time_point: Some(4) }), None);
        // XYCZT: T slowest, after the 4 slices
        assert_eq!((series.frame_stride, series.plane_of(3), series.plane_of(4)), (4, (0, 0), (0, 1)));
        let tfirst = StackMeta::parse(&xml(r#"SizeC="2" SizeZ="4" SizeT="3" DimensionOrder="XYTZC""#, 1));
        let tfirst = tfirst.unwrap().unwrap();
        assert_eq!((tfirst.frame_stride, tfirst.channel_stride), (1, 12));
        assert_eq!((tfirst.plane_of(1), tfirst.plane_of(12)), ((0, 1), (1, 0)));
        // channels stored after the slices: 4 pages of channel 0, then of channel 1
        let zfirst = StackMeta::parse(&xml(r#"SizeC="2" SizeZ="4" SizeT="1" DimensionOrder="XYZCT""#, 1));
        let zfirst = zfirst.unwrap().unwrap();
        assert_eq!((zfirst.channel_stride, zfirst.plane_of(3), zfirst.plane_of(4)), (4, (0, 0), (1, 0)));
        // sizes beyond any file (found by fuzzing: their product overflowed)
        let huge = StackMeta::parse(&xml(r#"SizeC="2" SizeZ="1e30" SizeT="9e18" DimensionOrder="XYZTC""#, 1));
        let huge = huge.unwrap().unwrap();
        assert_eq!((huge.channel_stride, huge.planes), (usize::MAX, Some(usize::MAX)));
        assert!(huge.refusal(Plane { channel: Some(0), time_point: None }).is_some());
        assert!(huge.refusal(Plane { channel: Some(0), time_point: Some(0) }).is_none());
        assert_eq!((huge.plane_of(0), huge.plane_of(usize::MAX - 1)), ((0, 0), (0, 0)));
        let e = StackMeta::parse(&xml(r#"SizeZ="4" PhysicalSizeZ="2" PhysicalSizeZUnit="furlong""#, 1));
        assert!(e.unwrap_err().contains("PhysicalSizeZUnit \"furlong\""));
        assert!(StackMeta::parse("<OME><Image><Pixels SizeZ=\"4").is_err());
    }
}
