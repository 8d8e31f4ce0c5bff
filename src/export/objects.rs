//! Per-object results of image jobs: a label image (one label per object,
//! `1..=n` in reading order of the centroids, 0 background; 16-bit PNG in 2D,
//! uint16 gzip NRRD in 3D) and a table of the objects (objects.csv, and
//! `"objects"` in shape.json).
//!
//! An object is a component of the shape together with the holes (cavities)
//! inside it ([`Mesh::objects`]). Area, perimeter (volume, surface area) and centroid come from the
//! polygons (triangles), exact for the shape; the bounding box and the mean
//! intensity from the object's pixels (voxels), whose centres it encloses.

use super::image_results::to_pixel;
use crate::flow::MeshData;
use crate::geometry::{Mesh, Point};
use crate::imaging::{rasterize_curve_window, rasterize_surface_window, Grid};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use serde::Serialize;

/// One row of the table, in image units (pixels, voxels; coordinates as in
/// shape.json's `pixels`/`voxels`: 2D `(column, row from the top)`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectRow {
    pub label: u32,
    /// Area (2D) or volume (3D).
    pub size: f64,
    /// Perimeter (2D) or surface area (3D).
    pub boundary: f64,
    pub centroid: Vec<f64>,
    /// Smallest and largest pixel (voxel) index along each axis (2D: column, row).
    pub bbox_min: Vec<usize>,
    pub bbox_max: Vec<usize>,
    /// Mean of the input image over the object's pixels (its original units).
    pub mean_intensity: f64,
    /// Number of the object's pixels (voxels).
    pub pixels: usize,
    /// (Addition) scikit-image's `regionprops` of the label in the label image
    /// as an array ([`Grid::to_array`]): its number of pixels (`area`, `num_pixels`)…
    pub num_pixels: usize,
    /// … the mean of their array indices (`centroid-0`, `-1`(, `-2`): 2D
    /// `(row, column)`, 3D `(plane, row, column)`)…
    pub array_centroid: Vec<f64>,
    /// … and their half-open box (`bbox-0` … : the smallest indices, then the
    /// largest plus one).
    pub array_bbox: Vec<usize>,
}

/// An object's area (volume), perimeter (surface area) and centroid in unit-box
/// units, and its elements.
type Measured = (f64, f64, Vec<f64>, Vec<usize>);

/// The objects of `mesh` in the order of their labels (reading order of their centroids).
fn measured_objects(image: &Grid, mesh: &MeshData) -> Vec<Measured> {
    let groups = match mesh.dimension {
        2 => mesh.to_mesh_unvalidated::<2>().map(|m| group(&m)),
        _ => mesh.to_mesh_unvalidated::<3>().map(|m| group(&m)),
    }
    .unwrap_or_default();
    // measures from the shape: Σ over elements of the divergence-theorem integrands
    let mut shapes: Vec<Measured> = Vec::new();
    for elements in &groups {
        let (mut size, mut boundary, mut moment) = (0.0, 0.0, vec![0.0; mesh.dimension]);
        for &e in elements {
            let el = &mesh.elements[e];
            if mesh.dimension == 2 {
                let (a, b) = (&mesh.positions[el[0]], &mesh.positions[el[1]]);
                let cross = a[0] * b[1] - b[0] * a[1];
                size += 0.5 * cross;
                boundary += (b[0] - a[0]).hypot(b[1] - a[1]);
                moment[0] += (a[0] + b[0]) * cross / 6.0;
                moment[1] += (a[1] + b[1]) * cross / 6.0;
            } else {
                let [a, b, c] = [0, 1, 2].map(|k| Point::<3>::from_fn(|i, _| mesh.positions[el[k]][i]));
                let n = (b - a).cross(&(c - a));
                let v = a.dot(&n) / 6.0;
                size += v;
                boundary += 0.5 * n.norm();
                let s = a + b + c;
                for (i, m) in moment.iter_mut().enumerate() {
                    *m += v * s[i] / 4.0;
                }
            }
        }
        let centroid: Vec<f64> = moment.iter().map(|m| if size != 0.0 { m / size } else { 0.0 }).collect();
        shapes.push((size, boundary, centroid, elements.clone()));
    }
    // reading order: top to bottom, then left to right (2D rows from the top)
    let key = |c: &[f64]| to_pixel(image, c).into_iter().rev().collect::<Vec<f64>>();
    shapes.sort_by(|a, b| {
        let (ka, kb) = (key(&a.2), key(&b.2));
        ka.iter().zip(&kb).map(|(x, y)| x.total_cmp(y)).find(|o| o.is_ne()).unwrap_or(std::cmp::Ordering::Equal)
    });
    shapes
}

/// The elements of each object, in the order of their labels (label `k + 1` at `k`).
pub fn object_elements(image: &Grid, mesh: &MeshData) -> Vec<Vec<usize>> {
    measured_objects(image, mesh).into_iter().map(|o| o.3).collect()
}

/// The label image (grid order, 2D rows from the bottom) and the table.
pub fn objects(image: &Grid, mesh: &MeshData) -> (Vec<u16>, Vec<ObjectRow>) {
    let shapes = measured_objects(image, mesh);
    let l = image.scale();
    let d = image.dims;
    // every object's pixels are found on the positions of the whole mesh, made once
    let (pos2, pos3): (Vec<Point<2>>, Vec<Point<3>>) = if mesh.dimension == 2 {
        (mesh.positions.iter().map(|p| Point::<2>::new(p[0], p[1])).collect(), Vec::new())
    } else {
        (Vec::new(), mesh.positions.iter().map(|p| Point::<3>::new(p[0], p[1], p[2])).collect())
    };
    let mut labels = vec![0u16; image.len()];
    let mut rows = Vec::with_capacity(shapes.len());
    for (k, (size, boundary, centroid, elements)) in shapes.into_iter().enumerate() {
        let label = (k + 1).min(u16::MAX as usize) as u16;
        // the samples of the object's bounding box
        let mut window = [0usize; 6];
        for a in 0..3 {
            let n = d[a];
            let (lo, hi) = if a < mesh.dimension {
                elements
                    .iter()
                    .flat_map(|&e| mesh.elements[e].iter())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                        (lo.min(mesh.positions[v][a]), hi.max(mesh.positions[v][a]))
                    })
            } else {
                (0.0, 0.0)
            };
            window[2 * a] = ((lo * l - 0.5).floor().max(0.0) as usize).min(n);
            window[2 * a + 1] =
                if a < mesh.dimension { ((hi * l - 0.5).ceil() + 1.0).clamp(0.0, n as f64) as usize } else { n };
        }
        let inside = if mesh.dimension == 2 {
            let segs: Vec<[usize; 2]> = elements.iter().map(|&e| [mesh.elements[e][0], mesh.elements[e][1]]).collect();
            rasterize_curve_window(&pos2, &segs, l, [window[0], window[1], window[2], window[3]])
        } else {
            let tris: Vec<[usize; 3]> =
                elements.iter().map(|&e| std::array::from_fn(|i| mesh.elements[e][i])).collect();
            rasterize_surface_window(&pos3, &tris, l, window)
        };
        let (w, h) = (window[1] - window[0], window[3] - window[2]);
        let (mut sum, mut count) = (0.0, 0usize);
        let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
        for (q, _) in inside.iter().enumerate().filter(|(_, &m)| m) {
            let ijk = [window[0] + q % w, window[2] + (q / w) % h, window[4] + q / (w * h)];
            let p = image.index(ijk[0], ijk[1], ijk[2]);
            if labels[p] == 0 {
                labels[p] = label;
            }
            sum += image.values[p];
            count += 1;
            for a in 0..3 {
                lo[a] = lo[a].min(ijk[a]);
                hi[a] = hi[a].max(ijk[a]);
            }
        }
        let (bbox_min, bbox_max) = if count == 0 {
            (vec![0; mesh.dimension], vec![0; mesh.dimension])
        } else if mesh.dimension == 2 {
            // rows from the top, as in the file
            (vec![lo[0], d[1] - 1 - hi[1]], vec![hi[0], d[1] - 1 - lo[1]])
        } else {
            (lo.to_vec(), hi.to_vec())
        };
        let scale = l.powi(mesh.dimension as i32);
        rows.push(ObjectRow {
            label: label as u32,
            size: size * scale,
            boundary: boundary * l.powi(mesh.dimension as i32 - 1),
            centroid: to_pixel(image, &centroid),
            bbox_min,
            bbox_max,
            mean_intensity: if count > 0 { sum / count as f64 } else { f64::NAN },
            pixels: count,
            num_pixels: 0,
            array_centroid: vec![f64::NAN; mesh.dimension],
            array_bbox: vec![0; 2 * mesh.dimension],
        });
    }
    let shape = image.array_shape();
    let measures = label_measures(&image.to_array(&labels), &shape, rows.len());
    for (row, m) in rows.iter_mut().zip(measures) {
        (row.num_pixels, row.array_centroid, row.array_bbox) = m;
    }
    (labels, rows)
}

/// For labels `1..=count` of a C-order label array of `shape`: the number of
/// its samples, the mean of their indices and their half-open bounding box (as
/// scikit-image's `regionprops`; NaN centroid and an empty box for an absent label).
fn label_measures(labels: &[u16], shape: &[usize], count: usize) -> Vec<(usize, Vec<f64>, Vec<usize>)> {
    let d = shape.len();
    let mut n = vec![0usize; count];
    let mut sums = vec![vec![0.0f64; d]; count];
    let mut lo = vec![vec![usize::MAX; d]; count];
    let mut hi = vec![vec![0usize; d]; count];
    let mut index = vec![0usize; d];
    for &l in labels {
        if l > 0 && (l as usize) <= count {
            let o = l as usize - 1;
            n[o] += 1;
            for a in 0..d {
                sums[o][a] += index[a] as f64;
                lo[o][a] = lo[o][a].min(index[a]);
                hi[o][a] = hi[o][a].max(index[a] + 1);
            }
        }
        // the next index in C order
        for a in (0..d).rev() {
            index[a] += 1;
            if index[a] < shape[a] {
                break;
            }
            index[a] = 0;
        }
    }
    (0..count)
        .map(|o| {
            if n[o] == 0 {
                return (0, vec![f64::NAN; d], vec![0; 2 * d]);
            }
            let centroid = sums[o].iter().map(|s| s / n[o] as f64).collect();
            (n[o], centroid, lo[o].iter().chain(&hi[o]).copied().collect())
        })
        .collect()
}

/// The elements of each object ([`Mesh::objects`]), objects in the order of their
/// first element; holes with nothing around them are left out.
fn group<const D: usize>(mesh: &Mesh<D>) -> Vec<Vec<usize>> {
    let objects = mesh.objects();
    let mut slot = vec![usize::MAX; objects.owner.len()];
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (e, el) in mesh.elements().iter().enumerate() {
        let o = objects.owner[objects.vertex_component[el[0]]];
        if objects.measures[o] <= 0.0 {
            continue;
        }
        if slot[o] == usize::MAX {
            slot[o] = out.len();
            out.push(Vec::new());
        }
        out[slot[o]].push(e);
    }
    out
}

/// labels.png: 16-bit gray, the object's label at its pixels, the image's size (the
/// encoder takes native-endian samples).
pub fn labels_png(image: &Grid, labels: &[u16]) -> Vec<u8> {
    let [w, h, _] = image.layout.dims;
    let bytes: Vec<u8> = image.to_array(labels).iter().flat_map(|l| l.to_ne_bytes()).collect();
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(&bytes, w as u32, h as u32, ExtendedColorType::L16)
        .expect("encoding to memory");
    out
}

/// objects.csv: one line per object (the columns of [`ObjectRow`]; 2D: `area`,
/// `perimeter`, `x`, `y`; 3D: `volume`, `surface_area`, `x`, `y`, `z`), then
/// scikit-image's columns of the label image (`num_pixels`, `centroid-0` …,
/// `bbox-0` …: see [`ObjectRow::array_bbox`]).
pub fn objects_csv(dimension: usize, rows: &[ObjectRow]) -> String {
    let mut out = String::new();
    if dimension == 2 {
        out.push_str("label,area,perimeter,centroid_x,centroid_y,bbox_min_x,bbox_min_y,bbox_max_x,bbox_max_y,mean_intensity,pixels");
    } else {
        out.push_str("label,volume,surface_area,centroid_x,centroid_y,centroid_z,bbox_min_x,bbox_min_y,bbox_min_z,bbox_max_x,bbox_max_y,bbox_max_z,mean_intensity,pixels");
    }
    out.push_str(",num_pixels");
    for a in 0..dimension {
        out.push_str(&format!(",centroid-{a}"));
    }
    for a in 0..2 * dimension {
        out.push_str(&format!(",bbox-{a}"));
    }
    out.push('\n');
    for r in rows {
        let mut cols = vec![r.label.to_string(), format!("{:.4}", r.size), format!("{:.4}", r.boundary)];
        cols.extend(r.centroid.iter().map(|c| format!("{c:.4}")));
        cols.extend(r.bbox_min.iter().chain(&r.bbox_max).map(|v| v.to_string()));
        cols.push(format!("{:.6}", r.mean_intensity));
        cols.push(r.pixels.to_string());
        cols.push(r.num_pixels.to_string());
        cols.extend(r.array_centroid.iter().map(|c| format!("{c:.4}")));
        cols.extend(r.array_bbox.iter().map(|v| v.to_string()));
        out.push_str(&cols.join(","));
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{circle, union};
    use crate::imaging::SampleKind;

    #[test]
    fn two_discs_and_a_ring() {
        let n = 100;
        let image = Grid::new(2, [n, n, 1], (0..n * n).map(|p| (p % n) as f64).collect(), SampleKind::U8);
        let a = circle([0.3, 0.7], 0.1, 400).unwrap();
        let b = circle([0.7, 0.3], 0.15, 400).unwrap();
        let hole = circle([0.7, 0.3], 0.05, 200).unwrap();
        let hole = hole.with_positions(hole.positions().iter().map(|p| Point::<2>::new(p.x, 0.6 - p.y)).collect());
        let m = union(&[a, b, hole]).unwrap();
        let (labels, rows) = objects(&image, &MeshData::from(&m));
        assert_eq!(rows.len(), 2);
        // the disc at the top comes first; the ring's area excludes its hole
        let pi = std::f64::consts::PI;
        assert!((rows[0].size - pi * 100.0).abs() < 0.1, "{}", rows[0].size);
        assert!((rows[1].size - pi * (225.0 - 25.0)).abs() < 0.3, "{}", rows[1].size);
        assert!((rows[1].boundary - 2.0 * pi * 20.0).abs() < 0.1);
        assert!((rows[0].centroid[0] - 29.5).abs() < 1e-6 && (rows[0].centroid[1] - 29.5).abs() < 1e-6);
        assert!((rows[0].mean_intensity - 29.5).abs() < 0.5);
        assert_eq!(labels.iter().filter(|&&l| l == 2).count(), rows[1].pixels);
        // scikit-image's measures of the label image: (row, column), half-open box
        assert_eq!(rows[1].num_pixels, rows[1].pixels);
        let c = &rows[0].array_centroid;
        assert!((c[0] - 29.5).abs() < 0.2 && (c[1] - 29.5).abs() < 0.2, "{c:?}");
        let b = &rows[0].array_bbox;
        assert!(b[0] >= 19 && b[0] <= 20 && b[2] >= 39 && b[2] <= 40 && b[2] - b[0] == b[3] - b[1], "{b:?}");
        assert!((rows[1].pixels as f64 - pi * 200.0).abs() < 15.0);
        let csv = objects_csv(2, &rows);
        assert_eq!(csv.lines().count(), 3);
        assert!(csv.lines().next().unwrap().ends_with(",num_pixels,centroid-0,centroid-1,bbox-0,bbox-1,bbox-2,bbox-3"));
        assert_eq!(csv.lines().nth(1).unwrap().split(',').count(), 18);
        assert!(labels_png(&image, &labels).starts_with(b"\x89PNG"));
    }
}
