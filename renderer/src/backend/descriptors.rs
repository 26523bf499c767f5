//! One descriptor set whose resources are bound once, at creation, for a compute or graphics
//! pipeline.
//!
//! Every pass in rrf works on images of a fixed size and on scene buffers made before it, so
//! its resources are known when it is built; binding them then keeps per-frame recording free
//! of descriptor updates.

use ash::vk;

use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::{Buffer, Image};
use crate::error::{Result, VkContext};

/// A resource bound at the binding with the same index as its position in the list.
pub enum Bind<'a> {
    /// A storage image in `GENERAL` layout.
    StorageImage(&'a Image),
    StorageBuffer(&'a Buffer),
    UniformBuffer(&'a Buffer),
    /// An image sampled through a sampler, in `SHADER_READ_ONLY_OPTIMAL` layout.
    Sampled(&'a Image, vk::Sampler),
}

impl Bind<'_> {
    fn descriptor_type(&self) -> vk::DescriptorType {
        match self {
            Bind::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
            Bind::StorageBuffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            Bind::UniformBuffer(_) => vk::DescriptorType::UNIFORM_BUFFER,
            Bind::Sampled(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        }
    }
}

/// The set, its layout and the pool it came from.
pub struct BoundSet {
    pub layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    /// Null when there are no bindings.
    pub set: vk::DescriptorSet,
}

impl BoundSet {
    /// A set of `bindings`, seen by `stages`, pointing at their resources.
    pub fn new(ctx: &Context, name: &str, bindings: &[Bind<'_>], stages: vk::ShaderStageFlags) -> Result<Self> {
        let device = &ctx.device;
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for b in bindings {
            match sizes.iter_mut().find(|s| s.ty == b.descriptor_type()) {
                Some(s) => s.descriptor_count += 1,
                None => sizes.push(vk::DescriptorPoolSize { ty: b.descriptor_type(), descriptor_count: 1 }),
            }
        }
        // Destroyed by the guard if a step fails; null handles are skipped.
        let mut bound = ctx.guard(BoundSet {
            layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
        });
        // Each object made below is destroyed by `destroy`, through the guard if a later
        // step fails.
        let types: Vec<vk::DescriptorType> = bindings.iter().map(Bind::descriptor_type).collect();
        bound.layout = create_set_layout(ctx, &types, stages)?;
        if !sizes.is_empty() {
            let pool_info = vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes);
            // SAFETY: a valid create info that outlives the call.
            bound.pool = unsafe { device.create_descriptor_pool(&pool_info, None) }.vk("vkCreateDescriptorPool")?;
            let set_layouts = [bound.layout];
            let alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(bound.pool).set_layouts(&set_layouts);
            // SAFETY: the pool and the layout were made above; the pool has room for the set.
            bound.set = unsafe { device.allocate_descriptor_sets(&alloc) }.vk("vkAllocateDescriptorSets")?[0];
        }
        // SAFETY: the set was just allocated from this device; the resources belong to it too.
        unsafe { write_set(device, bound.set, bindings) };
        ctx.set_name(bound.layout, name);
        Ok(bound.keep())
    }

    /// Points the set at other resources of the same kinds and order (after a resize). No
    /// submitted command buffer that uses the set may still be pending.
    pub fn rebind(&self, ctx: &Context, bindings: &[Bind<'_>]) {
        // SAFETY: the set belongs to this device and, as the caller guarantees, is not in use.
        unsafe { write_set(&ctx.device, self.set, bindings) };
    }
}

impl Destroy for BoundSet {
    fn destroy(self, ctx: &Context) {
        // SAFETY: no pending GPU work uses the set; null handles are ignored.
        unsafe {
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_descriptor_set_layout(self.layout, None);
        }
    }
}

/// A set layout with one descriptor of each of `types`, at bindings 0, 1, …, seen by `stages`.
/// The caller destroys it.
pub fn create_set_layout(
    ctx: &Context,
    types: &[vk::DescriptorType],
    stages: vk::ShaderStageFlags,
) -> Result<vk::DescriptorSetLayout> {
    let bindings: Vec<_> = types
        .iter()
        .enumerate()
        .map(|(i, ty)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(*ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: a valid create info that outlives the call.
    unsafe { ctx.device.create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")
}

/// Points every binding of `set` at its resource.
unsafe fn write_set(device: &ash::Device, set: vk::DescriptorSet, bindings: &[Bind<'_>]) {
    if set == vk::DescriptorSet::null() {
        return;
    }
    let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
        .iter()
        .map(|b| match b {
            Bind::StorageImage(image) => {
                [vk::DescriptorImageInfo::default().image_view(image.view).image_layout(vk::ImageLayout::GENERAL)]
            }
            Bind::Sampled(image, sampler) => [vk::DescriptorImageInfo::default()
                .image_view(image.view)
                .sampler(*sampler)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
            _ => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
        .iter()
        .map(|b| match b {
            Bind::StorageBuffer(buffer) | Bind::UniformBuffer(buffer) => {
                [vk::DescriptorBufferInfo::default().buffer(buffer.raw).offset(0).range(vk::WHOLE_SIZE)]
            }
            Bind::StorageImage(_) | Bind::Sampled(..) => [vk::DescriptorBufferInfo::default()],
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
                Bind::StorageImage(_) | Bind::Sampled(..) => write.image_info(&image_infos[i]),
                _ => write.buffer_info(&buffer_infos[i]),
            }
        })
        .collect();
    // SAFETY: the set and every resource belong to this device (caller's contract).
    unsafe { device.update_descriptor_sets(&writes, &[]) };
}
