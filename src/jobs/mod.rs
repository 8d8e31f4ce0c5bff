//! Jobs: the job spec (docs/job-spec.md) (serde, validated with errors naming the
//! field), its translation into a mesh, a problem and flow settings, and the run of
//! a prepared job with progress and checkpoint callbacks. No I/O: input files arrive
//! as bytes.

mod build;
mod design;
mod film;
mod image_shapes;
mod results;
mod run;
mod schema;
mod schema_doc;
mod segment;
mod spec;
mod spec_path;

pub use crate::formats::{read_mesh_file, MeshFileError};
pub use build::{prepare, AnyMesh, PreparedJob, ProblemKind};
pub use results::{image_result_names, job_extras, result_state, state_glb, states_glb, StateResults, MAX_FRAMES};
pub use run::{run_prepared, vertex_fields, JobFailure, JobOutcome, RunEvents};
pub use schema::{job_spec_schema, openapi_schemas};
pub use schema_doc::job_spec_reference;
pub use segment::{default_min_size, default_mu, SegmentationSetup};
pub use spec::{
    parse_spec, BoundarySpec, ControlSpec, FlowSpec, InitialSpec, JobSpec, MeansKind, MeshSpec, OutputSpec, Polarity,
    ProblemSpec, SegmentationModel, SegmentationSpec, ShapeDesignSpec, SpecError, StressedFilmSpec, TargetSpec,
};
