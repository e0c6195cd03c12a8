//! One error type for the whole crate.

use std::path::PathBuf;

/// The crate's result type, with [`Error`] as its default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What can go wrong in any fsot call.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter or input that the user can fix.
    #[error("{0}")]
    Invalid(String),
    /// A file (a mask, a scene or a checkpoint) that cannot be used.
    #[error("{path}: {reason}")]
    BadFile {
        /// The file.
        path: PathBuf,
        /// Why it cannot be used, in words.
        reason: String,
    },
    /// A file or folder operation failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done, in words (the path and the operation).
        context: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A Vulkan call or a GPU allocation failed.
    #[error(transparent)]
    #[cfg(feature = "vulkan")]
    Vulkan(crate::vk::Error),
    /// No usable Vulkan (no loader, no device, missing feature).
    #[error("Vulkan unavailable: {0}")]
    VulkanUnavailable(String),
    /// A checkpoint is in the way of a run that does not resume it.
    #[error("checkpoint {} exists: continue it, or remove it to start over", .0.display())]
    CheckpointExists(PathBuf),
    /// The work was cancelled before it finished.
    #[error("interrupted")]
    Interrupted,
}

#[cfg(feature = "vulkan")]
impl From<crate::vk::Error> for Error {
    fn from(e: crate::vk::Error) -> Self {
        match e {
            crate::vk::Error::Invalid(msg) => Error::Invalid(msg),
            crate::vk::Error::VulkanUnavailable(msg) => Error::VulkanUnavailable(msg),
            e => Error::Vulkan(e),
        }
    }
}

impl Error {
    /// The GPU failed in a way the CPU path does not share: worth a fall-back.
    pub fn is_device_failure(&self) -> bool {
        #[cfg(feature = "vulkan")]
        if matches!(self, Error::Vulkan(_)) {
            return true;
        }
        matches!(self, Error::VulkanUnavailable(_))
    }

    /// An `Invalid` error with this message.
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
    /// A `BadFile` error: the file at `path` cannot be used, for `reason`.
    pub fn bad_file(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::BadFile { path: path.into(), reason: reason.into() }
    }
    /// An `Io` error: `source` happened while doing `context`.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io { context: context.into(), source }
    }
}

impl Error {
    /// Out of GPU memory (an allocation, or a Vulkan call that said so).
    pub fn is_out_of_device_memory(&self) -> bool {
        #[cfg(feature = "vulkan")]
        return matches!(self, Error::Vulkan(e) if e.is_out_of_device_memory());
        #[cfg(not(feature = "vulkan"))]
        false
    }
}
