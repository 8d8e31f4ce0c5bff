//! What a TIFF stack's first image description says of its layout and voxel
//! spacing: ImageJ's `key=value` lines (`channels=`, `slices=`, `frames=`,
//! `spacing=`) or OME-XML's `Pixels` element (`SizeC`, `SizeZ`, `SizeT`,
//! `PhysicalSize{X,Y,Z}` with their units, the `SamplesPerPixel` of its first
//! `Channel`). A volume is one channel at one time point: of a stack of several
//! channels the one asked for is read (`problem.channel`); a stack of several
//! time points, or of several channels without a choice, is refused with its
//! layout named, never read as slices.

use quick_xml::events::Event;
use quick_xml::XmlVersion;

/// The layout and spacing a description declares.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct StackMeta {
    /// Channels stored as separate pages (colour interleaved within a page is one).
    pub channels: usize,
    pub frames: usize,
    /// Consecutive pages of one channel: the pages of the dimensions stored
    /// faster than the channel's (ImageJ: 1, channels fastest; OME: by its
    /// `DimensionOrder`).
    pub channel_stride: usize,
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

    /// What keeps this stack from being read as the volume of `channel` (or of
    /// its only channel), if anything: several time points, or several channels
    /// and none chosen.
    pub(super) fn refusal(&self, channel: Option<usize>) -> Option<String> {
        let count = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        let layout = format!(
            "is a stack of {} at {} ({} metadata)",
            count(self.channels, "channel"),
            count(self.frames, "time point"),
            self.source
        );
        if self.frames > 1 {
            return Some(format!("{layout}; a volume is one time point: save the one to segment as its own stack"));
        }
        match channel {
            None if self.channels > 1 => Some(format!(
                "{layout}; choose the channel to segment with `problem.channel` (0 to {})",
                self.channels - 1
            )),
            _ => None,
        }
    }

    /// The channel that page `page` belongs to.
    pub(super) fn channel_of(&self, page: usize) -> usize {
        (page / self.channel_stride.max(1)) % self.channels.max(1)
    }
}

/// A positive finite number.
fn positive(v: &str) -> Option<f64> {
    v.trim().parse().ok().filter(|v: &f64| v.is_finite() && *v > 0.0)
}

/// ImageJ's description: `images=`, `channels=`, `slices=`, `frames=`,
/// `spacing=` (the z step in the unit of the x resolution).
fn imagej(text: &str) -> StackMeta {
    let value = |key: &str| text.lines().find_map(|l| l.strip_prefix(key)?.strip_prefix('=')).and_then(positive);
    let count = |key: &str| value(key).map_or(1, |v| v as usize);
    StackMeta {
        channels: count("channels"),
        frames: count("frames"),
        channel_stride: 1,
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
    // the dimensions stored faster than C, from `XY` + the order of Z, C and T
    let order = get("DimensionOrder").unwrap_or("XYCZT");
    let faster = order.get(2..).and_then(|o| o.split_once('C')).map_or("", |(before, _)| before);
    // (sizes as written, however large: saturated, never overflowed)
    let channel_stride = faster.chars().fold(1usize, |p, d| p.saturating_mul(if d == 'Z' { slices } else { frames }));
    Ok(StackMeta {
        channels,
        frames,
        channel_stride,
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
        let e = m.refusal(None).unwrap();
        assert!(e.contains("2 channels at 1 time point (ImageJ") && e.contains("`problem.channel` (0 to 1)"), "{e}");
        assert_eq!(m.refusal(Some(1)), None);
        assert_eq!((m.channel_of(0), m.channel_of(1), m.channel_of(2)), (0, 1, 0));
        let one = StackMeta::parse("ImageJ=1.11a\nimages=4\nspacing=2\n").unwrap().unwrap();
        assert_eq!(one.refusal(None), None);
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
        assert!(series.refusal(Some(0)).unwrap().contains("1 channel at 5 time points (OME"));
        // channels stored after the slices: 4 pages of channel 0, then of channel 1
        let zfirst = StackMeta::parse(&xml(r#"SizeC="2" SizeZ="4" SizeT="1" DimensionOrder="XYZCT""#, 1));
        let zfirst = zfirst.unwrap().unwrap();
        assert_eq!((zfirst.channel_stride, zfirst.channel_of(3), zfirst.channel_of(4)), (4, 0, 1));
        // sizes beyond any file (found by fuzzing: their product overflowed)
        let huge = StackMeta::parse(&xml(r#"SizeC="2" SizeZ="1e30" SizeT="9e18" DimensionOrder="XYZTC""#, 1));
        let huge = huge.unwrap().unwrap();
        assert_eq!((huge.channel_stride, huge.planes), (usize::MAX, Some(usize::MAX)));
        assert!(huge.refusal(Some(0)).is_some());
        let e = StackMeta::parse(&xml(r#"SizeZ="4" PhysicalSizeZ="2" PhysicalSizeZUnit="furlong""#, 1));
        assert!(e.unwrap_err().contains("PhysicalSizeZUnit \"furlong\""));
        assert!(StackMeta::parse("<OME><Image><Pixels SizeZ=\"4").is_err());
    }
}
