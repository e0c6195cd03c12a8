//! 2-D array images: `Image` owns one (its memory and a 2-D array view), and
//! `ImageTarget` describes one a host application owns; both are filled from
//! and read back into plain bytes through a staging buffer, with the layout
//! transitions recorded around the copy. `Sampler` is a nearest-texel sampler
//! for combined image-sampler bindings read with `texelFetch`.
//!
//! Synchronisation of a fill or read-back, recorded in one submission on the
//! context's queue (under its queue lock) and waited for before returning:
//! 1. a barrier from every earlier command on the queue (all stages, memory
//!    reads and writes) to the copy, moving the image from `layout_before` to
//!    TRANSFER_DST_OPTIMAL (or TRANSFER_SRC_OPTIMAL); UNDEFINED discards the old
//!    contents, which a fill overwrites anyway;
//! 2. the copy of every layer;
//! 3. a barrier from the copy to every later command on the queue (all stages,
//!    memory reads), moving the image to `layout_after`.
//!
//! No queue family ownership transfer is recorded: the image must be usable on
//! the context's queue family (created EXCLUSIVE for that family or
//! CONCURRENT); a host that uses it on another family releases and acquires it
//! itself around the call.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::buffer::{Buffer, Location};
use super::check;
use super::commands::barrier;
use super::commands::Recording;
use super::context::Context;
use super::error::{Error, Result};

/// A 2-D array image as its creator made it: what a fill or read-back needs
/// to know and checks. Vulkan cannot be asked how an image was created, so the
/// host states it here and fsot checks it against what it writes. The image is
/// single-sampled with OPTIMAL tiling and its memory bound; a fill or read-back
/// touches mip level 0 only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageTarget {
    /// The host's image.
    pub image: vk::Image,
    /// Its format (R8/R16 UNORM for d = 1, R8G8/R16G16 for d = 2, RGBA for more).
    pub format: vk::Format,
    /// Its width, the tile's.
    pub width: u32,
    /// Its height, the tile's.
    pub height: u32,
    /// Array layers the image was created with.
    pub layers: u32,
    /// The usage it was created with (a fill needs TRANSFER_DST, a read-back
    /// TRANSFER_SRC).
    pub usage: vk::ImageUsageFlags,
    /// Its layout before the call (UNDEFINED: the contents may be discarded).
    pub layout_before: vk::ImageLayout,
    /// The layout to leave it in (SHADER_READ_ONLY_OPTIMAL to sample it).
    pub layout_after: vk::ImageLayout,
}

/// What an owned image is made as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageDesc {
    /// The texel format.
    pub format: vk::Format,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Array layers.
    pub layers: u32,
    /// How it will be used.
    pub usage: vk::ImageUsageFlags,
}

/// A device-local 2-D array image with optimal tiling, its memory and a 2-D
/// array view of every layer, destroyed on drop. Starts in UNDEFINED layout;
/// `layout` tracks the layout fsot's own calls leave it in.
pub struct Image {
    ctx: Context,
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    pub(crate) desc: ImageDesc,
    pub(crate) layout: vk::ImageLayout,
}

impl Image {
    /// The Vulkan handle (fsot destroys it on drop).
    pub fn raw(&self) -> vk::Image {
        self.raw
    }

    /// A 2-D array view of every layer.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }

    /// What it was made as.
    pub fn desc(&self) -> ImageDesc {
        self.desc
    }

    /// The layout fsot's own calls left it in.
    pub fn layout(&self) -> vk::ImageLayout {
        self.layout
    }

    /// Records the layout a write through `target(after)` left it in (the
    /// renderer's calls take a target, not the image): the next copy's barrier
    /// moves it from there.
    ///
    /// # Safety
    /// Every layer of the image is in `layout` now, and stays so until the next
    /// copy (the barriers fsot records move it from there).
    pub unsafe fn set_layout(&mut self, layout: vk::ImageLayout) {
        self.layout = layout;
    }

    /// A device-local image as `desc` says, named `name` for debuggers. An
    /// error, before the image is made, for a usage its view cannot have (none
    /// of sampled, storage or an attachment) and for a format, usage, extent or
    /// layer count the device does not support.
    pub fn new(ctx: &Context, desc: ImageDesc, name: &str) -> Result<Self> {
        if desc.width == 0 || desc.height == 0 || desc.layers == 0 {
            return Err(Error::invalid(format!(
                "image {name}: {}x{} with {} layers",
                desc.width, desc.height, desc.layers
            )));
        }
        if texel_bytes_of(desc.format).is_none() {
            return Err(Error::invalid(format!(
                "image {name}: {:?} is not one of the plain colour formats fsot copies",
                desc.format
            )));
        }
        let viewable = vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::INPUT_ATTACHMENT;
        let known = viewable | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
        if !known.contains(desc.usage) {
            return Err(Error::invalid(format!(
                "image {name}: usage {:?} is not a colour image's",
                desc.usage
            )));
        }
        if !desc.usage.intersects(viewable) {
            return Err(Error::invalid(format!(
                "image {name}: usage {:?} allows no view (give SAMPLED or STORAGE)",
                desc.usage
            )));
        }
        let s = &ctx.shared;
        // SAFETY: a plain query on a live instance.
        let supported = unsafe {
            s.instance.get_physical_device_image_format_properties(
                s.physical_device,
                desc.format,
                vk::ImageType::TYPE_2D,
                vk::ImageTiling::OPTIMAL,
                desc.usage,
                vk::ImageCreateFlags::empty(),
            )
        };
        let fits = supported.as_ref().is_ok_and(|p| {
            desc.width <= p.max_extent.width
                && desc.height <= p.max_extent.height
                && desc.layers <= p.max_array_layers
        });
        if !fits {
            let limit = match supported {
                Ok(p) => format!(
                    "at most {}x{} with {} layers",
                    p.max_extent.width, p.max_extent.height, p.max_array_layers
                ),
                Err(e) => format!("{e:?}"),
            };
            return Err(Error::invalid(format!(
                "image {name}: {:?} {}x{} with {} layers for {:?}: the device supports {limit}",
                desc.format, desc.width, desc.height, desc.layers, desc.usage
            )));
        }
        let device = ctx.device();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info on a live device.
        let raw = check("vkCreateImage", unsafe { device.create_image(&info, None) })?;
        let mut me = Self {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            allocation: None,
            desc,
            layout: vk::ImageLayout::UNDEFINED,
        };
        // From here Drop frees whatever was made if a step fails.
        // SAFETY: `raw` was just made on this device.
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let alloc_desc = AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        let allocation = ctx.allocator()?.allocate(&alloc_desc)?;
        // SAFETY: the memory is bound below and freed only after the image is destroyed.
        let (memory, offset) = (unsafe { allocation.memory() }, allocation.offset());
        me.allocation = Some(allocation);
        // SAFETY: the allocation satisfies the image's requirements.
        check("vkBindImageMemory", unsafe { device.bind_image_memory(raw, memory, offset) })?;
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
            .format(desc.format)
            .subresource_range(all_layers(desc.layers));
        // SAFETY: the image is bound to memory; the range is inside it.
        me.view = check("vkCreateImageView", unsafe { device.create_image_view(&view_info, None) })?;
        Ok(me)
    }

    /// This image as a target that fsot's calls move from its current layout to `after`.
    pub fn target(&self, after: vk::ImageLayout) -> ImageTarget {
        ImageTarget {
            image: self.raw,
            format: self.desc.format,
            width: self.desc.width,
            height: self.desc.height,
            layers: self.desc.layers,
            usage: self.desc.usage,
            layout_before: self.layout,
            layout_after: after,
        }
    }

    /// Fills every layer from `bytes` (see `fill`), leaving it in `after`.
    pub fn fill(&mut self, bytes: &[u8], texel_bytes: u32, after: vk::ImageLayout) -> Result<()> {
        fill(&self.ctx, &self.target(after), bytes, texel_bytes)?;
        self.layout = after;
        Ok(())
    }

    /// Every layer's texels (see `read_back`), leaving it in `after`.
    pub fn read_back(&mut self, texel_bytes: u32, after: vk::ImageLayout) -> Result<Vec<u8>> {
        let bytes = read_back(&self.ctx, &self.target(after), texel_bytes)?;
        self.layout = after;
        Ok(bytes)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the image (every submission is waited
        // for); null handles (a failed constructor) are ignored by Vulkan. The
        // view goes before the image, the image before its memory.
        unsafe {
            self.ctx.device().destroy_image_view(self.view, None);
            self.ctx.device().destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            if let Ok(mut alloc) = self.ctx.allocator() {
                let _ = alloc.free(allocation); // nothing useful to do with a failure in drop
            }
        }
    }
}

/// A nearest-texel sampler for reading with `texelFetch` through a combined
/// image-sampler binding, destroyed on drop.
pub struct Sampler {
    ctx: Context,
    raw: vk::Sampler,
}

impl Sampler {
    /// The Vulkan handle (fsot destroys it on drop).
    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }

    /// Nearest filtering, repeating addresses: a mask read as a tile.
    pub fn nearest(ctx: &Context) -> Result<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::REPEAT)
            .max_lod(0.0);
        // SAFETY: a valid create info on a live device.
        let raw = check("vkCreateSampler", unsafe { ctx.device().create_sampler(&info, None) })?;
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the sampler.
        unsafe { self.ctx.device().destroy_sampler(self.raw, None) };
    }
}

fn all_layers(layers: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: layers,
    }
}

/// Bytes per texel of the plain colour formats (the core formats 9 to 121 of
/// `VkFormat`: 8-, 16-, 32- and 64-bit channels, and the packed 32-bit ones);
/// None for any other.
pub fn texel_bytes_of(format: vk::Format) -> Option<u32> {
    Some(match format.as_raw() {
        9..=15 => 1,
        16..=22 | 70..=76 => 2,
        23..=36 => 3,
        37..=69 | 77..=83 | 98..=100 => 4,
        84..=90 => 6,
        91..=97 | 101..=103 | 110..=112 => 8,
        104..=106 => 12,
        107..=109 | 113..=115 => 16,
        116..=118 => 24,
        119..=121 => 32,
        _ => return None,
    })
}

/// Checks a target against a copy of `bytes` bytes of `texel_bytes`-byte texels
/// needing `usage`, on the context's device: every layer covered exactly, the
/// usage present, the format able to take the copy with optimal tiling, the
/// texel size the format's (for the plain colour formats).
pub fn check_copy(
    ctx: &Context,
    target: &ImageTarget,
    bytes: usize,
    texel_bytes: u32,
    usage: vk::ImageUsageFlags,
) -> Result<()> {
    if target.image == vk::Image::null() {
        return Err(Error::invalid("the image handle is null"));
    }
    if [vk::ImageLayout::UNDEFINED, vk::ImageLayout::PREINITIALIZED].contains(&target.layout_after) {
        return Err(Error::invalid(format!(
            "an image cannot be left in {:?}: give the layout it is read in (layout_after)",
            target.layout_after
        )));
    }
    // The colour layouts a copy may leave an image in, each with the usage
    // Vulkan asks of an image in it.
    use vk::ImageUsageFlags as U;
    let needs = match target.layout_after {
        vk::ImageLayout::GENERAL => Some(U::empty()),
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL => Some(U::TRANSFER_SRC),
        vk::ImageLayout::TRANSFER_DST_OPTIMAL => Some(U::TRANSFER_DST),
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL => Some(U::SAMPLED | U::INPUT_ATTACHMENT),
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL => Some(U::COLOR_ATTACHMENT),
        _ => None,
    };
    match needs {
        None => {
            return Err(Error::invalid(format!(
                "fsot leaves an image in GENERAL, TRANSFER_SRC_OPTIMAL, TRANSFER_DST_OPTIMAL, \
                 SHADER_READ_ONLY_OPTIMAL or COLOR_ATTACHMENT_OPTIMAL, not {:?}",
                target.layout_after
            )))
        }
        Some(any) if !any.is_empty() && !target.usage.intersects(any) => {
            return Err(Error::invalid(format!(
                "an image left in {:?} needs the usage {any:?}; it has {:?}",
                target.layout_after, target.usage
            )))
        }
        Some(_) => {}
    }
    if !target.usage.contains(usage) {
        return Err(Error::invalid(format!(
            "the image's usage {:?} lacks {usage:?}, which this copy needs",
            target.usage
        )));
    }
    match texel_bytes_of(target.format) {
        None => {
            return Err(Error::invalid(format!(
                "fsot copies the plain colour formats only, not {:?}",
                target.format
            )))
        }
        Some(real) if real != texel_bytes => {
            return Err(Error::invalid(format!(
                "{:?} has {real}-byte texels, the copy was given {texel_bytes}",
                target.format
            )))
        }
        Some(_) => {}
    }
    let needed = target.width as u64 * target.height as u64 * target.layers as u64 * texel_bytes as u64;
    if target.width == 0 || target.height == 0 || target.layers == 0 || needed != bytes as u64 {
        return Err(Error::invalid(format!(
            "a {}x{} image of {} layers of {texel_bytes}-byte texels holds {needed} bytes, the data is {bytes}",
            target.width, target.height, target.layers
        )));
    }
    let feature = if usage.contains(vk::ImageUsageFlags::TRANSFER_DST) {
        vk::FormatFeatureFlags::TRANSFER_DST
    } else {
        vk::FormatFeatureFlags::TRANSFER_SRC
    };
    let s = &ctx.shared;
    // SAFETY: a plain query on a live instance.
    let props = unsafe { s.instance.get_physical_device_format_properties(s.physical_device, target.format) };
    if !props.optimal_tiling_features.contains(feature) {
        return Err(Error::invalid(format!(
            "the device cannot copy into or out of {:?} images with optimal tiling",
            target.format
        )));
    }
    Ok(())
}

/// Records the layout transition of every layer from `from` to `to`, ordered
/// after `src` stages' `src_access` and before `dst` stages' `dst_access`.
#[allow(clippy::too_many_arguments)]
fn transition(
    ctx: &Context,
    cmd: Recording<'_>,
    target: &ImageTarget,
    (from, to): (vk::ImageLayout, vk::ImageLayout),
    (src, src_access): (vk::PipelineStageFlags, vk::AccessFlags),
    (dst, dst_access): (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .old_layout(from)
        .new_layout(to)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(target.image)
        .subresource_range(all_layers(target.layers));
    // SAFETY: `cmd` is being recorded; the image is alive (the caller's promise for a host's).
    unsafe {
        ctx.device().cmd_pipeline_barrier(
            cmd.raw(),
            src,
            dst,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier],
        )
    };
}

fn whole_copy(target: &ImageTarget) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(0)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: target.layers,
        })
        .image_extent(vk::Extent3D { width: target.width, height: target.height, depth: 1 })
}

/// Every command before or after on the queue, any memory access: the scope of
/// the barriers around a copy into or out of a host's resource.
pub(crate) const EVERY_COMMAND: (vk::PipelineStageFlags, vk::AccessFlags) = (
    vk::PipelineStageFlags::ALL_COMMANDS,
    vk::AccessFlags::from_raw(vk::AccessFlags::MEMORY_READ.as_raw() | vk::AccessFlags::MEMORY_WRITE.as_raw()),
);

/// Writes `bytes` into every layer of `target`: layer by layer, row by row,
/// rows tightly packed, `texel_bytes` bytes a texel (the image's format's
/// size). Checked before any GPU work: the size, the usage (TRANSFER_DST) and
/// the device's support for copies into the format.
pub fn fill(ctx: &Context, target: &ImageTarget, bytes: &[u8], texel_bytes: u32) -> Result<()> {
    check_copy(ctx, target, bytes.len(), texel_bytes, vk::ImageUsageFlags::TRANSFER_DST)?;
    let staging = Buffer::with_data(ctx, bytes, Location::Upload, "image-staging")?;
    let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
    ctx.submit(|cmd| {
        let write = (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_WRITE);
        transition(ctx, cmd, target, (target.layout_before, dst), EVERY_COMMAND, write);
        // SAFETY: `cmd` is being recorded; the staging buffer holds every layer.
        unsafe {
            ctx.device().cmd_copy_buffer_to_image(
                cmd.raw(),
                staging.raw,
                target.image,
                dst,
                &[whole_copy(target)],
            )
        };
        transition(ctx, cmd, target, (dst, target.layout_after), write, EVERY_COMMAND);
    })
}

/// Every layer of `target` as bytes, laid out as `fill` takes them. Needs
/// TRANSFER_SRC usage.
pub fn read_back(ctx: &Context, target: &ImageTarget, texel_bytes: u32) -> Result<Vec<u8>> {
    let bytes =
        target.width as usize * target.height as usize * target.layers as usize * texel_bytes as usize;
    check_copy(ctx, target, bytes, texel_bytes, vk::ImageUsageFlags::TRANSFER_SRC)?;
    let staging = Buffer::new(ctx, bytes as u64, Location::Readback, "image-readback")?;
    let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    ctx.submit(|cmd| {
        let read = (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ);
        transition(ctx, cmd, target, (target.layout_before, src), EVERY_COMMAND, read);
        // SAFETY: `cmd` is being recorded; the staging buffer has room for every layer.
        unsafe {
            ctx.device().cmd_copy_image_to_buffer(
                cmd.raw(),
                target.image,
                src,
                staging.raw,
                &[whole_copy(target)],
            )
        };
        transition(ctx, cmd, target, (src, target.layout_after), read, EVERY_COMMAND);
        barrier(cmd); // the copy's writes visible to the host
    })?;
    staging.read(bytes)
}
