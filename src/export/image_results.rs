//! Results of image jobs: the segmentation mask (PNG in 2D, gzip NRRD in 3D), the
//! contours drawn over the image (PNG), and pixel coordinates for shape.json.

use crate::flow::MeshData;
use crate::geometry::Point;
use crate::imaging::{draw_overlay, rasterize_curve, rasterize_surface, Grid};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

fn points<const D: usize>(mesh: &MeshData) -> Vec<Point<D>> {
    mesh.positions.iter().map(|p| Point::<D>::from_fn(|i, _| p[i])).collect()
}

fn elements<const D: usize>(mesh: &MeshData) -> Vec<[usize; D]> {
    mesh.elements.iter().map(|e| std::array::from_fn(|k| e[k])).collect()
}

fn png(width: usize, height: usize, data: &[u8], color: ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out).write_image(data, width as u32, height as u32, color).expect("encoding to memory");
    out
}

/// The inside/outside mask of `mesh` on the grid of `image`, grid order (2D rows
/// from the bottom).
pub fn mask(image: &Grid, mesh: &MeshData) -> Vec<bool> {
    let d = image.dims;
    if mesh.dimension == 2 {
        rasterize_curve(&points::<2>(mesh), &elements::<2>(mesh), [d[0], d[1]])
    } else {
        rasterize_surface(&points::<3>(mesh), &elements::<3>(mesh), d)
    }
}

/// mask.png: 8-bit gray, 255 inside, 0 outside, the size of the input image.
pub fn mask_png(image: &Grid, mesh: &MeshData) -> Vec<u8> {
    let [w, h, _] = image.dims;
    let m = mask(image, mesh);
    let mut rows = vec![0u8; w * h];
    for j in 0..h {
        for i in 0..w {
            rows[i + w * (h - 1 - j)] = if m[i + w * j] { 255 } else { 0 };
        }
    }
    png(w, h, &rows, ExtendedColorType::L8)
}

/// overlay.png: the image in gray with the contours in red (2D only).
pub fn overlay_png(image: &Grid, mesh: &MeshData) -> Vec<u8> {
    let rgb = draw_overlay(image, &points::<2>(mesh), &elements::<2>(mesh));
    png(image.dims[0], image.dims[1], &rgb, ExtendedColorType::Rgb8)
}

/// Unit-box coordinates to image coordinates: 2D `(column, row)` with rows counted
/// from the top as in the file (pixel centres at integers), 3D voxel indices `(i, j, k)`.
pub fn to_pixel(image: &Grid, x: &[f64]) -> Vec<f64> {
    let l = image.scale();
    if image.dimension == 2 {
        vec![x[0] * l - 0.5, image.dims[1] as f64 - 0.5 - x[1] * l]
    } else {
        x.iter().map(|v| v * l - 0.5).collect()
    }
}

/// Unit-box coordinates to the image's physical space, as VTK readers (ParaView's
/// NRRD, NIfTI and PNG readers) place the image: sample `(i, j, k)` of the grid
/// (2D rows counted from the bottom, so that the picture is upright) at
/// `origin + i axes[0] + j axes[1] + k axes[2]` of its [`Placement`](crate::imaging::Placement)
/// (a 2D image: unit spacing, origin 0; `z` = 0).
pub fn to_world(image: &Grid, x: &[f64]) -> [f64; 3] {
    let l = image.scale();
    let p = &image.placement;
    let mut w = p.origin;
    for (a, axis) in p.axes.iter().enumerate().take(image.dimension.min(x.len())) {
        let g = x[a] * l - 0.5;
        for c in 0..3 {
            w[c] += g * axis[c];
        }
    }
    if image.dimension == 2 {
        w[2] = 0.0;
    }
    w
}

/// Unit-box coordinates to the axis order and units of the image as an array
/// (numpy, scikit-image, napari): 2D `(row, column)`, rows from the top as in
/// the file, in pixels; 3D the physical coordinates ([`to_world`]) reversed,
/// `(z, y, x)`, with `y` counted from the first row where the input's rows run
/// from the top (a TIFF stack or a stack of slices, placed at the origin along
/// the axes): the physical coordinates of the array as tifffile reads it.
pub fn to_array_coordinates(image: &Grid, x: &[f64]) -> Vec<f64> {
    if image.dimension == 2 {
        return to_pixel(image, x).into_iter().rev().collect();
    }
    let mut w = to_world(image, x);
    if image.layout.rows_flipped {
        // grid row j_in of the input (from the bottom) lies at y = s j_in
        w[1] = (image.layout.dims[1] as f64 - 1.0) * image.input_spacing()[1] - w[1];
    }
    w.into_iter().rev().collect()
}
