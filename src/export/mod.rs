//! Result formats (pure functions to strings/bytes): shape.json (DESIGN.md §3) and
//! the energy history as CSV.

mod energy_csv;
mod shape_json;

pub use energy_csv::energy_csv;
pub use shape_json::shape_json;
