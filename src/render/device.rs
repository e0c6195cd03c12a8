//! Masks straight into a renderer's own Vulkan memory: on a context wrapped
//! around the renderer's device and queue (`vk::Context::wrap`, with the
//! renderer's queue lock), fsot writes a mask, or a plan's masks stacked, into
//! the renderer's 2-D array image (`write_mask`, `write_plan`), the include's
//! plan block into its uniform buffer (`write_plan_block`), or a mask's texels
//! into a buffer (`write_mask_to_buffer`); `make_into_image` and
//! `make_plan_into_image` first make the mask, or a scene plan's masks, on that
//! device (the Vulkan optimizer), `upload` takes a mask file or a plan folder
//! made earlier (no optimization).
//!
//! The image: a 2-D array of the tile's width and height, one layer per frame
//! and sample of each mask (`layers_for`: masks x T x spp, mask m from layer
//! m T spp, `glsl/include/fsot.glsl`'s layout), in one of the KTX2 formats
//! (`io::ktx2::Format`: r8/r16 UNORM or r32 float, 1, 2 or 4 channels, at least
//! the masks' d), created with TRANSFER_DST usage (and SAMPLED to read it).
//! UNORM texels are round(v (2^b - 1)), as in the KTX2 files. Everything is
//! checked before any GPU work: the format, the extent, the layer count, the
//! usage (a clear error, nothing written).
//!
//! Synchronisation (`vk::image`): one submission on the wrapped queue under the
//! queue lock, waited for before the call returns; a barrier orders the copy
//! after every earlier command on the queue and the image moves from
//! `layout_before` (UNDEFINED is fine: every texel is written) to
//! TRANSFER_DST_OPTIMAL; after the copy a barrier makes it available to every
//! later command on the queue and moves it to `layout_after`
//! (SHADER_READ_ONLY_OPTIMAL to sample it). No queue family ownership transfer:
//! the image must be usable on the wrapped queue's family. fsot never destroys
//! what it did not create: the image, the buffer, the device and the queue stay
//! the renderer's.
//!
//! # Safety
//!
//! Every function here that takes an `ImageTarget` or a `BufferTarget` is
//! `unsafe`: Vulkan cannot be asked how an image or a buffer was made, so fsot
//! checks what the target states but cannot check the statement. The caller
//! promises that the target's image (buffer) is alive with its memory bound,
//! belongs to the context's device, was created with the format, width, height,
//! layer count (size) and usage the target states, is in `layout_before` in
//! every layer (an image), can be used on the context's queue family, and is
//! used by no other work until the call returns (the host's own submissions to
//! the queue take the queue lock). An image is also a plain 2-D array image: one
//! sample per texel, OPTIMAL tiling. Only its mip level 0 is written and moved
//! to `layout_after`; any other level keeps its layout and contents.

use std::path::Path;

use ash::vk;

use crate::core::mask::Mask;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::io::ktx2::Format;
use crate::optimize::backend::BackendChoice;
use crate::optimize::run::{CancelFlag, Event, Outcome, Run, RunOptions};
use crate::optimize::settings::Settings;
use crate::optimize::vulkan::VulkanOptions;
use crate::optimize::clock::Stamp;
use crate::render::sampler::{plan_masks, SamplerPlan};
use crate::scene::plan::{Plan, PlanEvent};
use crate::vk::buffer::fill_buffer;
use crate::vk::image::{check_copy, fill};
use crate::vk::{BufferTarget, Context, ImageTarget};

/// The KTX2 format of a Vulkan format, if it is one fsot writes.
pub fn format_of(format: vk::Format) -> Result<Format> {
    Format::ALL.into_iter().find(|f| f.vk_format() == format.as_raw() as u32).ok_or_else(|| {
        let names: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
        Error::invalid(format!("fsot cannot write {format:?} images; the formats: {}", names.join(", ")))
    })
}

/// The Vulkan format of a KTX2 format.
pub fn vk_format(format: Format) -> vk::Format {
    vk::Format::from_raw(format.vk_format() as i32)
}

/// Layers the image of `masks` masks of tile `tile` needs; `u32::MAX` where
/// the count does not fit in 32 bits (no device makes such an image, and
/// fsot's writes refuse it).
pub fn layers_for(tile: &Tile, masks: usize) -> u32 {
    layers_needed(tile, masks).unwrap_or(u32::MAX)
}

fn layers_needed(tile: &Tile, masks: usize) -> Option<u32> {
    masks.checked_mul(tile.frames)?.checked_mul(tile.spp)?.try_into().ok()
}

/// What an image must be to hold `masks` masks of `tile`: the format's
/// channels, the extent, the layer count and the usage, checked against the
/// target and the device (before any GPU work).
fn check_image(ctx: &Context, image: &ImageTarget, tile: &Tile, masks: usize, dims: usize) -> Result<Format> {
    let format = format_of(image.format)?;
    format.check_holds(dims)?;
    if (image.width, image.height) != (tile.width as u32, tile.height as u32) {
        return Err(Error::invalid(format!(
            "the image is {}x{}, the mask's tile {}x{}",
            image.width, image.height, tile.width, tile.height
        )));
    }
    let layers = layers_needed(tile, masks).ok_or_else(|| {
        Error::invalid(format!(
            "{masks} masks of {} frames x {} spp need more than 2^32 layers",
            tile.frames, tile.spp
        ))
    })?;
    if image.layers != layers {
        return Err(Error::invalid(format!(
            "the image has {} layers; {masks} mask{} of {} frames x {} spp need {layers}",
            image.layers,
            if masks == 1 { "" } else { "s" },
            tile.frames,
            tile.spp
        )));
    }
    let bytes = format.texel_bytes() * tile.width * tile.height * layers as usize;
    check_copy(ctx, image, bytes, format.texel_bytes() as u32, vk::ImageUsageFlags::TRANSFER_DST)?;
    Ok(format)
}

/// Writes a plan's masks, stacked, into the renderer's image (see the module's
/// notes); bind the plan block (`write_plan_block`) beside it.
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn write_plan(ctx: &Context, plan: &SamplerPlan, image: &ImageTarget) -> Result<()> {
    let tile = plan.masks()[0].tile;
    let format = check_image(ctx, image, &tile, plan.masks().len(), plan.max_dims())?;
    Ok(fill(ctx, image, &plan.texels(format)?, format.texel_bytes() as u32)?)
}

/// Writes one mask into the renderer's image (a one-part plan: its block is
/// `SamplerPlan::single(mask)`'s).
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn write_mask(ctx: &Context, mask: &Mask, image: &ImageTarget) -> Result<()> {
    // SAFETY: the caller's promise for `image`.
    unsafe { write_plan(ctx, &SamplerPlan::single(mask.clone())?, image) }
}

/// Writes the include's plan block (`FsotPlan`, std140, `FSOT_MAX_PARTS` = 16)
/// into the renderer's buffer at `target.offset`.
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn write_plan_block(ctx: &Context, plan: &SamplerPlan, target: &BufferTarget) -> Result<()> {
    // SAFETY: the target is as this function's caller promised.
    Ok(unsafe { fill_buffer(ctx, target, &plan.plan_block()?) }?)
}

/// Writes the plan block for a shader that defines `FSOT_MAX_PARTS` as
/// `capacity` (at most `MAX_BLOCK_PARTS`; `SamplerPlan::plan_block_for`'s bytes)
/// into the renderer's buffer at `target.offset`.
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn write_plan_block_for(
    ctx: &Context,
    plan: &SamplerPlan,
    capacity: usize,
    target: &BufferTarget,
) -> Result<()> {
    // SAFETY: the target is as this function's caller promised.
    Ok(unsafe { fill_buffer(ctx, target, &plan.plan_block_for(capacity)?) }?)
}

/// Writes a mask's texels in `format` (laid out as in the image: layer by
/// layer, row by row) into the renderer's buffer at `target.offset`.
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn write_mask_to_buffer(ctx: &Context, mask: &Mask, format: Format, target: &BufferTarget) -> Result<()> {
    // SAFETY: the target is as this function's caller promised.
    Ok(unsafe { fill_buffer(ctx, target, &crate::io::ktx2::texels(mask, format)?) }?)
}

/// Makes a mask on the context's device (the Vulkan optimizer in its
/// deterministic mode, so the same settings give the same mask bit for bit,
/// run to run; `settings` as for `fsot optimize`) and writes it into the
/// renderer's image. The image is checked before the optimization starts.
/// Under a time budget (`Until::Seconds`) the budget counts from this call, the
/// run's start on the device (pipelines, buffers) included; the write after it
/// is not. Returns the mask (None when `cancel` stopped the run: nothing is
/// written then).
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn make_into_image(
    ctx: &Context,
    tile: Tile,
    settings: Settings,
    image: &ImageTarget,
    cancel: &CancelFlag,
    on: &mut dyn FnMut(Event),
) -> Result<Option<Mask>> {
    let called = std::time::Instant::now();
    tile.check()?;
    check_image(ctx, image, &tile, 1, tile.dims)?;
    let options = RunOptions { budget_from: Some(called), ..device_options(ctx, cancel) };
    let mut run = match Run::start(tile, settings, None, options) {
        Err(Error::Interrupted) => return Ok(None),
        run => run?,
    };
    if let Outcome::Cancelled { .. } = run.run(cancel, on)? {
        return Ok(None);
    }
    let mask = run.finish()?;
    // SAFETY: the caller's promise for `image`.
    unsafe { write_mask(ctx, &mask, image)? };
    Ok(Some(mask))
}

/// Makes every mask of a scene plan on the context's device (as
/// `fsot optimize --scene` would: the plateau rule stopping each, or under the
/// plan's budget each in its share of it, one after another; white noise for
/// what is not visible; the deterministic mode) and writes them, stacked,
/// into the renderer's image. The image is checked before the first run. The
/// plan's budget counts from this call. Returns the plan as the include reads
/// it, for its block (None when `cancel` stopped a run: nothing is written then).
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn make_plan_into_image(
    ctx: &Context,
    plan: &Plan,
    image: &ImageTarget,
    cancel: &CancelFlag,
    on: &mut dyn FnMut(PlanEvent),
) -> Result<Option<SamplerPlan>> {
    let origin = Stamp::now();
    plan.check()?;
    let first = &plan.masks[0];
    let dims = plan.masks.iter().map(|m| m.dims).max().unwrap_or(1);
    check_image(ctx, image, &plan.tile(first)?, plan.masks.len(), dims)?;
    let Some(masks) = plan_masks(plan, origin, &device_options(ctx, cancel), cancel, on)? else {
        return Ok(None);
    };
    let sampler = SamplerPlan::from_plan(plan, masks)?;
    // SAFETY: the caller's promise for `image`.
    unsafe { write_plan(ctx, &sampler, image)? };
    Ok(Some(sampler))
}

/// A Vulkan run on the context's device in the deterministic mode, whose
/// start `cancel` also cuts short.
fn device_options(ctx: &Context, cancel: &CancelFlag) -> RunOptions {
    RunOptions {
        backend: BackendChoice::Vulkan,
        context: Some(ctx.clone()),
        cancel_start: Some(cancel.clone()),
        vulkan: VulkanOptions { deterministic: true, ..VulkanOptions::default() },
        ..RunOptions::default()
    }
}

/// Writes a mask file (`.exr` or `.ktx2`, `Mask::open`) or a plan folder (`fsot optimize --scene`'s,
/// with `plan.json`) made earlier into the renderer's image; the plan, for its
/// block.
/// # Safety
/// The target is as the module's notes say (`# Safety`).
pub unsafe fn upload(ctx: &Context, path: &Path, image: &ImageTarget) -> Result<SamplerPlan> {
    let plan = SamplerPlan::load(path)?;
    // SAFETY: the caller's promise for `image`.
    unsafe { write_plan(ctx, &plan, image)? };
    Ok(plan)
}
