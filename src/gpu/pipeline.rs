//! Compute pipelines (one per shader pass) with storage-buffer bindings 0..n in set
//! 0, a push-constant block and specialization constants 0..m (workgroup size
//! first), and one-shot command submission.

use ash::vk;

use super::buffer::Buffer;
use super::check;
use super::context::Context;
use crate::error::{Error, Result};

pub struct ComputePipeline {
    ctx: Context,
    module: vk::ShaderModule,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    sets: Vec<vk::DescriptorSet>,
    pub raw: vk::Pipeline,
    bindings: u32,
    push_bytes: u32,
}

impl ComputePipeline {
    /// `spirv`: the compiled pass; `bindings`: storage buffers it reads or writes;
    /// `push_bytes`: size of its push-constant block; `spec`: values of its
    /// specialization constants 0, 1, ...
    pub fn new(ctx: &Context, spirv: &[u8], bindings: u32, push_bytes: u32, spec: &[u32]) -> Result<Self> {
        Self::with_sets(ctx, spirv, bindings, push_bytes, spec, 1)
    }

    /// As `new`, with `sets` descriptor sets, each bound to its own buffers and
    /// chosen at dispatch (e.g. the ping-pong passes of a sort).
    pub fn with_sets(
        ctx: &Context,
        spirv: &[u8],
        bindings: u32,
        push_bytes: u32,
        spec: &[u32],
        sets: u32,
    ) -> Result<Self> {
        let device = ctx.device();
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| Error::invalid(format!("bad SPIR-V: {e}")))?;
        let module = check("vkCreateShaderModule", unsafe {
            device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
        })?;
        let mut me = Self {
            ctx: ctx.clone(),
            module,
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pool: vk::DescriptorPool::null(),
            sets: Vec::new(),
            raw: vk::Pipeline::null(),
            bindings,
            push_bytes,
        };
        // Every handle below is destroyed by Drop if a later step fails.
        let layout_bindings: Vec<_> = (0..bindings)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        me.set_layout = check("vkCreateDescriptorSetLayout", unsafe {
            device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )
        })?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(push_bytes.max(4))];
        let set_layouts = [me.set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        me.layout =
            check("vkCreatePipelineLayout", unsafe { device.create_pipeline_layout(&layout_info, None) })?;
        let entries: Vec<_> = (0..spec.len() as u32)
            .map(|i| vk::SpecializationMapEntry::default().constant_id(i).offset(4 * i).size(4))
            .collect();
        let data: Vec<u8> = spec.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let spec_info = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(me.layout);
        me.raw = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, result)| Error::Vulkan { call: "vkCreateComputePipelines", result })?[0];
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(bindings.max(1) * sets)];
        me.pool = check("vkCreateDescriptorPool", unsafe {
            device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(sets).pool_sizes(&sizes),
                None,
            )
        })?;
        let layouts = vec![me.set_layout; sets as usize];
        me.sets = check("vkAllocateDescriptorSets", unsafe {
            device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(me.pool).set_layouts(&layouts),
            )
        })?;
        Ok(me)
    }

    /// Points bindings 0..n of set 0 at `buffers` (whole buffers).
    pub fn bind(&self, buffers: &[&Buffer]) -> Result<()> {
        self.bind_set(0, buffers)
    }

    /// Points bindings 0..n of descriptor set `set` at `buffers`.
    pub fn bind_set(&self, set: usize, buffers: &[&Buffer]) -> Result<()> {
        let target = *self
            .sets
            .get(set)
            .ok_or_else(|| Error::invalid(format!("pipeline has no descriptor set {set}")))?;
        if buffers.len() as u32 != self.bindings {
            return Err(Error::invalid(format!(
                "pipeline takes {} buffers, got {}",
                self.bindings,
                buffers.len()
            )));
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).offset(0).range(vk::WHOLE_SIZE)])
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(target)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        unsafe { self.ctx.device().update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Records a dispatch of `groups` workgroups with push constants `push`.
    pub fn dispatch(&self, cmd: vk::CommandBuffer, groups: [u32; 3], push: &[u8]) {
        self.dispatch_set(cmd, 0, groups, push)
    }

    /// Binds the pipeline, descriptor set `set` and the push constants.
    fn bind_for_dispatch(&self, cmd: vk::CommandBuffer, set: usize, push: &[u8]) {
        let device = self.ctx.device();
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw);
            device.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[self.sets[set]],
                &[],
            );
            if self.push_bytes > 0 {
                device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
        }
    }

    /// Records a dispatch whose size the GPU wrote into `args` at `offset` (a
    /// VkDispatchIndirectCommand), using descriptor set `set`.
    pub fn dispatch_indirect_set(
        &self,
        cmd: vk::CommandBuffer,
        set: usize,
        args: &Buffer,
        offset: u64,
        push: &[u8],
    ) {
        self.bind_for_dispatch(cmd, set, push);
        unsafe { self.ctx.device().cmd_dispatch_indirect(cmd, args.raw, offset) };
    }

    /// Records a dispatch using descriptor set `set`.
    pub fn dispatch_set(&self, cmd: vk::CommandBuffer, set: usize, groups: [u32; 3], push: &[u8]) {
        self.bind_for_dispatch(cmd, set, push);
        unsafe { self.ctx.device().cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            device.destroy_descriptor_pool(self.pool, None);
            device.destroy_pipeline(self.raw, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_shader_module(self.module, None);
        }
    }
}

/// A full memory barrier between recorded commands (compute and transfer writes
/// made visible to compute, transfer, host and indirect-argument reads).
pub fn barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let mb = vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::HOST_READ
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        );
    unsafe {
        ctx.device().cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::COMPUTE_SHADER
                | vk::PipelineStageFlags::TRANSFER
                | vk::PipelineStageFlags::HOST
                | vk::PipelineStageFlags::DRAW_INDIRECT,
            vk::DependencyFlags::empty(),
            &[mb],
            &[],
            &[],
        )
    };
}

/// Records commands with `record`, submits them and waits for completion.
pub fn submit_and_wait(ctx: &Context, record: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
    let device = ctx.device();
    let pool = check("vkCreateCommandPool", unsafe {
        device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(ctx.shared.queue_family),
            None,
        )
    })?;
    let result = (|| -> Result<()> {
        let cmd = check("vkAllocateCommandBuffers", unsafe {
            device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )
        })?[0];
        check("vkBeginCommandBuffer", unsafe {
            device.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
        })?;
        record(cmd);
        check("vkEndCommandBuffer", unsafe { device.end_command_buffer(cmd) })?;
        let fence =
            check("vkCreateFence", unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) })?;
        let cmds = [cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        let submitted = match super::fault::submission() {
            Some(injected) => Err(injected),
            None => unsafe { device.queue_submit(ctx.shared.queue, &submit, fence) },
        };
        let waited = check("vkQueueSubmit", submitted).and_then(|_| {
            check("vkWaitForFences", unsafe { device.wait_for_fences(&[fence], true, u64::MAX) })
        });
        unsafe { device.destroy_fence(fence, None) };
        waited
    })();
    unsafe { device.destroy_command_pool(pool, None) };
    result
}

/// Copies `src` into `dst` (whole of `src`).
pub fn copy(ctx: &Context, cmd: vk::CommandBuffer, src: &Buffer, dst: &Buffer) {
    let region = [vk::BufferCopy::default().size(src.size.min(dst.size))];
    unsafe { ctx.device().cmd_copy_buffer(cmd, src.raw, dst.raw, &region) };
}
