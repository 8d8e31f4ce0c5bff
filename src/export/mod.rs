//! Result formats (pure functions to strings/bytes): shape.json (DESIGN.md §3), the
//! energy history as CSV and as an SVG plot.

mod energy_csv;
mod energy_svg;
mod shape_json;

pub use energy_csv::energy_csv;
pub use energy_svg::energy_svg;
pub use shape_json::shape_json;
