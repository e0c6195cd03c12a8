//! Compute pipelines: one shader pass, a descriptor set layout at bindings 0..n
//! in set 0 (storage buffers unless listed as uniform buffers, uniform texel
//! buffers or combined image samplers; a shader family shares one layout), a
//! push-constant block, specialization constants 0..m (workgroup size first),
//! and descriptor sets bound to buffers, texel views and images by binding index.

use ash::vk;

use super::buffer::Buffer;
use super::check;
use super::commands::Recording;
use super::context::Context;
use super::error::{Error, Result};
use super::texel_view::TexelView;

/// What a compute pipeline is made from.
#[derive(Clone, Copy, Debug)]
pub struct ComputeDesc<'a> {
    /// The compiled pass.
    pub spirv: &'a [u8],
    /// Bindings 0..bindings in the layout: storage buffers, except those below.
    pub bindings: u32,
    /// Bindings that are combined image samplers (`sampler2DArray` and the like).
    pub images: &'a [u32],
    /// Bindings that are uniform buffers.
    pub uniforms: &'a [u32],
    /// Bindings that are uniform texel buffers (`samplerBuffer` and the like).
    pub texels: &'a [u32],
    /// Size of the push-constant block (0: none).
    pub push_bytes: u32,
    /// Values of specialization constants 0, 1, ...
    pub spec: &'a [u32],
    /// Descriptor sets to allocate, each bound to its own buffers and chosen at
    /// dispatch (e.g. the ping-pong passes of a sort).
    pub sets: u32,
    /// The pass relies on every subgroup being full (`gl_SubgroupSize`
    /// invocations, the workgroup `gl_NumSubgroups` whole subgroups). Where the
    /// device can promise it (`DeviceInfo::full_subgroups`) and the workgroup's
    /// size (specialization constant 0) is a multiple of the subgroup size, the
    /// pipeline asks for it.
    pub full_subgroups: bool,
}

/// A compute pipeline with its layout and descriptor sets (`ComputeDesc`).
pub struct ComputePipeline {
    ctx: Context,
    module: vk::ShaderModule,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pool: vk::DescriptorPool,
    sets: Vec<vk::DescriptorSet>,
    /// The pipeline handle.
    pub raw: vk::Pipeline,
    kinds: Vec<vk::DescriptorType>,
    push_bytes: u32,
    full_subgroups: bool,
}

impl ComputePipeline {
    /// Whether the pipeline asks the driver for full subgroups
    /// (`ComputeDesc::full_subgroups` on a device that offers it).
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    pub fn full_subgroups(&self) -> bool {
        self.full_subgroups
    }

    /// The pipeline `desc` describes, with its descriptor sets; an error for a
    /// pass that relies on full subgroups on a device that neither fills them
    /// unasked nor can be asked (`DeviceInfo::fills_subgroups`).
    pub fn new(ctx: &Context, desc: &ComputeDesc) -> Result<Self> {
        let device = ctx.device();
        let words = ash::util::read_spv(&mut std::io::Cursor::new(desc.spirv))
            .map_err(|e| Error::invalid(format!("bad SPIR-V: {e}")))?;
        // SAFETY: the words are SPIR-V embedded from spirv/ (or the caller's).
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
            kinds: (0..desc.bindings)
                .map(|b| {
                    if desc.images.contains(&b) {
                        vk::DescriptorType::COMBINED_IMAGE_SAMPLER
                    } else if desc.uniforms.contains(&b) {
                        vk::DescriptorType::UNIFORM_BUFFER
                    } else if desc.texels.contains(&b) {
                        vk::DescriptorType::UNIFORM_TEXEL_BUFFER
                    } else {
                        vk::DescriptorType::STORAGE_BUFFER
                    }
                })
                .collect(),
            push_bytes: desc.push_bytes,
            full_subgroups: false,
        };
        // Every handle below is destroyed by Drop if a later step fails.
        if let Some(b) =
            desc.images.iter().chain(desc.uniforms).chain(desc.texels).find(|&&b| b >= desc.bindings)
        {
            return Err(Error::invalid(format!("binding {b} is outside the pipeline's {}", desc.bindings)));
        }
        let layout_bindings: Vec<_> = (0..desc.bindings)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(me.kinds[b as usize])
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
        let info = ctx.info();
        let whole = |x: &u32| info.subgroup_size > 0 && x % info.subgroup_size == 0;
        let asks = desc.full_subgroups && info.full_subgroups && desc.spec.first().is_some_and(whole);
        if desc.full_subgroups && !asks && !info.fills_subgroups() {
            return Err(Error::VulkanUnavailable(format!(
                "{} may run a workgroup in subgroups smaller than its {}, which these passes cannot take: \
                 enable computeFullSubgroups (VK_EXT_subgroup_size_control) on the device",
                info.name, info.subgroup_size
            )));
        }
        me.full_subgroups = asks;
        let flags = match asks {
            true => vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS_EXT,
            false => vk::PipelineShaderStageCreateFlags::empty(),
        };
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .flags(flags)
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(me.layout);
        // SAFETY: the module, layout and specialization data are alive during the call.
        me.raw = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, result)| Error::Vulkan { call: "vkCreateComputePipelines", result })?[0];
        let sizes: Vec<_> = [
            vk::DescriptorType::STORAGE_BUFFER,
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        ]
        .into_iter()
        .map(|ty| {
            let count = me.kinds.iter().filter(|&&k| k == ty).count() as u32;
            vk::DescriptorPoolSize::default().ty(ty).descriptor_count(count.max(1) * desc.sets.max(1))
        })
        .collect();
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

    /// Descriptor set `set`, checked to exist, and each binding checked to be one
    /// of `kinds` (`what` names them in the error).
    fn set_for(
        &self,
        set: usize,
        bindings: &[u32],
        kinds: &[vk::DescriptorType],
        what: &str,
    ) -> Result<vk::DescriptorSet> {
        let target = *self
            .sets
            .get(set)
            .ok_or_else(|| Error::invalid(format!("the pipeline has no descriptor set {set}")))?;
        for &b in bindings {
            let found = self.kinds.get(b as usize).ok_or_else(|| {
                Error::invalid(format!("binding {b} is outside the pipeline's {} bindings", self.kinds.len()))
            })?;
            if !kinds.contains(found) {
                return Err(Error::invalid(format!("binding {b} is a {found:?}, not a {what}")));
            }
        }
        Ok(target)
    }

    /// Points the given bindings of descriptor set `set` at whole buffers. A
    /// binding the pass does not use may stay unbound.
    ///
    /// # Safety
    /// Each buffer outlives every dispatch that uses the set while it is bound
    /// there (until the binding points elsewhere or the pipeline is dropped).
    pub unsafe fn bind(&self, set: usize, buffers: &[(u32, &Buffer)]) -> Result<()> {
        let raw: Vec<(u32, vk::Buffer)> = buffers.iter().map(|(b, buffer)| (*b, buffer.raw)).collect();
        // SAFETY: the caller's promise, for buffers of this context's device.
        unsafe { self.bind_raw(set, &raw) }
    }

    /// As `bind`, for buffers fsot did not make (a host's).
    ///
    /// # Safety
    /// Each handle is a live buffer of the context's device, with the usage its
    /// binding needs, that outlives every dispatch that uses the set while it
    /// is bound there.
    pub unsafe fn bind_raw(&self, set: usize, buffers: &[(u32, vk::Buffer)]) -> Result<()> {
        let bindings: Vec<u32> = buffers.iter().map(|(b, _)| *b).collect();
        let kinds = [vk::DescriptorType::STORAGE_BUFFER, vk::DescriptorType::UNIFORM_BUFFER];
        let target = self.set_for(set, &bindings, &kinds, "buffer")?;
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, b)| [vk::DescriptorBufferInfo::default().buffer(*b).offset(0).range(vk::WHOLE_SIZE)])
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .zip(buffers)
            .map(|(info, (binding, _))| {
                vk::WriteDescriptorSet::default()
                    .dst_set(target)
                    .dst_binding(*binding)
                    .descriptor_type(self.kinds[*binding as usize])
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use by a pending submission (every submission is waited for).
        unsafe { self.ctx.device().update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Points a combined image-sampler binding of set `set` at an image view
    /// (in `layout` when the pass runs) and a sampler.
    ///
    /// # Safety
    /// The view and the sampler are live objects of the context's device that
    /// outlive every dispatch that uses the set while they are bound there, and
    /// the image is in `layout` whenever such a dispatch runs.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    pub unsafe fn bind_image(
        &self,
        set: usize,
        binding: u32,
        view: vk::ImageView,
        sampler: vk::Sampler,
        layout: vk::ImageLayout,
    ) -> Result<()> {
        let target = self.set_for(set, &[binding], &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER], "image")?;
        let info =
            [vk::DescriptorImageInfo::default().image_view(view).sampler(sampler).image_layout(layout)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(target)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&info);
        // SAFETY: the set is not in use by a pending submission; the view and
        // sampler are alive (the caller keeps them while the set is used).
        unsafe { self.ctx.device().update_descriptor_sets(&[write], &[]) };
        Ok(())
    }

    /// Points the given uniform-texel-buffer bindings of set `set` at texel
    /// views.
    ///
    /// # Safety
    /// The views and their buffers outlive every dispatch that uses the set
    /// while they are bound there.
    pub unsafe fn bind_texels(&self, set: usize, views: &[(u32, &TexelView)]) -> Result<()> {
        let bindings: Vec<u32> = views.iter().map(|(b, _)| *b).collect();
        let target =
            self.set_for(set, &bindings, &[vk::DescriptorType::UNIFORM_TEXEL_BUFFER], "texel buffer")?;
        let raw: Vec<[vk::BufferView; 1]> = views.iter().map(|(_, v)| [v.raw]).collect();
        let writes: Vec<_> = raw
            .iter()
            .zip(views)
            .map(|(view, (binding, _))| {
                vk::WriteDescriptorSet::default()
                    .dst_set(target)
                    .dst_binding(*binding)
                    .descriptor_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                    .texel_buffer_view(view)
            })
            .collect();
        // SAFETY: the set is not in use by a pending submission; the views are alive.
        unsafe { self.ctx.device().update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Binds the pipeline, descriptor set `set` and the push constants. Panics
    /// for push constants of another size than the pipeline's, or a set it has
    /// not.
    fn bind_for_dispatch(&self, cmd: Recording<'_>, set: usize, push: &[u8]) {
        assert!(
            push.len() == self.push_bytes as usize && set < self.sets.len(),
            "a dispatch with {} bytes of push constants and set {set}; the pipeline has {} and {} sets",
            push.len(),
            self.push_bytes,
            self.sets.len()
        );
        let device = self.ctx.device();
        // SAFETY: `cmd` is being recorded; the set index and the push range are checked above.
        unsafe {
            device.cmd_bind_pipeline(cmd.raw(), vk::PipelineBindPoint::COMPUTE, self.raw);
            device.cmd_bind_descriptor_sets(
                cmd.raw(),
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[self.sets[set]],
                &[],
            );
            if self.push_bytes > 0 {
                device.cmd_push_constants(cmd.raw(), self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
        }
    }

    /// Records a dispatch of `groups` workgroups with descriptor set `set` and
    /// push constants `push` (`bytemuck::bytes_of` of the pass's push struct).
    pub fn dispatch(&self, cmd: Recording<'_>, set: usize, groups: [u32; 3], push: &[u8]) {
        self.bind_for_dispatch(cmd, set, push);
        // SAFETY: `cmd` is being recorded with this pipeline bound.
        unsafe { self.ctx.device().cmd_dispatch(cmd.raw(), groups[0], groups[1], groups[2]) };
    }

    /// Records a dispatch whose size the GPU wrote into `args` at `offset` (a
    /// VkDispatchIndirectCommand).
    pub fn dispatch_indirect(&self, cmd: Recording<'_>, set: usize, args: &Buffer, offset: u64, push: &[u8]) {
        self.bind_for_dispatch(cmd, set, push);
        // SAFETY: `cmd` is being recorded; `args` has INDIRECT_BUFFER usage.
        unsafe { self.ctx.device().cmd_dispatch_indirect(cmd.raw(), args.raw, offset) };
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
