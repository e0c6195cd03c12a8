//! Buffers that own their memory (gpu-allocator), freed on drop, with one upload
//! and one download path: through a host-visible staging buffer for device-local
//! memory, directly for host-visible memory.

use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::commands::{barrier, copy, Recording};
use super::context::Context;
use super::error::{Error, Result};
use super::{check, fault};

/// Where a buffer's memory lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// Device-local: the data passes work on.
    Device,
    /// Host-visible, written by the CPU: staging for uploads, small counts.
    Upload,
    /// Host-visible, read by the CPU: staging for read-back.
    Readback,
}

/// A buffer and its memory, freed on drop.
pub struct Buffer {
    ctx: Context,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub(crate) size: u64,
    pub(crate) location: Location,
}

impl Buffer {
    /// The Vulkan handle (fsot destroys it on drop).
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// Its size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Where its memory lies.
    pub fn location(&self) -> Location {
        self.location
    }

    /// A storage buffer (also a uniform buffer, a uniform texel buffer through a
    /// `TexelView`, a copy source and destination, and indirect arguments) of
    /// `size` bytes. Device-local buffers larger than one binding
    /// (maxStorageBufferRange) are refused.
    pub fn new(ctx: &Context, size: u64, location: Location, name: &str) -> Result<Self> {
        if size == 0 {
            return Err(Error::invalid(format!("buffer {name}: size 0")));
        }
        if location == Location::Device && size > ctx.info().max_storage_buffer_range {
            return Err(Error::invalid(format!(
                "buffer {name} needs {size} bytes; the device binds at most {} (maxStorageBufferRange)",
                ctx.info().max_storage_buffer_range
            )));
        }
        if location == Location::Device && fault::refuse_device_allocation(size) {
            return Err(Error::Allocation(gpu_allocator::AllocationError::OutOfMemory));
        }
        let device = ctx.device();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::UNIFORM_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let info =
            vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: a valid create info on a live device.
        let raw = check("vkCreateBuffer", unsafe { device.create_buffer(&info, None) })?;
        // SAFETY: `raw` was just made on this device.
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let memory_location = match location {
            Location::Device => MemoryLocation::GpuOnly,
            Location::Upload => MemoryLocation::CpuToGpu,
            Location::Readback => MemoryLocation::GpuToCpu,
        };
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location: memory_location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        let allocation = ctx.allocator().and_then(|mut a| a.allocate(&desc).map_err(Error::from));
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and unbound.
                unsafe { device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements.
        if let Err(result) =
            unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }
        {
            if let Ok(mut alloc) = ctx.allocator() {
                let _ = alloc.free(allocation); // the bind's error is the one to report
            }
            // SAFETY: the buffer is unused.
            unsafe { device.destroy_buffer(raw, None) };
            return Err(Error::Vulkan { call: "vkBindBufferMemory", result });
        }
        Ok(Self { ctx: ctx.clone(), raw, allocation: Some(allocation), size, location })
    }

    /// A buffer holding `data`.
    pub fn with_data<T: Pod>(ctx: &Context, data: &[T], location: Location, name: &str) -> Result<Self> {
        let mut buffer = Self::new(ctx, std::mem::size_of_val(data).max(4) as u64, location, name)?;
        buffer.upload(data)?;
        Ok(buffer)
    }

    /// Writes `data` at the start of the buffer (through a staging buffer when the
    /// buffer is device-local); waits until it is there.
    pub fn upload<T: Pod>(&mut self, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        match self.location {
            Location::Device => upload_batch(&self.ctx, &[(self, bytes)], |_| {}),
            _ => {
                if bytes.len() as u64 > self.size {
                    return Err(Error::invalid(format!(
                        "an upload of {} bytes into a buffer of {}",
                        bytes.len(),
                        self.size
                    )));
                }
                self.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
                Ok(())
            }
        }
    }

    /// The first `count` values of type T in the buffer (through a staging buffer
    /// made for it when the buffer is device-local).
    pub fn download<T: Pod>(&self, count: usize) -> Result<Vec<T>> {
        let bytes = count
            .checked_mul(std::mem::size_of::<T>())
            .ok_or_else(|| Error::invalid("a read past the end of a buffer"))? as u64;
        match self.location {
            Location::Readback | Location::Upload => self.read(count),
            Location::Device => {
                let parts = download_batch(&self.ctx, &[(self, bytes)], None)?;
                Ok(bytemuck::pod_collect_to_vec(&parts[0]))
            }
        }
    }

    /// The first `count` values of a host-visible buffer, as they are now (after
    /// the submission that wrote them has completed).
    pub fn read<T: Pod>(&self, count: usize) -> Result<Vec<T>> {
        let bytes = count
            .checked_mul(std::mem::size_of::<T>())
            .ok_or_else(|| Error::invalid("a read past the end of a buffer"))?;
        let mapped = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| Error::invalid("the buffer is not host-visible"))?;
        let slice = mapped.get(..bytes).ok_or_else(|| Error::invalid("a read past the end of a buffer"))?;
        // Copied out: the mapping's alignment need not suit T.
        Ok(bytemuck::pod_collect_to_vec(slice))
    }

    fn mapped_mut(&mut self) -> Result<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
            .ok_or_else(|| Error::invalid("the buffer is not host-visible"))
    }
}

/// Uploads into device-local buffers, all through one staging buffer in one
/// submission, followed by whatever `after` records; waits until done.
pub fn upload_batch(
    ctx: &Context,
    uploads: &[(&Buffer, &[u8])],
    after: impl FnOnce(Recording<'_>),
) -> Result<()> {
    let mut offsets = Vec::with_capacity(uploads.len());
    let mut total = 0u64;
    for (buffer, bytes) in uploads {
        if buffer.location != Location::Device || bytes.len() as u64 > buffer.size {
            return Err(Error::invalid(format!(
                "an upload of {} bytes into a {:?} buffer of {}",
                bytes.len(),
                buffer.location,
                buffer.size
            )));
        }
        offsets.push(total);
        total += (bytes.len() as u64).div_ceil(16) * 16;
    }
    let staging = match total {
        0 => None,
        _ => {
            let mut s = Buffer::new(ctx, total, Location::Upload, "upload-staging")?;
            let mapped = s.mapped_mut()?;
            for ((_, bytes), &at) in uploads.iter().zip(&offsets) {
                mapped[at as usize..at as usize + bytes.len()].copy_from_slice(bytes);
            }
            Some(s)
        }
    };
    ctx.submit(|cmd| {
        if let Some(s) = &staging {
            for ((buffer, bytes), &at) in uploads.iter().zip(&offsets) {
                if !bytes.is_empty() {
                    let region = [vk::BufferCopy::default().src_offset(at).size(bytes.len() as u64)];
                    // SAFETY: `cmd` is being recorded; both buffers are alive with TRANSFER usage.
                    unsafe { ctx.device().cmd_copy_buffer(cmd.raw(), s.raw, buffer.raw, &region) };
                }
            }
        }
        barrier(cmd);
        after(cmd);
    })
}

/// Downloads from device-local buffers (the first `bytes` of each), all in one
/// submission, through `staging` (a host-visible buffer the caller keeps, so
/// nothing is allocated) or one made for the call; the bytes of each.
pub fn download_batch(
    ctx: &Context,
    sources: &[(&Buffer, u64)],
    staging: Option<&Buffer>,
) -> Result<Vec<Vec<u8>>> {
    let mut offsets = Vec::with_capacity(sources.len());
    let mut total = 0u64;
    for (buffer, bytes) in sources {
        if *bytes > buffer.size {
            return Err(Error::invalid(format!(
                "a download of {bytes} bytes from a buffer of {}",
                buffer.size
            )));
        }
        offsets.push(total);
        total += bytes.div_ceil(16) * 16;
    }
    let own;
    let staging = match staging {
        Some(s) if s.location == Location::Readback && s.size >= total => s,
        Some(s) => {
            return Err(Error::invalid(format!(
                "a staging buffer of {} bytes ({:?}) for {total} bytes of read-back",
                s.size, s.location
            )))
        }
        None => {
            own = Buffer::new(ctx, total.max(4), Location::Readback, "download-staging")?;
            &own
        }
    };
    ctx.submit(|cmd| {
        // A copy of 0 bytes is not a valid region: nothing to copy.
        for ((buffer, bytes), &at) in sources.iter().zip(&offsets).filter(|((_, b), _)| *b > 0) {
            copy(cmd, buffer, staging, *bytes, at);
        }
        barrier(cmd);
    })?;
    let all: Vec<u8> = staging.read(total as usize)?;
    Ok(sources
        .iter()
        .zip(&offsets)
        .map(|((_, bytes), &at)| all[at as usize..(at + bytes) as usize].to_vec())
        .collect())
}

/// A range of a buffer a host application owns, as its creator made it (Vulkan
/// cannot be asked): what a fill checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferTarget {
    /// The caller's buffer.
    pub buffer: vk::Buffer,
    /// The buffer's size as created.
    pub size: u64,
    /// The usage it was created with (a fill needs TRANSFER_DST).
    pub usage: vk::BufferUsageFlags,
    /// Where the data goes (a multiple of 4).
    pub offset: u64,
}

/// Writes `bytes` into a host's buffer at `target.offset`, through a staging
/// buffer, in one submission on the context's queue: ordered after every earlier
/// command on the queue and before every later one (barriers of all stages and
/// memory accesses around the copy); waits until done. No queue family
/// ownership transfer (as for images: see `image`). Checked before any GPU
/// work: the handle, the usage, the offset's alignment and the range.
///
/// # Safety
/// The target's buffer is alive with its memory bound, belongs to the context's
/// device, was created with the size and usage the target states, can be used on
/// the context's queue family, and is used by no other work until the call
/// returns.
pub unsafe fn fill_buffer(ctx: &Context, target: &BufferTarget, bytes: &[u8]) -> Result<()> {
    if target.buffer == vk::Buffer::null() {
        return Err(Error::invalid("the buffer handle is null"));
    }
    if !target.usage.contains(vk::BufferUsageFlags::TRANSFER_DST) {
        return Err(Error::invalid(format!(
            "the buffer's usage {:?} lacks TRANSFER_DST, which this copy needs",
            target.usage
        )));
    }
    let end = target.offset.checked_add(bytes.len() as u64);
    if target.offset % 4 != 0 || bytes.is_empty() || end.is_none_or(|e| e > target.size) {
        return Err(Error::invalid(format!(
            "{} bytes at offset {} do not fit a buffer of {} (the offset a multiple of 4)",
            bytes.len(),
            target.offset,
            target.size
        )));
    }
    let staging = Buffer::with_data(ctx, bytes, Location::Upload, "buffer-staging")?;
    let (stages, access) = super::image::EVERY_COMMAND;
    let memory = |src, dst| vk::MemoryBarrier::default().src_access_mask(src).dst_access_mask(dst);
    let device = ctx.device();
    ctx.submit(|cmd| {
        let region = [vk::BufferCopy::default().dst_offset(target.offset).size(bytes.len() as u64)];
        let write = vk::AccessFlags::TRANSFER_WRITE;
        let flags = vk::DependencyFlags::empty();
        let transfer = vk::PipelineStageFlags::TRANSFER;
        // SAFETY: `cmd` is being recorded; the host's buffer is alive (its promise)
        // with TRANSFER_DST usage, and the range was checked above.
        unsafe {
            device.cmd_pipeline_barrier(
                cmd.raw(),
                stages,
                transfer,
                flags,
                &[memory(access, write)],
                &[],
                &[],
            );
            device.cmd_copy_buffer(cmd.raw(), staging.raw, target.buffer, &region);
            device.cmd_pipeline_barrier(
                cmd.raw(),
                transfer,
                stages,
                flags,
                &[memory(write, access)],
                &[],
                &[],
            );
        }
    })
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(allocation) = self.allocation.take() {
            if let Ok(mut alloc) = self.ctx.allocator() {
                let _ = alloc.free(allocation); // nothing useful to do with a failure in drop
            }
        }
        // SAFETY: no pending submission uses the buffer (every submission is waited for).
        unsafe { self.ctx.device().destroy_buffer(self.raw, None) };
    }
}
