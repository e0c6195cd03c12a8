//! fsot makes sample masks for Monte Carlo rendering at one sample per pixel:
//! a tile of W x H pixels x T frames (wrapping) whose per-pixel samples are
//! optimized by filtered sliced optimal transport under a spatio-temporal
//! kernel (the eye's filter, and the display's temporal antialiasing), so that
//! the error a renderer leaves is noise the eye barely sees.
//!
//! It runs on the CPU and, with the default `vulkan` feature, on Vulkan compute
//! (on its own device, or on the host renderer's). Without that feature the
//! crate has no Vulkan dependency at all.
//!
//! # A mask on the CPU
//!
//! ```
//! use fsot::{KernelSpec, Settings, Tile};
//!
//! // 16 x 16 pixels, 4 frames, 1 sample of 2 dimensions per pixel.
//! let tile = Tile::new(16, 16, 4, 1, 2)?;
//! let mut settings = Settings::new(KernelSpec::named("perceptual-taa")?, 7);
//! settings.iterations = 50;
//! let mask = fsot::optimize(tile, settings, None)?;
//! assert_eq!(mask.samples.len(), 16 * 16 * 4 * 2);
//! assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
//! # Ok::<(), fsot::Error>(())
//! ```
//!
//! # A scene's plan
//!
//! A scene names its display and its sampling decisions; the plan says which
//! masks it needs (tile, kernel, reading) and why.
//!
//! ```
//! use fsot::{CostModel, Plan, Scene};
//!
//! let scene = Scene::parse(
//!     r#"
//! [display]
//! name = "standard_fhd"
//! fps = 60
//! taa_alpha = 0.1
//!
//! [[group]]
//! name = "light"
//! dims = 2
//! "#,
//!     "example",
//! )
//! .map_err(fsot::Error::invalid)?;
//! let plan = Plan::new(&scene, &CostModel::unmeasured())?;
//! assert!(!plan.masks.is_empty());
//! for mask in &plan.masks {
//!     println!("{}: d = {}, {} spp", mask.file, mask.dims, mask.spp);
//! }
//! # Ok::<(), fsot::Error>(())
//! ```
//!
//! # Into a host renderer's image
//!
//! A renderer hands fsot its device and an image it created; fsot optimizes on
//! that device and writes the mask's frames into the image's layers.
//!
//! ```no_run
//! # #[cfg(feature = "vulkan")]
//! # fn host(external: fsot::vk::ExternalDevice, image: fsot::ash::vk::Image) -> fsot::Result<()> {
//! use fsot::ash::vk;
//! use fsot::vk::{Context, ImageTarget};
//! use fsot::{CancelFlag, KernelSpec, Settings, Tile};
//!
//! // SAFETY: `external` is the renderer's live instance, device and queue, made
//! // with the features it claims, alive until `ctx` is dropped.
//! let ctx = unsafe { Context::wrap(external) }?;
//! let tile = Tile::new(64, 64, 32, 1, 2)?;
//! let target = ImageTarget {
//!     image,
//!     format: vk::Format::R8G8_UNORM,
//!     width: 64,
//!     height: 64,
//!     layers: 32,
//!     usage: vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED,
//!     layout_before: vk::ImageLayout::UNDEFINED,
//!     layout_after: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
//! };
//! let settings = Settings::new(KernelSpec::named("perceptual-taa")?, 1);
//! // SAFETY: `image` is the renderer's, made as `target` states, used by nothing
//! // else until the call returns.
//! let mask =
//!     unsafe { fsot::make_into_image(&ctx, tile, settings, &target, &CancelFlag::new(), &mut |_| {}) }?;
//! # let _ = mask;
//! # Ok(())
//! # }
//! ```
//!
//! # Features
//!
//! - `vulkan` (default): the Vulkan backend, `vk` (a small Vulkan layer that
//!   knows nothing of sampling) and the renderer's calls.
//! - `build-shaders`: compile `glsl/` with shaderc at build time instead of
//!   embedding the committed SPIR-V (needs shaderc's libraries, or cmake and a
//!   C++ compiler to build them).
//! - `internals`: makes the modules behind the items above public, for fsot's
//!   own command line and tests. They carry no stability promise; without the
//!   feature they are private to the crate.
//!
//! # On the web
//!
//! With default features off, the CPU path builds for wasm32-unknown-unknown and
//! runs there on one thread. That target has no clock: a run takes a number of
//! iterations (`Settings::iterations`), a time budget is refused with its reason,
//! and reported times read 0. Nothing is written to files there: a mask goes to
//! the page as bytes (`Mask::ktx2`) or as its samples, and a scene's plan as the
//! includes read it (`SamplerPlan::make`: the stacked texels and the plan block).
//! `examples/web-host` makes the 64x64x32 RG mask in the page.
#![warn(missing_docs)]
#![warn(unnameable_types)]

/// The bytes of one embedded SPIR-V file: committed under `spirv/` (made from
/// `glsl/` by `scripts/spirv.sh`), or compiled into OUT_DIR at build time with
/// the `build-shaders` feature.
#[cfg(all(feature = "vulkan", not(feature = "build-shaders")))]
macro_rules! spirv {
    ($file:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/spirv/", $file))
    };
}
#[cfg(all(feature = "vulkan", feature = "build-shaders"))]
macro_rules! spirv {
    ($file:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/spirv/", $file))
    };
}
/// One shader family's constants (`spirv/FAMILY.rs`, or OUT_DIR's with `build-shaders`).
#[cfg(all(feature = "vulkan", not(feature = "build-shaders")))]
macro_rules! spirv_module {
    ($family:literal) => {
        include!(concat!(env!("CARGO_MANIFEST_DIR"), "/spirv/", $family, ".rs"));
    };
}
#[cfg(all(feature = "vulkan", feature = "build-shaders"))]
macro_rules! spirv_module {
    ($family:literal) => {
        include!(concat!(env!("OUT_DIR"), "/spirv/", $family, ".rs"));
    };
}

/// Declares modules (and re-exports) that are public to fsot's own command line
/// and tests, with the `internals` feature, and private to the crate otherwise:
/// a renderer that depends on fsot sees the items re-exported below and `vk`.
macro_rules! internal {
    ($(mod $name:ident;)*) => {$(
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $name;
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        pub(crate) mod $name;
    )*};
    (mod $name:ident { $($body:tt)* }) => {
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $name { $($body)* }
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        pub(crate) mod $name { $($body)* }
    };
    ($(#[$meta:meta])* fn $($rest:tt)*) => {
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        $(#[$meta])*
        pub fn $($rest)*
        #[cfg(not(feature = "internals"))]
        $(#[$meta])*
        pub(crate) fn $($rest)*
    };
    (use $($tree:tt)*) => {
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub use $($tree)*;
        #[cfg(not(feature = "internals"))]
        #[allow(unused_imports)]
        pub(crate) use $($tree)*;
    };
}

/// The README's Rust code blocks, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeCodeBlocks;
/// The Vulkan guide's Rust code blocks, compiled as doctests.
#[cfg(doctest)]
#[doc = include_str!("../docs/vulkan.md")]
pub struct VulkanGuideCodeBlocks;
/// The architecture's Rust code blocks, compiled as doctests.
#[cfg(doctest)]
#[doc = include_str!("../ARCHITECTURE.md")]
pub struct ArchitectureCodeBlocks;

internal! {
    mod core;
    mod error;
    mod io;
    mod optimize;
    mod peers;
    mod quality;
    mod render;
    mod scene;
}
#[cfg(feature = "vulkan")]
pub mod vk;

pub use crate::core::kernel::{KernelSpec, Spatial, Temporal};
pub use crate::core::mask::Mask;
pub use crate::core::objective::Score;
pub use crate::core::step_rule::{Plateau, StepRule};
pub use crate::core::tile::{Tile, MAX_DIMS, MAX_SPP};
pub use error::{Error, Result};
pub use io::ktx2::Format as TexelFormat;
pub use optimize::backend::{BackendChoice, BackendKind, Profile, Report};
pub use optimize::run::{optimize, CancelFlag, Checkpointing, Event, Outcome, Run, RunOptions, SetUp};
pub use optimize::settings::{
    Settings, Start, Until, COARSE_BUDGET_SHARE, DEFAULT_HITS, DEFAULT_ITERATIONS, SPATIAL_BUDGET_SHARE,
    SPATIAL_ITERATIONS,
};
pub use render::sampler::{SamplerPart, SamplerPlan};
pub use scene::file::{Display as SceneDisplay, Group as SceneGroup, Reading, Scene};
pub use scene::plan::{
    CostModel, Made as MadeMask, Part as PlannedPart, Plan, PlanEvent, PlannedGroup, PlannedMask,
};

#[cfg(feature = "vulkan")]
pub use ash;
#[cfg(feature = "vulkan")]
pub use optimize::vulkan::VulkanOptions;
#[cfg(feature = "vulkan")]
pub use render::device::{
    layers_for, make_into_image, make_plan_into_image, upload, vk_format, write_mask, write_mask_to_buffer,
    write_plan, write_plan_block, write_plan_block_for,
};
