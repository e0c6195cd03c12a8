//! The Vulkan layer's error. fsot's own error takes it by `From`: a bad
//! argument becomes `fsot::Error::Invalid`, a missing capability
//! `VulkanUnavailable`, a failed call or allocation `Vulkan`.

use ash::vk;

/// The result of the Vulkan layer's calls.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What went wrong in the Vulkan layer.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An argument the caller can fix (a size, a format, a capacity).
    #[error("{0}")]
    Invalid(String),
    /// A Vulkan call failed; `call` names it.
    #[error("Vulkan: {call} failed: {result}{}", hint(*.result))]
    Vulkan {
        /// The call, as Vulkan names it.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
    /// No usable Vulkan (no loader, no device, a missing feature).
    #[error("Vulkan unavailable: {0}")]
    VulkanUnavailable(String),
    /// The allocator could not place a buffer or an image.
    #[error("GPU memory: {0} (a smaller tile may fit)")]
    Allocation(#[from] gpu_allocator::AllocationError),
}

impl Error {
    /// A bad argument, in words.
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }

    /// Out of GPU memory (an allocation, or a Vulkan call that said so).
    pub fn is_out_of_device_memory(&self) -> bool {
        matches!(self, Error::Allocation(_))
            || matches!(self, Error::Vulkan { result, .. } if *result == vk::Result::ERROR_OUT_OF_DEVICE_MEMORY)
    }
}

/// What a Vulkan result means for the user.
fn hint(result: vk::Result) -> &'static str {
    use vk::Result as R;
    match result {
        R::ERROR_DEVICE_LOST => {
            " (the GPU was lost: a driver reset, a hang or a removed device; nothing was written)"
        }
        R::ERROR_OUT_OF_DEVICE_MEMORY => " (out of GPU memory: a smaller tile may fit)",
        R::ERROR_OUT_OF_HOST_MEMORY => " (out of host memory)",
        _ => "",
    }
}
