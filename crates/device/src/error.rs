//! Small typed errors: only what a caller cannot prevent. Each Vulkan failure names the call.

use ash::vk;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}; install the package `libvulkan1`")]
    Loader(String),
    #[error("no Vulkan device found{0}; install `mesa-vulkan-drivers` for the CPU device (lavapipe) or a GPU driver")]
    NoDevice(String),
    #[error("no Vulkan device matches `{wanted}`; available: {available}")]
    NoMatchingDevice { wanted: String, available: String },
    #[error("Vulkan device `{device}` lacks {what}{hint}")]
    MissingFeature { device: String, what: String, hint: String },
    #[error("the validation layer VK_LAYER_KHRONOS_validation is not installed; install the package `vulkan-validationlayers`")]
    NoValidationLayer,
    #[error("{call} failed: {result:?}")]
    Vk { call: &'static str, result: vk::Result },
    #[error("allocating `{name}`: {source}")]
    Alloc { name: String, source: gpu_allocator::AllocationError },
    #[error("{what} exceeds the device limit {limit} ({value} > {max})")]
    Limit { what: String, limit: &'static str, value: u64, max: u64 },
    #[error("the window has no area to present to (its surface reports 0×0)")]
    NoWindowArea,
}

/// Attach the Vulkan call's name to a failing `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vk { call, result })
    }
}
