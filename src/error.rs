//! One error type for the whole crate.

use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter or input that the user can fix.
    #[error("{0}")]
    Invalid(String),
    /// A mask file that cannot be used.
    #[error("{path}: {reason}")]
    BadFile { path: PathBuf, reason: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
    /// A Vulkan call failed; `call` names it.
    #[error("Vulkan: {call} failed: {result}{}", vulkan_hint(*.result))]
    #[cfg(feature = "vulkan")]
    Vulkan { call: &'static str, result: ash::vk::Result },
    /// No usable Vulkan (no loader, no device, missing feature).
    #[error("Vulkan unavailable: {0}")]
    VulkanUnavailable(String),
    #[error("GPU memory: {0} (a smaller tile may fit)")]
    #[cfg(feature = "vulkan")]
    Allocation(#[from] gpu_allocator::AllocationError),
    /// A checkpoint is in the way of a run that does not resume it.
    #[error("checkpoint {} exists: continue it, or remove it to start over", .0.display())]
    CheckpointExists(PathBuf),
    #[error("interrupted")]
    Interrupted,
}

/// What a Vulkan result means for the user.
#[cfg(feature = "vulkan")]
fn vulkan_hint(result: ash::vk::Result) -> &'static str {
    use ash::vk::Result as R;
    match result {
        R::ERROR_DEVICE_LOST => {
            " (the GPU was lost: a driver reset, a hang or a removed device; nothing was written)"
        }
        R::ERROR_OUT_OF_DEVICE_MEMORY => " (out of GPU memory: a smaller tile may fit)",
        R::ERROR_OUT_OF_HOST_MEMORY => " (out of host memory)",
        _ => "",
    }
}

impl Error {
    /// The GPU failed in a way the CPU path does not share: worth a fall-back.
    pub fn is_device_failure(&self) -> bool {
        #[cfg(feature = "vulkan")]
        if matches!(self, Error::Vulkan { .. } | Error::Allocation(_)) {
            return true;
        }
        matches!(self, Error::VulkanUnavailable(_))
    }

    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
    pub fn bad_file(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::BadFile { path: path.into(), reason: reason.into() }
    }
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io { context: context.into(), source }
    }
}

impl Error {
    /// Out of GPU memory (an allocation, or a Vulkan call that said so).
    pub fn is_out_of_device_memory(&self) -> bool {
        #[cfg(feature = "vulkan")]
        return matches!(self, Error::Allocation(_))
            || matches!(self, Error::Vulkan { result, .. } if *result == ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY);
        #[cfg(not(feature = "vulkan"))]
        false
    }
}
