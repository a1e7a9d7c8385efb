//! Driver workarounds, in one place, each with its reason (as wgpu keeps its own). The renderer asks
//! [`Gpu`](crate::Gpu) for the facts below; no other code tests a driver's identity.
//!
//! | driver | what it does | what bounce does |
//! |---|---|---|
//! | Mesa llvmpipe (lavapipe) | stops every loop of an invocation after 65,535 iterations *in total*, silently (`LP_MAX_TGSI_LOOP_ITERATIONS`): a long gather would return a truncated sum, not an error | [`loop_iteration_limit`] is `Some(65535)`; every pass whose invocations loop long (gather, mis, ris, the reference, gbg's importance rays, voxelize) splits its work into dispatches that stay under it (`Renderer::vpls_per_dispatch` and its kin) |
//! | Mesa llvmpipe (lavapipe) | compiles a shader variant per image-size class (power of two or not) at its first dispatch, and times it inside that dispatch | `Renderer::warm_up` renders an untimed small frame whose sizes keep the frame's classes, so timed frames measure the frame, not the compiler |
//! | Mesa llvmpipe (lavapipe) | takes a timestamp's time when a later flush runs the rasterizer's queue it was put in (the next timestamp's write flushes), while a compute dispatch runs at once: some compute passes read about 0 ms with their time in the next pass or nowhere, and a frame could lose most of its total (Sibenik, a light moving, 512² maps: 77 ms by the timestamps against 1.24 s a frame by the wall clock; its VPL end balls, 726 ms, read 0.03) | [`timestamp_needs_flush`] is true; [`TimestampPool::write`](crate::TimestampPool::write) writes a second, unread timestamp right after each one, whose write flushes the first into place |
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

/// Whether a timestamp written on this driver takes its time at the next flush of its queue rather than
/// when the command stream reaches it (the table above).
pub fn timestamp_needs_flush(driver: vk::DriverId) -> bool {
    driver == vk::DriverId::MESA_LLVMPIPE
}
