//! # shapeflow
//!
//! Shape optimization by discrete gradient flows (Doğan, Morin, Nochetto, Verani):
//! parametric P1 finite elements on closed curves (2D) and closed triangle surfaces
//! (3D), a semi-implicit step with implicit curvature and normal velocity, solved
//! through the Schur complement for the scalar normal velocity `V`.
//!
//! Layers, lowest first (a layer never imports one above it; nothing here does I/O
//! except [`jobs`] reading nothing and the binary writing files):
//!
//! ```text
//! geometry -> fem -> flow -> problems -> jobs
//! export (JSON, CSV)
//! ```
//!
//! The mesh type is [`geometry::Mesh<D>`]: `D = 2` is a set of closed polygons in the
//! plane (elements are segments, two vertices each), `D = 3` a closed oriented
//! triangle surface in space (elements are triangles, three vertices each). In both
//! cases an element has `D` vertices, which lets the assembly and the flow be written
//! once for both dimensions.

pub mod bulk;
pub mod export;
pub mod fem;
pub mod flow;
pub mod formats;
pub mod geometry;
pub mod imaging;
pub mod jobs;
pub mod limits;
pub mod linalg;
pub mod problems;
pub mod service;

/// The number of threads this machine runs at once (1 if it cannot be told), read
/// once: the work that splits over cores asks on hot paths.
pub fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Keep freed memory in the process instead of returning it to the kernel at once
/// (glibc on Linux; elsewhere a no-op). A flow step allocates and frees vectors of
/// a few hundred KiB (positions, loops, hash tables); by default glibc serves
/// blocks above 128 KiB with fresh `mmap`s whose zero-filled pages fault in on
/// every use, which measured up to half of the time of a curve management pass at
/// 10k vertices. Blocks below 32 MiB now come from the heap, and up to 64 MiB of
/// free heap is kept. Called once at start by the binary and the benches.
pub fn tune_allocator() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes allocator parameters; called before any thread
    // allocates concurrently (at the start of main), with valid parameter codes.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20);
    }
}
