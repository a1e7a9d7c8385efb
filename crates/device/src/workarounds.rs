//! Driver workarounds, in one place, each with its reason (as wgpu keeps its own). The renderer asks
//! [`Gpu`](crate::Gpu) for the facts below; no other code tests a driver's identity.
//!
//! | driver | what it does | what bounce does |
//! |---|---|---|
//! | Mesa llvmpipe (lavapipe) | stops every loop of an invocation after 65,535 iterations *in total*, silently (`LP_MAX_TGSI_LOOP_ITERATIONS`): a long gather would return a truncated sum, not an error | [`loop_iteration_limit`] is `Some(65535)`; every pass whose invocations loop long (gather, mis, ris, the reference, gbg's importance rays, voxelize) splits its work into dispatches that stay under it (`Renderer::vpls_per_dispatch` and its kin) |
//! | Mesa llvmpipe (lavapipe) | compiles a shader variant per image-size class (power of two or not) at its first dispatch, and times it inside that dispatch | `Renderer::warm_up` renders an untimed small frame whose sizes keep the frame's classes, so timed frames measure the frame, not the compiler |
//!
//! Performance choices made on lavapipe's costs (texel buffers instead of storage buffers for data read
//! with a per-lane index, shadow rays from a queue, loops that unroll to constant indices) are not
//! workarounds: they are correct everywhere, and BENCHMARKS.md gives each one's measurement.

use ash::vk;

/// The most loop iterations one invocation may run in total on this driver, or `None` where there is no
/// such limit (the table above).
pub fn loop_iteration_limit(driver: vk::DriverId) -> Option<u32> {
    (driver == vk::DriverId::MESA_LLVMPIPE).then_some(65535)
}
