//! The renderer's side: the sampler plan a shader reads (`sampler`), and, with
//! Vulkan, masks written into a host's images and buffers (`device`).
#[cfg(feature = "vulkan")]
pub mod device;
pub mod sampler;
