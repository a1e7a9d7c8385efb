//! bounce-oracles: the independent references the tests judge the renderer by. None of it runs in a
//! frame; the renderer (`bounce-graph`) does not depend on it, and it depends on the scene crate alone.
//!
//! - [`cpu_ref`]: the exact CPU reference renderer (f64 ray casting over the renderer's SAH tree,
//!   [`bounce_scene::bvh::Bvh`]): direct light per pixel, with the edge classification the per-pixel
//!   comparisons need, and a Monte Carlo one-bounce reference. `tests/src/bin/make_references.rs`
//!   renders the committed reference images with it.
//! - [`cpu_voxel`]: the CPU twin of the voxelizer and the voxel march (same f32 operations in the same
//!   order, so the results are bit-identical).
//! - [`cpu_threaded`]: the CPU twin of the shadow rays' stackless walk over the threaded BVH.
//! - [`cpu_end_balls`]: the CPU twin of the shadow rays' end-ball radii.
//! - [`cpu_cdf`]: the CPU twin of `cdf_reduce` and of the CDF sampling (same f32 operations).
//! - [`cpu_sobol`]: the CPU twin of the stratified sample points (Owen-scrambled Sobol).
//! - [`scene_fuzz`]: the scene loader's robustness contract as one function, shared by the fuzz target
//!   (`tests/fuzz`) and the corpus replay test.
//!
//! Users: the integration tests (`tests/tests`), the tools in `tests/src/bin`, and the fuzz target.

pub mod cpu_cdf;
pub mod cpu_end_balls;
pub mod cpu_ref;
pub mod cpu_segment;
pub mod cpu_sobol;
pub mod cpu_threaded;
pub mod cpu_voxel;
pub mod scene_fuzz;
