//! The engine's tests, from the library's API and the CLI's job runner: convergence
//! orders and conserved quantities (numerics), mesh management and pinch-off,
//! segmentation of generated and real images, shape design, the stressed film,
//! validation of inputs, and the glTF results. One test binary: each binary
//! compiles the library's generic code again at opt-level 2 (about a minute of CI's
//! build for each), and the film's long tests, which start first (film/mod.rs),
//! leave the second core to the others.

#[path = "../common/mod.rs"]
mod common;
mod contact;
mod dumbbell;
mod film;
mod gltf_results;
mod mesh_management;
mod numerics;
mod pinch_off;
mod real_images;
mod segmentation;
mod shape_design;
mod validation;
