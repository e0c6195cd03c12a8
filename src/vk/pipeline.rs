//! Compute pipelines: one shader pass, a descriptor set layout of storage buffers
//! at bindings 0..n in set 0 (a shader family shares one layout), a push-constant
//! block, specialization constants 0..m (workgroup size first), and descriptor
//! sets bound to buffers by binding index.

use ash::vk;

use super::buffer::Buffer;
use super::check;
use super::context::Context;
use crate::error::{Error, Result};

/// What a compute pipeline is made from.
#[derive(Clone, Copy, Debug)]
pub struct ComputeDesc<'a> {
    /// The compiled pass.
    pub spirv: &'a [u8],
    /// Storage buffers in the layout: bindings 0..bindings.
    pub bindings: u32,
    /// Size of the push-constant block (0: none).
    pub push_bytes: u32,
    /// Values of specialization constants 0, 1, ...
    pub spec: &'a [u32],
    /// Descriptor sets to allocate, each bound to its own buffers and chosen at
    /// dispatch (e.g. the ping-pong passes of a sort).
    pub sets: u32,
}

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
    pub fn new(ctx: &Context, desc: &ComputeDesc) -> Result<Self> {
        let device = ctx.device();
        let words = ash::util::read_spv(&mut std::io::Cursor::new(desc.spirv))
            .map_err(|e| Error::invalid(format!("bad SPIR-V: {e}")))?;
        // SAFETY: the words are SPIR-V compiled by build.rs (or the caller's).
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
            bindings: desc.bindings,
            push_bytes: desc.push_bytes,
        };
        // Every handle below is destroyed by Drop if a later step fails.
        let layout_bindings: Vec<_> = (0..desc.bindings)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings);
        // SAFETY: a valid create info.
        me.set_layout = check("vkCreateDescriptorSetLayout", unsafe {
            device.create_descriptor_set_layout(&set_info, None)
        })?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .offset(0)
            .size(desc.push_bytes.max(4))];
        let set_layouts = [me.set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if desc.push_bytes > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        // SAFETY: the set layout above is alive.
        me.layout =
            check("vkCreatePipelineLayout", unsafe { device.create_pipeline_layout(&layout_info, None) })?;
        let entries: Vec<_> = (0..desc.spec.len() as u32)
            .map(|i| vk::SpecializationMapEntry::default().constant_id(i).offset(4 * i).size(4))
            .collect();
        let spec_info =
            vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(desc.spec));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(me.layout);
        // SAFETY: the module, layout and specialization data are alive during the call.
        me.raw = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, result)| Error::Vulkan { call: "vkCreateComputePipelines", result })?[0];
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(desc.bindings.max(1) * desc.sets.max(1))];
        let pool_info = vk::DescriptorPoolCreateInfo::default().max_sets(desc.sets.max(1)).pool_sizes(&sizes);
        // SAFETY: a valid create info.
        me.pool =
            check("vkCreateDescriptorPool", unsafe { device.create_descriptor_pool(&pool_info, None) })?;
        let layouts = vec![me.set_layout; desc.sets.max(1) as usize];
        let alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(me.pool).set_layouts(&layouts);
        // SAFETY: the pool has room for these sets.
        me.sets = check("vkAllocateDescriptorSets", unsafe { device.allocate_descriptor_sets(&alloc) })?;
        Ok(me)
    }

    /// Points the given bindings of descriptor set `set` at whole buffers. A
    /// binding the pass does not use may stay unbound.
    pub fn bind(&self, set: usize, buffers: &[(u32, &Buffer)]) -> Result<()> {
        let target = *self
            .sets
            .get(set)
            .ok_or_else(|| Error::invalid(format!("the pipeline has no descriptor set {set}")))?;
        if let Some((b, _)) = buffers.iter().find(|(b, _)| *b >= self.bindings) {
            return Err(Error::invalid(format!(
                "binding {b} is outside the pipeline's {} bindings",
                self.bindings
            )));
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, b)| [vk::DescriptorBufferInfo::default().buffer(b.raw).offset(0).range(vk::WHOLE_SIZE)])
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .zip(buffers)
            .map(|(info, (binding, _))| {
                vk::WriteDescriptorSet::default()
                    .dst_set(target)
                    .dst_binding(*binding)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use by a pending submission (every submission is waited for).
        unsafe { self.ctx.device().update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Binds the pipeline, descriptor set `set` and the push constants.
    fn bind_for_dispatch(&self, cmd: vk::CommandBuffer, set: usize, push: &[u8]) {
        let device = self.ctx.device();
        // SAFETY: `cmd` is being recorded; the set index was checked when bound.
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

    /// Records a dispatch of `groups` workgroups with descriptor set `set` and
    /// push constants `push` (`bytemuck::bytes_of` of the pass's push struct).
    pub fn dispatch(&self, cmd: vk::CommandBuffer, set: usize, groups: [u32; 3], push: &[u8]) {
        self.bind_for_dispatch(cmd, set, push);
        // SAFETY: `cmd` is being recorded with this pipeline bound.
        unsafe { self.ctx.device().cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
    }

    /// Records a dispatch whose size the GPU wrote into `args` at `offset` (a
    /// VkDispatchIndirectCommand).
    pub fn dispatch_indirect(
        &self,
        cmd: vk::CommandBuffer,
        set: usize,
        args: &Buffer,
        offset: u64,
        push: &[u8],
    ) {
        self.bind_for_dispatch(cmd, set, push);
        // SAFETY: `cmd` is being recorded; `args` has INDIRECT_BUFFER usage.
        unsafe { self.ctx.device().cmd_dispatch_indirect(cmd, args.raw, offset) };
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        let device = self.ctx.device();
        // SAFETY: no pending submission uses the pipeline (every submission is waited for);
        // null handles (a failed constructor) are ignored by Vulkan.
        unsafe {
            device.destroy_descriptor_pool(self.pool, None);
            device.destroy_pipeline(self.raw, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
            device.destroy_shader_module(self.module, None);
        }
    }
}
