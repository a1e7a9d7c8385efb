//! The BVH: the scene's triangles in a bounding volume hierarchy, built once per scene on the CPU and
//! ray cast on the GPU (`glsl/shared/bvh.glsl`; the graph crate's `gpu_bvh` uploads it) and on the CPU.
//!
//! - [`build`]: the binned-SAH build in f64 ([`Bvh`]). The CPU reference of the tests
//!   (`bounce-oracles`) casts its rays through this same tree.
//! - `optimize`: the built tree's subtrees moved where they cost less (insertion-based optimization).
//! - [`flat`]: the GPU layout (32-byte nodes, 48-byte leaf-ordered triangles), the flattening under the
//!   traversal's stack limit ([`FlatBvh`]), and the constants the shaders share.
//! - [`quant`]: the child box packed into a threaded box record, so one step of the walk tests two boxes.
//! - [`query`]: closest hit and occlusion on the CPU over the flattened tree, for the host's decisions.

pub mod build;
pub mod flat;
mod optimize;
pub mod quant;
pub mod query;

pub use build::{Bvh, BvhNode, BvhTri, MEDIAN_DEPTH};
pub use flat::{
    FlatBvh, GpuBvhNode, GpuBvhTri, GpuThreadRec, B_BVH_NODES, B_BVH_THREADED, B_BVH_TRIS, MAX_STEPS, NO_TRI,
    SHADOW_EPS, STACK_SIZE, THREAD_TRI, THREAD_UNROLL,
};

/// Test-only: a deterministic xorshift stream of numbers in [0, 1) from `seed` (the unit tests' random
/// boxes and triangles).
#[cfg(test)]
pub(crate) fn test_uniforms(mut seed: u64) -> impl FnMut() -> f32 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    }
}
