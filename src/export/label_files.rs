//! Label images and contours for Fiji, napari and the TIFF readers: labels.tif (a
//! 2D image's labels, uint16, rows from the top), labels.ome.tif (a volume's
//! labels, one uint16 page per plane, with OME-XML giving `PhysicalSizeX/Y/Z`)
//! and rois.zip (an ImageJ ROI set: one sub-pixel polygon per contour).

use super::image_results::to_pixel;
use super::objects::object_elements;
use super::zip_files::zip_files;
use crate::flow::MeshData;
use crate::geometry::segment_cycles;
use crate::imaging::Grid;
use std::io::Cursor;
use tiff::encoder::{colortype::Gray16, TiffEncoder};
use tiff::tags::Tag;

/// labels.tif (2D) or labels.ome.tif (3D) of grid-order `labels`, in the input's
/// shape and order ([`Grid::to_array`]).
pub fn labels_tiff(image: &Grid, labels: &[u16]) -> Vec<u8> {
    let [w, h, d] = image.layout.dims;
    let array = image.to_array(labels);
    let mut out = Cursor::new(Vec::new());
    let mut tiff = TiffEncoder::new(&mut out).expect("a TIFF in memory");
    let planes = if image.dimension == 2 { 1 } else { d };
    for k in 0..planes {
        let page = &array[k * w * h..(k + 1) * w * h];
        let mut encoder = tiff.new_image::<Gray16>(w as u32, h as u32).expect("a TIFF page in memory");
        if k == 0 && image.dimension == 3 {
            encoder.encoder().write_tag(Tag::ImageDescription, ome_xml(image).as_str()).expect("a TIFF tag in memory");
        }
        encoder.write_data(page).expect("a TIFF page in memory");
    }
    out.into_inner()
}

/// The OME-XML of a volume's label image: `XYZCT`, uint16, the input's sample
/// spacing as `PhysicalSizeX/Y/Z` (in the input's units, which OME's readers take
/// as its default, µm, when a file names none).
fn ome_xml(image: &Grid) -> String {
    let [w, h, d] = image.layout.dims;
    let [sx, sy, sz] = image.input_spacing();
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\" \
         xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:schemaLocation=\"http://www.openmicroscopy.org/Schemas/OME/2016-06 \
         http://www.openmicroscopy.org/Schemas/OME/2016-06/ome.xsd\">\
         <Image ID=\"Image:0\" Name=\"labels\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYZCT\" Type=\"uint16\" \
         SizeX=\"{w}\" SizeY=\"{h}\" SizeZ=\"{d}\" SizeC=\"1\" SizeT=\"1\" \
         PhysicalSizeX=\"{sx:?}\" PhysicalSizeY=\"{sy:?}\" PhysicalSizeZ=\"{sz:?}\" BigEndian=\"false\">\
         <Channel ID=\"Channel:0:0\" SamplesPerPixel=\"1\"/><TiffData IFD=\"0\" PlaneCount=\"{d}\"/>\
         </Pixels></Image></OME>"
    )
}

/// rois.zip of a 2D image job: for each object (in the order of its label), one
/// polygon ROI per contour, named `LLLL-K` (label, contour), with ImageJ's
/// sub-pixel coordinates (pixel `(c, r)` covers `[c, c + 1) × [r, r + 1)`, rows
/// from the top). A contour of more than 65535 vertices is thinned to that
/// many (the format's limit).
pub fn rois_zip(image: &Grid, mesh: &MeshData) -> Vec<u8> {
    let mut files = Vec::new();
    for (k, elements) in object_elements(image, mesh).iter().enumerate() {
        let n = mesh.positions.len();
        let cycles = segment_cycles(n, elements.iter().map(|&e| (mesh.elements[e][0], mesh.elements[e][1])));
        for (c, cycle) in cycles.iter().enumerate() {
            let step = cycle.len().div_ceil(u16::MAX as usize).max(1);
            let points: Vec<[f32; 2]> = cycle
                .iter()
                .step_by(step)
                .map(|&v| {
                    let p = to_pixel(image, &mesh.positions[v]);
                    [(p[0] + 0.5) as f32, (p[1] + 0.5) as f32]
                })
                .collect();
            let name = format!("{:04}-{}", k + 1, c + 1);
            files.push((format!("{name}.roi"), polygon_roi(&points, &name)));
        }
    }
    zip_files(&files)
}

/// One ImageJ ROI file (`Iout`, version 228, big-endian): a polygon with its
/// integer coordinates relative to its box and its sub-pixel ones
/// (`SUB_PIXEL_RESOLUTION`), then the second header with its `name`.
fn polygon_roi(points: &[[f32; 2]], name: &str) -> Vec<u8> {
    let clamp = |v: f32| v.floor().clamp(i16::MIN as f32, i16::MAX as f32) as i16;
    let left = points.iter().map(|p| clamp(p[0])).min().unwrap_or(0);
    let top = points.iter().map(|p| clamp(p[1])).min().unwrap_or(0);
    let right = points.iter().map(|p| clamp(p[0].ceil())).max().unwrap_or(0);
    let bottom = points.iter().map(|p| clamp(p[1].ceil())).max().unwrap_or(0);
    let mut out = Vec::with_capacity(64 + 12 * points.len());
    out.extend_from_slice(b"Iout");
    out.extend_from_slice(&228i16.to_be_bytes()); // version
    out.push(0); // type: polygon
    out.push(0);
    for v in [top, left, bottom, right] {
        out.extend_from_slice(&v.to_be_bytes());
    }
    out.extend_from_slice(&(points.len() as u16).to_be_bytes());
    out.resize(50, 0); // line ends, stroke width, shape size, colours, subtype
    out.extend_from_slice(&128i16.to_be_bytes()); // options: SUB_PIXEL_RESOLUTION
    out.resize(56, 0);
    out.extend_from_slice(&0i32.to_be_bytes()); // position: none (a 2D image)
    let header2 = 64 + 12 * points.len();
    out.extend_from_slice(&(header2 as i32).to_be_bytes());
    for p in points {
        out.extend_from_slice(&(clamp(p[0]) - left).to_be_bytes());
    }
    for p in points {
        out.extend_from_slice(&(clamp(p[1]) - top).to_be_bytes());
    }
    for axis in 0..2 {
        for p in points {
            out.extend_from_slice(&p[axis].to_be_bytes());
        }
    }
    // the second header (64 bytes): the name's offset and length at 16 and 20
    let chars: Vec<u16> = name.encode_utf16().collect();
    let start = out.len();
    out.resize(start + 64, 0);
    out[start + 16..start + 20].copy_from_slice(&((start + 64) as i32).to_be_bytes());
    out[start + 20..start + 24].copy_from_slice(&(chars.len() as i32).to_be_bytes());
    out.extend(chars.iter().flat_map(|c| c.to_be_bytes()));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::circle;
    use crate::imaging::SampleKind;

    #[test]
    fn a_disc_as_tiff_and_roi() {
        let n = 64;
        let image = Grid::new(2, [n, n, 1], vec![0.0; n * n], SampleKind::U8);
        let mesh = MeshData::from(&circle([0.5, 0.25], 0.1, 100).unwrap());
        let (labels, _) = super::super::objects(&image, &mesh);
        let tif = labels_tiff(&image, &labels);
        let decoded = image::load_from_memory(&tif).unwrap().into_luma16();
        let array = image.to_array(&labels);
        assert_eq!(decoded.as_raw(), &array);
        assert!(array.contains(&1));
        let roi = polygon_roi(&[[1.5, 2.5], [10.0, 2.5], [10.0, 8.0]], "0001-1");
        assert_eq!(&roi[..4], b"Iout");
        assert_eq!(roi.len(), 64 + 3 * 4 + 3 * 8 + 64 + 2 * 6);
        assert_eq!(u16::from_be_bytes([roi[16], roi[17]]), 3);
        let zip = rois_zip(&image, &mesh);
        let archive = zip::ZipArchive::new(Cursor::new(zip)).unwrap();
        let names: Vec<String> = archive.file_names().map(|n| n.unwrap().to_string()).collect();
        assert_eq!(names, ["0001-1.roi"]);
    }
}
