//! bounce-graph: the pass graph and the render passes of bounce.
//!
//! Start reading at [`frame::build_frame`], the frame recipe: gbuffer → dprsm → direct → the VPL passes,
//! with typed handles flowing between the calls. [`graph`] is the executor (declared reads and writes,
//! derived barriers, labels, timestamps, culling; it depends on the device crate only). The scene
//! (loading, camera, CPU BVH, grid) is `bounce_scene`'s; [`gpu_scene`] and [`gpu_bvh`] upload it once.
//! The tests' references (the CPU renderer and twins) are in `tests/oracles`, not here. Shaders are
//! compiled at build time from `glsl/` (see `build.rs`); binding numbers and shared structs come from
//! `glsl/shared/` and are mirrored in `bounce_scene::bindings` and [`shader_types`].

pub mod frame;
pub mod gpu_bvh;
pub mod gpu_scene;
pub mod graph;
pub mod passes;
pub mod pipelines;
pub mod shader_types;

// The scene crate's modules under the names the passes use.
pub use bounce_scene::{bindings, bvh, camera, scene};

/// SPIR-V of every row of build.rs's `SHADERS` table (shaders and their variants), as bytes; see [`spirv`].
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// SPIR-V bytes → words (the bytes of `include_bytes!` carry no alignment guarantee).
pub fn spirv(bytes: &[u8]) -> Vec<u32> {
    assert_eq!(bytes.len() % 4, 0, "SPIR-V is a whole number of words");
    bytes.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
}
