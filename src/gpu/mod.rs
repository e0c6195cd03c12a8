//! A small, explicit Vulkan layer on `ash` and `gpu-allocator`: a context (instance,
//! device, queue, allocator, validation messages), buffers that own their memory,
//! compute pipelines built from the SPIR-V that `build.rs` compiles out of `glsl/`,
//! and one-shot command submission. Nothing here knows about sampling.

pub mod buffer;
pub mod context;
pub(crate) mod fault;
pub mod layout;
pub mod optimizer;
pub mod pipeline;
pub mod sort;
pub mod timer;
pub mod shaders {
    //! SPIR-V of every `glsl/*.comp`, compiled by `build.rs`.
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

use ash::vk;

use crate::error::Error;

/// Maps a failed Vulkan call to the crate's error, naming the call.
pub(crate) fn check<T>(call: &'static str, result: Result<T, vk::Result>) -> Result<T, Error> {
    result.map_err(|result| Error::Vulkan { call, result })
}
