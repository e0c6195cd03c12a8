//! A small, explicit Vulkan compute layer on `ash` and `gpu-allocator` that knows
//! nothing of sampling; a renderer can share it (`Context::wrap` works on the
//! host's own device).
//!
//! - `instance`: the process's instance (one per validation setting, kept for
//!   the process's life) and the validation layer's messages, per context;
//! - `device`: device choice and what fsot reads of a device (`DeviceInfo`);
//! - `context`: a device, its compute queue (submission guarded by a lock) and
//!   its memory allocator, made here or wrapped around a host's device;
//! - `commands`: submission through one persistent command pool and fence per
//!   context, and the barrier and copy helpers;
//! - `buffer`: buffers that own their memory, with one upload and one download
//!   path through staging, and fills of a host's buffer;
//! - `texel_view`: a buffer viewed as texels of one format (texel buffers);
//! - `image`: 2-D array images (owned, or a host's described by `ImageTarget`)
//!   filled and read back through staging with their layout transitions, and a
//!   nearest sampler;
//! - `pipeline`: compute pipelines with their descriptor sets;
//! - `timer`: timestamp queries;
//! - `sort`: a reusable radix sort of 32-bit keys with 32-bit payloads;
//! - `sort_choice`: its path chosen at run time, timed on the device;
//! - `requirements`: the features and extensions a host's device must enable.
//!
//! Every handle is destroyed in `Drop` and holds the context alive. Errors are
//! this layer's own `vk::Error` (fsot's `Error` converts from it); `FSOT_FAULT`
//! injects failures for tests (`fault`). Nothing here imports the rest of fsot.

internal! {
    mod buffer;
    mod commands;
    mod sort;
}
pub(crate) mod context;
pub(crate) mod device;
mod error;
pub(crate) mod fault;
pub(crate) mod image;
pub(crate) mod instance;
pub(crate) mod pipeline;
mod requirements;
pub(crate) mod sort_choice;
pub(crate) mod texel_view;
pub(crate) mod timer;

pub use buffer::{Buffer, BufferTarget, Location};
pub use commands::Recording;
pub use context::{Context, ContextOptions, ExternalDevice};
pub use device::DeviceInfo;
pub use error::{Error, Result};
pub use image::{texel_bytes_of, Image, ImageDesc, ImageTarget, Sampler};
internal!(use pipeline::{ComputeDesc, ComputePipeline});
pub use requirements::{missing, requirements, Requirement, API_VERSION};
internal!(use sort::SortPath);
pub use sort::{DeviceCount, RadixSort, SortCount};
internal!(use sort_choice::{choose_sort_path, time_sort_paths, PathChoice, PathTimes});
internal!(use texel_view::TexelView);
internal!(use timer::Timer);

internal! {
    mod shaders {
        //! SPIR-V of `glsl/sort/*.comp`, embedded from `spirv/sort/`.
        spirv_module!("sort");
    }
}

use ash::vk;

/// Maps a failed Vulkan call to the crate's error, naming the call.
pub(crate) fn check<T>(call: &'static str, result: std::result::Result<T, vk::Result>) -> Result<T> {
    result.map_err(|result| Error::Vulkan { call, result })
}
