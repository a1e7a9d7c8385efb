//! bounce-device: the Vulkan device and memory layer of bounce.
//!
//! It owns the instance, the validation-message collector, the chosen physical device, the logical device
//! with its one queue, the memory allocator, buffers and images, pipelines, one-shot command submission and
//! GPU timestamp queries. It knows nothing about passes or scenes.
//!
//! Contracts (everything here is explicit; convenience lives in `bounce-graph`):
//! 1. **No automatic synchronisation.** Nothing here inserts a barrier on the caller's behalf, except the
//!    upload/readback helpers, which document the state they leave a resource in. Every barrier is
//!    planned by [`sync::plan`] from one table, [`sync::Access`] → (stage, access, layout), and recorded
//!    by [`sync::transition`]: by the graph for its passes, here for readbacks and presentation.
//! 2. **Ownership and lifetime.** [`Buffer`], [`Image`] and pipelines hold a [`Gpu`] clone and destroy
//!    themselves on drop, *immediately*. Drop a resource only when the GPU no longer uses it: every
//!    submission here waits for its fence before returning, so after [`Gpu::submit`] everything it used may
//!    be dropped. The device itself is destroyed when the last clone of [`Gpu`] (held by every
//!    resource) goes: wait idle → allocator → device → debug messenger → instance. A panic while
//!    recording (a contract violation caught by a debug assertion) poisons no lock for good: the
//!    device still tears down cleanly.
//! 3. **Validation messages are collected per device**, through the messenger's user-data pointer, never in
//!    a process global: tests run as threads of one process, each with its own [`Gpu`] and
//!    [`ValidationLog`].
//! 4. **Errors**: [`Error`] covers what a caller cannot prevent (no device, missing feature, out of memory,
//!    device lost, any failing Vulkan call, named). Contract violations are bugs and panic.

#![warn(clippy::undocumented_unsafe_blocks)]

mod command;
mod error;
mod gpu;
mod memory;
mod pipeline;
mod swapchain;
pub mod sync;
mod timestamps;
pub mod workarounds;

pub use ash::vk;
pub use command::DescriptorWrites;
pub use error::{Error, Result};
pub use gpu::{DeviceInfo, Gpu, GpuOptions, ValidationLog};
pub use gpu_allocator::MemoryLocation;
pub use memory::{is_depth_format, texel_size, Buffer, BufferDesc, Image, ImageDesc, Sampler, TexelBuffer};
pub use pipeline::{Binding, ComputePipeline, GraphicsPipeline, GraphicsPipelineDesc};
pub use swapchain::{Presented, Swapchain};
pub use timestamps::TimestampPool;
