//! Result formats (pure functions to strings/bytes): shape.json (DESIGN.md §3), the
//! energy history as CSV and as an SVG plot; masks and overlays of image jobs; glTF (.glb) shapes and evolutions.

mod energy_csv;
mod energy_svg;
mod gltf;
mod image_results;
mod shape_json;

pub use energy_csv::energy_csv;
pub use energy_svg::energy_svg;
pub use gltf::{evolution_glb, shape_glb, GltfFrame, FRAME_SECONDS};
pub use image_results::{mask, mask_nrrd, mask_png, overlay_png, to_pixel};
pub use shape_json::shape_json;
