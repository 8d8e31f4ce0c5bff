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
pub mod film;
pub mod flow;
pub mod geometry;
pub mod imaging;
pub mod jobs;
pub mod problems;
pub mod service;
