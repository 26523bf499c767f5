//! A compute pipeline with one descriptor set whose resources are bound once, at creation.
//!
//! Every pass in rrf works on images of a fixed size, so its resources are known when it is
//! built; binding them then keeps per-frame recording free of descriptor updates.

use ash::vk;

use crate::context::Context;
use crate::error::{Result, VkContext};
use crate::resources::{Buffer, Image};

/// A resource bound at the binding with the same index as its position in the list.
pub enum Bind<'a> {
    /// A storage image in `GENERAL` layout.
    StorageImage(&'a Image),
    StorageBuffer(&'a Buffer),
    UniformBuffer(&'a Buffer),
}

impl Bind<'_> {
    fn descriptor_type(&self) -> vk::DescriptorType {
        match self {
            Bind::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
            Bind::StorageBuffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            Bind::UniformBuffer(_) => vk::DescriptorType::UNIFORM_BUFFER,
        }
    }
}

pub struct ComputePass {
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    /// Local workgroup size in x and y, as declared by the shader.
    workgroup: (u32, u32),
}

impl ComputePass {
    /// Builds the pipeline from SPIR-V with entry point `main`, a push-constant block of
    /// `push_bytes`, and `bindings` in binding order. `workgroup` must match the shader's
    /// `local_size_x/y`.
    pub fn new(
        ctx: &Context,
        name: &str,
        spirv: &[u32],
        bindings: &[Bind<'_>],
        push_bytes: u32,
        workgroup: (u32, u32),
    ) -> Result<Self> {
        let device = &ctx.device;
        let layout_bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(b.descriptor_type())
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: all create infos are valid and outlive their calls; every object is
        // destroyed in `destroy`.
        unsafe {
            let set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                    None,
                )
                .vk("vkCreateDescriptorSetLayout")?;
            let push = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .offset(0)
                .size(push_bytes)];
            let set_layouts = [set_layout];
            let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if push_bytes > 0 {
                layout_info = layout_info.push_constant_ranges(&push);
            }
            let layout = device.create_pipeline_layout(&layout_info, None).vk("vkCreatePipelineLayout")?;

            let module = device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(spirv), None)
                .vk("vkCreateShaderModule")?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
            let pipeline = device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None);
            device.destroy_shader_module(module, None);
            let pipeline = pipeline.map_err(|(_, e)| e).vk("vkCreateComputePipelines")?[0];

            let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
            for b in bindings {
                match sizes.iter_mut().find(|s| s.ty == b.descriptor_type()) {
                    Some(s) => s.descriptor_count += 1,
                    None => sizes.push(vk::DescriptorPoolSize { ty: b.descriptor_type(), descriptor_count: 1 }),
                }
            }
            let pool = if sizes.is_empty() {
                vk::DescriptorPool::null()
            } else {
                device
                    .create_descriptor_pool(
                        &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                        None,
                    )
                    .vk("vkCreateDescriptorPool")?
            };
            let set = if sizes.is_empty() {
                vk::DescriptorSet::null()
            } else {
                device
                    .allocate_descriptor_sets(
                        &vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&set_layouts),
                    )
                    .vk("vkAllocateDescriptorSets")?[0]
            };
            write_set(device, set, bindings);

            ctx.set_name(pipeline, name);
            ctx.set_name(layout, name);
            ctx.set_name(set_layout, name);
            Ok(Self { pipeline, layout, set_layout, pool, set, workgroup })
        }
    }

    /// Records a dispatch that covers `width × height` invocations, rounded up to whole
    /// workgroups; the shader skips invocations outside the image.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, push: &[u8], width: u32, height: u32) {
        let device = &ctx.device;
        // SAFETY: `cmd` is recording; the pipeline, layout and set belong to this device.
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            if self.set != vk::DescriptorSet::null() {
                device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[self.set], &[]);
            }
            if !push.is_empty() {
                device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            device.cmd_dispatch(cmd, width.div_ceil(self.workgroup.0), height.div_ceil(self.workgroup.1), 1);
        }
    }

    pub fn destroy(self, ctx: &Context) {
        let device = &ctx.device;
        // SAFETY: the caller has finished all GPU work that uses the pass.
        unsafe {
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_pool(self.pool, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Points every binding of `set` at its resource.
unsafe fn write_set(device: &ash::Device, set: vk::DescriptorSet, bindings: &[Bind<'_>]) {
    let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
        .iter()
        .map(|b| match b {
            Bind::StorageImage(image) => {
                [vk::DescriptorImageInfo::default().image_view(image.view).image_layout(vk::ImageLayout::GENERAL)]
            }
            _ => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
        .iter()
        .map(|b| match b {
            Bind::StorageBuffer(buffer) | Bind::UniformBuffer(buffer) => {
                [vk::DescriptorBufferInfo::default().buffer(buffer.raw).offset(0).range(vk::WHOLE_SIZE)]
            }
            Bind::StorageImage(_) => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let writes: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(i as u32)
                .descriptor_type(b.descriptor_type());
            match b {
                Bind::StorageImage(_) => write.image_info(&image_infos[i]),
                _ => write.buffer_info(&buffer_infos[i]),
            }
        })
        .collect();
    // SAFETY: the set and every resource belong to this device (caller's contract).
    unsafe { device.update_descriptor_sets(&writes, &[]) };
}
