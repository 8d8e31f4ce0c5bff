//! The sizes the library and the service accept, stated once: what a spec, an
//! upload, an image or a result may hold. A leaf module: it imports nothing.

/// Largest number of vertices an initial mesh may have (shapes, mesh files).
pub const MAX_VERTICES: usize = 2_000_000;

/// A run's mesh may grow by mesh management to this many times the vertices it
/// started with (at least [`MIN_VERTEX_ALLOWANCE`], at most [`MAX_VERTICES`]);
/// beyond, the run fails with a message on its last state instead of refining
/// until the machine's memory runs out (steps made unstable by the settings:
/// no backtracking and no step control).
pub const MAX_MESH_GROWTH: usize = 8;

/// The vertices a run's mesh may always grow to (see [`MAX_MESH_GROWTH`]).
pub const MIN_VERTEX_ALLOWANCE: usize = 100_000;

/// Largest number of vertices of a stressed film's initial surface.
pub const MAX_FILM_VERTICES: usize = 100_000;

/// Largest number of vertices of a fixed boundary of the shape-design domain.
pub const MAX_BOUNDARY_VERTICES: usize = 100_000;

/// Largest number of frames in evolution.glb; longer runs are subsampled evenly
/// (first and last checkpoint always kept).
pub const MAX_FRAMES: usize = 500;

/// About the largest size of evolution.glb: runs whose frames have many vertices
/// keep fewer of them (evenly picked, first and last always kept; see
/// `GlbContext::evolution_glb`).
pub const MAX_EVOLUTION_BYTES: usize = 64 * 1024 * 1024;

/// Largest accepted JSON request body (a job spec).
pub const MAX_BODY_BYTES: usize = 2 * 1024 * 1024;

/// Largest accepted multipart request body (a spec plus input files).
pub const MAX_UPLOAD_BYTES: usize = 64 * 1024 * 1024;

/// Largest number of pixels of a 2D image (4096²).
pub const MAX_PIXELS: usize = 4096 * 4096;

/// Largest number of voxels of a volume (256³).
pub const MAX_VOXELS: usize = 256 * 256 * 256;

/// Fewest samples along any axis of an image or a volume.
pub const MIN_SIDE: usize = 4;
