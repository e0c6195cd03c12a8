//! One error type for the whole crate.

use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
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
    #[error("Vulkan: {call} failed: {result}")]
    Vulkan { call: &'static str, result: ash::vk::Result },
    /// No usable Vulkan (no loader, no device, missing feature).
    #[error("Vulkan unavailable: {0}")]
    VulkanUnavailable(String),
    #[error("GPU memory: {0}")]
    Allocation(#[from] gpu_allocator::AllocationError),
    #[error("interrupted")]
    Interrupted,
}

impl Error {
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
