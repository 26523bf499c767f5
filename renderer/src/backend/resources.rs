//! Buffers and 2D images with their memory, and the transfers between them and the CPU.
//!
//! Resources are destroyed explicitly through the context that made them; a resource still
//! alive at [`Context::finish`](crate::Context::finish) is reported as a leak by name.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::error::{Error, Result, VkContext};

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Allocation,
}

impl Buffer {
    /// The buffer's bytes, for host-visible buffers.
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.mapped_slice().map(|s| &s[..self.size as usize])
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation.mapped_slice_mut().map(|s| &mut s[..size])
    }
}

/// A 2D image with one mip level, and a view of all of it when its usage allows views
/// (a transfer-only image has a null view).
pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    allocation: Allocation,
}

impl Image {
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.format)
    }

    /// Bytes per texel of the formats rrf uses (0 for others).
    pub fn texel_bytes(&self) -> u32 {
        texel_bytes(self.format)
    }

    pub fn pixel_count(&self) -> usize {
        self.extent.width as usize * self.extent.height as usize
    }
}

impl Destroy for Buffer {
    fn destroy(self, ctx: &Context) {
        ctx.destroy_buffer(self);
    }
}

impl Destroy for Image {
    fn destroy(self, ctx: &Context) {
        ctx.destroy_image(self);
    }
}

/// Bytes per texel of the formats rrf uses (0 for others).
fn texel_bytes(format: vk::Format) -> u32 {
    match format {
        vk::Format::R32G32B32A32_SFLOAT => 16,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32A32_UINT => 16,
        vk::Format::R32_SFLOAT | vk::Format::R32_UINT | vk::Format::D32_SFLOAT => 4,
        vk::Format::R8G8B8A8_UNORM | vk::Format::B8G8R8A8_UNORM => 4,
        _ => 0,
    }
}

/// How the channels of a format that can be read back are stored.
#[derive(Clone, Copy)]
enum Channel {
    F32,
    U32,
    Unorm8,
}

impl Channel {
    /// The channel type and channel count of `format`, if it can be read back.
    fn of(format: vk::Format) -> Option<(Channel, usize)> {
        match format {
            vk::Format::R32G32B32A32_SFLOAT => Some((Channel::F32, 4)),
            vk::Format::R32_SFLOAT => Some((Channel::F32, 1)),
            vk::Format::R32_UINT => Some((Channel::U32, 1)),
            vk::Format::R32G32B32A32_UINT => Some((Channel::U32, 4)),
            vk::Format::R8G8B8A8_UNORM => Some((Channel::Unorm8, 4)),
            _ => None,
        }
    }

    fn bytes(self) -> usize {
        match self {
            Channel::F32 | Channel::U32 => 4,
            Channel::Unorm8 => 1,
        }
    }

    fn decode(self, b: &[u8]) -> f32 {
        match self {
            Channel::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            // The bits, unchanged: `f32::to_bits` gives the integer back.
            Channel::U32 => f32::from_bits(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Channel::Unorm8 => f32::from(b[0]) / 255.0,
        }
    }
}

const GIB: f64 = (1u64 << 30) as f64;

impl Context {
    pub fn create_buffer(
        &self,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        let info =
            vk::BufferCreateInfo::default().size(size.max(4)).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        self.step("vkCreateBuffer")?;
        // SAFETY: valid create info; the buffer is bound to memory before use.
        let raw = unsafe { self.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: a query on the buffer just made.
        let requirements = unsafe { self.device.get_buffer_memory_requirements(raw) };
        // SAFETY: the buffer has no memory and no user yet.
        let allocation =
            self.allocate(name, requirements, location, true, || unsafe { self.device.destroy_buffer(raw, None) })?;
        let buffer = Buffer { raw, size, allocation };
        if let Err(e) =
            // SAFETY: the allocation was made for this buffer's requirements.
            unsafe {
                self.device.bind_buffer_memory(raw, buffer.allocation.memory(), buffer.allocation.offset())
            }
        {
            self.destroy_buffer(buffer);
            return Err(e).vk("vkBindBufferMemory");
        }
        self.set_name(raw, name);
        Ok(buffer)
    }

    /// A shader module of `spirv` (the build script's glslang output), for making pipelines;
    /// destroy it with [`Context::destroy_shader_module`] once they are made.
    pub(crate) fn create_shader_module(&self, spirv: &[u32]) -> Result<vk::ShaderModule> {
        let info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: the create info outlives the call; the words are glslang's validated SPIR-V.
        unsafe { self.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")
    }

    /// Destroys a module made by [`Context::create_shader_module`].
    pub(crate) fn destroy_shader_module(&self, module: vk::ShaderModule) {
        // SAFETY: pipelines made from a module do not need it afterwards; null is ignored.
        unsafe { self.device.destroy_shader_module(module, None) };
    }

    /// Memory for an object with `requirements` (`linear`: a buffer, not an optimally tiled
    /// image). If there is none, `release` destroys the object before the error returns.
    fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
        release: impl FnOnce(),
    ) -> Result<Allocation> {
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        self.allocator().allocate(&desc).map_err(|source| {
            release();
            Error::Allocation { name: name.to_string(), bytes: requirements.size, source }
        })
    }

    pub fn destroy_buffer(&self, buffer: Buffer) {
        // SAFETY: the caller has finished all GPU work that uses the buffer.
        unsafe { self.device.destroy_buffer(buffer.raw, None) };
        let _ = self.allocator().free(buffer.allocation);
    }

    /// A host-visible buffer filled with `data`.
    pub fn create_buffer_with_data(&self, name: &str, data: &[u8], usage: vk::BufferUsageFlags) -> Result<Buffer> {
        let mut buffer = self.create_buffer(name, data.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        match buffer.mapped_mut() {
            Some(bytes) => bytes.copy_from_slice(data),
            None => {
                self.destroy_buffer(buffer);
                return Err(Error::Invalid(format!("buffer {name:?} is not host-visible")));
            }
        }
        Ok(buffer)
    }

    pub fn create_image(
        &self,
        name: &str,
        extent: vk::Extent2D,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Image> {
        let max = self.info.limits.max_image_dimension_2d;
        if extent.width == 0 || extent.height == 0 || extent.width > max || extent.height > max {
            return Err(Error::Invalid(format!(
                "image {name:?}: size {}x{} is outside 1..={max} on this device",
                extent.width, extent.height
            )));
        }
        // Images too large for the device are refused with their size, before Vulkan is asked.
        // SAFETY: a query on the context's own physical device.
        let limits = unsafe {
            self.instance.get_physical_device_image_format_properties(
                self.physical_device,
                format,
                vk::ImageType::TYPE_2D,
                vk::ImageTiling::OPTIMAL,
                usage,
                vk::ImageCreateFlags::empty(),
            )
        }
        .map_err(|e| Error::Invalid(format!("image {name:?}: {format:?} for {usage:?} is not supported here ({e})")))?;
        let bytes = u64::from(extent.width) * u64::from(extent.height) * u64::from(texel_bytes(format));
        if bytes >= limits.max_resource_size {
            return Err(Error::Invalid(format!(
                "image {name:?} of {}x{} {format:?} would take {:.2} GiB, and this device allows less than {:.2} GiB \
                 for one image; use a smaller size",
                extent.width,
                extent.height,
                bytes as f64 / GIB,
                limits.max_resource_size as f64 / GIB
            )));
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        self.step("vkCreateImage")?;
        // SAFETY: valid create info; memory is bound before the view is made.
        let raw = unsafe { self.device.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: a query on the image just made.
        let requirements = unsafe { self.device.get_image_memory_requirements(raw) };
        // SAFETY: the image has no memory and no user yet.
        let allocation = self.allocate(name, requirements, MemoryLocation::GpuOnly, false, || unsafe {
            self.device.destroy_image(raw, None)
        })?;
        // Destroyed on every early return below; the view is null until it is made.
        let mut image = self.guard(Image { raw, view: vk::ImageView::null(), format, extent, allocation });
        // SAFETY: the allocation was made for this image's requirements.
        unsafe { self.device.bind_image_memory(raw, image.allocation.memory(), image.allocation.offset()) }
            .vk("vkBindImageMemory")?;
        let viewable = vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
        if usage.intersects(viewable) {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(full_range(aspect_of(format)));
            // SAFETY: the image is bound to memory; its usage allows a view of this format.
            image.view = unsafe { self.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
            self.set_name(image.view, name);
        }
        self.set_name(raw, name);
        Ok(image.keep())
    }

    pub fn destroy_image(&self, image: Image) {
        // SAFETY: the caller has finished all GPU work that uses the image.
        unsafe {
            if image.view != vk::ImageView::null() {
                self.device.destroy_image_view(image.view, None);
            }
            self.device.destroy_image(image.raw, None);
        }
        let _ = self.allocator().free(image.allocation);
    }

    /// Records a layout transition that waits for all earlier work and blocks all later work.
    /// Coarse on purpose: it is for set-up and read-back, not for per-frame pass boundaries.
    pub fn transition(&self, cmd: vk::CommandBuffer, image: &Image, from: vk::ImageLayout, to: vk::ImageLayout) {
        let barrier = vk::ImageMemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
            .old_layout(from)
            .new_layout(to)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(full_range(aspect_of(image.format)));
        // SAFETY: `cmd` is recording and the image belongs to this device.
        unsafe {
            self.device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[barrier],
            )
        };
    }

    /// Uploads RGBA f32 pixels into an `R32G32B32A32_SFLOAT` image (usage `TRANSFER_DST`) and
    /// leaves it in `GENERAL` layout, ready for a compute pass.
    pub fn upload_rgba32f(&self, image: &Image, pixels: &[[f32; 4]]) -> Result<()> {
        if image.format != vk::Format::R32G32B32A32_SFLOAT || pixels.len() != image.pixel_count() {
            return Err(Error::Invalid(format!(
                "upload_rgba32f: {} pixels into a {:?} image of {}x{}",
                pixels.len(),
                image.format,
                image.extent.width,
                image.extent.height
            )));
        }
        let staging = self.create_buffer_with_data(
            "upload staging",
            bytemuck::cast_slice(pixels),
            vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        let result = self.submit_once(|cmd| {
            self.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            let region = copy_region(image);
            // SAFETY: the staging buffer holds exactly the image's texels.
            unsafe {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            self.transition(cmd, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::GENERAL);
        });
        self.destroy_buffer(staging);
        result
    }

    /// A host-visible buffer the size of `image`'s pixels, for [`copy_to_buffer`] and
    /// [`Context::decode`].
    pub fn create_readback_buffer(&self, image: &Image) -> Result<Buffer> {
        let Some((channel, channels)) = Channel::of(image.format) else {
            return Err(Error::Invalid(format!("format {:?} cannot be read back", image.format)));
        };
        let size = (image.pixel_count() * channels * channel.bytes()) as u64;
        self.create_buffer("read-back staging", size, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)
    }

    /// The pixels `copy_to_buffer` copied from an image of `format` into `buffer`, as floats,
    /// row-major, all channels. 8-bit UNORM channels become `byte / 255`. Call it after the
    /// copy's submission has finished.
    pub fn decode(&self, format: vk::Format, buffer: &Buffer) -> Result<Vec<f32>> {
        let Some((channel, _)) = Channel::of(format) else {
            return Err(Error::Invalid(format!("format {format:?} cannot be read back")));
        };
        buffer
            .mapped()
            .map(|bytes| bytes.chunks_exact(channel.bytes()).map(|b| channel.decode(b)).collect())
            .ok_or_else(|| Error::Invalid("read-back buffer is not host-visible".into()))
    }

    /// Reads an image (usage `TRANSFER_SRC`, currently in `layout`) back as floats, row-major,
    /// all channels (the bits of integer channels: `f32::to_bits` gives them back); the image is
    /// left in `layout`. For set-up and tests; frames read back
    /// through [`copy_to_buffer`] passes.
    pub fn read_image(&self, image: &Image, layout: vk::ImageLayout) -> Result<Vec<f32>> {
        let staging = self.create_readback_buffer(image)?;
        let copied = self.submit_once(|cmd| {
            self.transition(cmd, image, layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
            copy_to_buffer(self, cmd, image, &staging);
            self.transition(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, layout);
        });
        let values = copied.and_then(|()| self.decode(image.format, &staging));
        self.destroy_buffer(staging);
        values
    }
}

/// Records a copy of all of `image` (in `TRANSFER_SRC_OPTIMAL`) into `buffer`, which
/// [`Context::create_readback_buffer`] made for it.
pub fn copy_to_buffer(ctx: &Context, cmd: vk::CommandBuffer, image: &Image, buffer: &Buffer) {
    // SAFETY: `cmd` is recording; the buffer holds exactly the image's texels.
    unsafe {
        ctx.device.cmd_copy_image_to_buffer(
            cmd,
            image.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[copy_region(image)],
        )
    };
}

fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
        _ => vk::ImageAspectFlags::COLOR,
    }
}

fn full_range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn copy_region(image: &Image) -> vk::BufferImageCopy {
    copy_rect(image, vk::Rect2D { offset: vk::Offset2D::default(), extent: image.extent })
}

/// A copy between `rect` of `image` and a buffer that holds its texels tightly packed from
/// offset 0.
pub(crate) fn copy_rect(image: &Image, rect: vk::Rect2D) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: aspect_of(image.format),
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_offset(vk::Offset3D { x: rect.offset.x, y: rect.offset.y, z: 0 })
        .image_extent(vk::Extent3D { width: rect.extent.width, height: rect.extent.height, depth: 1 })
}
