//! Jobs: the job spec (`spec`: serde types, parsing with errors naming the field,
//! the JSON Schema and its Markdown reference), its translation into a mesh, a
//! problem and flow settings (`prepare`), the run of a prepared job with progress
//! and checkpoint callbacks (`run`), the stored states with their fields
//! (`frames`) and the result files of a run (`results`, `vtk_files`).
//! No I/O: input files arrive as bytes.

mod estimate;
mod frames;
mod kept;
mod necks;
mod outputs;
mod prepare;
mod results;
mod run;
mod schema;
mod schema_doc;
mod spec;
mod vtk_files;

pub use crate::formats::{read_mesh_file, MeshFileError};
pub use crate::geometry::AnyMesh;
pub use estimate::MemoryEstimate;
pub use frames::{
    evolution_frames_of, job_extras, state_glb, states_glb, Frame, FrameFields, FrameMaker, GlbContext, MAX_FRAMES,
};
pub use kept::{run_with_frames, KeptFrames, FRAMES_AHEAD};
pub use necks::NeckSplit;
pub use outputs::output_files;
pub use prepare::{default_min_size, default_mu, default_mu_in, prepare, PreparedJob, ProblemKind, SegmentationSetup};
pub use results::{image_result_names, result_files, result_state, ImageArrays, ResultFile, StateResults, GLB};
pub use run::{run_prepared, run_vertex_fields, vertex_fields, JobFailure, JobOutcome, RunEvents};
pub use schema::{job_spec_schema, openapi_schemas};
pub use schema_doc::job_spec_reference;
pub use spec::{
    format_size, parse_size, parse_spec, BoundarySpec, ColorBy, ControlSpec, FlowSpec, InitialSpec, JobSpec, Limits,
    LimitsSpec, MeansKind, MeshSpec, OutputSpec, Polarity, ProblemSpec, SegmentationModel, SegmentationSpec,
    ShapeDesignSpec, Size, SpecError, StressedFilmSpec, TargetSpec,
};
pub use vtk_files::{frame_vtp, vtk_series, zip_files, EVOLUTION_VTK_ZIP};
