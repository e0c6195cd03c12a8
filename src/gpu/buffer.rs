//! Buffers that own their memory (gpu-allocator), freed on drop.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::check;
use super::context::Context;
use crate::error::{Error, Result};

/// Where a buffer's memory lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// Device-local: samples, optimizer state, accumulators, tables.
    Device,
    /// Host-visible, written by the CPU: staging for uploads.
    Upload,
    /// Host-visible, read by the CPU: staging for read-back.
    Readback,
}

pub struct Buffer {
    ctx: Context,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
}

impl Buffer {
    /// A storage buffer usable as a copy source and destination.
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
        if location == Location::Device && super::fault::refuse_device_allocation(size) {
            return Err(Error::Allocation(gpu_allocator::AllocationError::OutOfMemory));
        }
        let device = ctx.device();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::INDIRECT_BUFFER;
        let info =
            vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = check("vkCreateBuffer", unsafe { device.create_buffer(&info, None) })?;
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let memory_location = match location {
            Location::Device => MemoryLocation::GpuOnly,
            Location::Upload => MemoryLocation::CpuToGpu,
            Location::Readback => MemoryLocation::GpuToCpu,
        };
        let allocation =
            ctx.shared.allocator.lock().map_err(|_| Error::invalid("allocator lock poisoned"))?.allocate(
                &AllocationCreateDesc {
                    name,
                    requirements,
                    location: memory_location,
                    linear: true,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                },
            );
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(e.into());
            }
        };
        if let Err(result) =
            unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }
        {
            if let Ok(mut alloc) = ctx.shared.allocator.lock() {
                let _ = alloc.free(allocation);
            }
            unsafe { device.destroy_buffer(raw, None) };
            return Err(Error::Vulkan { call: "vkBindBufferMemory", result });
        }
        Ok(Self { ctx: ctx.clone(), raw, allocation: Some(allocation), size })
    }

    /// Copies `bytes` into a host-visible buffer.
    pub fn write(&mut self, bytes: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::invalid("buffer is not host-visible"))?;
        if bytes.len() > slice.len() {
            return Err(Error::invalid("write larger than the buffer"));
        }
        slice[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// The contents of a host-visible buffer.
    pub fn read(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..self.size as usize])
            .ok_or_else(|| Error::invalid("buffer is not host-visible"))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(allocation) = self.allocation.take() {
            if let Ok(mut alloc) = self.ctx.shared.allocator.lock() {
                let _ = alloc.free(allocation);
            }
        }
        unsafe { self.ctx.device().destroy_buffer(self.raw, None) };
    }
}
