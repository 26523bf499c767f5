//! Immediate-mode user interface drawn over the display image: indexed triangles with a colour
//! per vertex, each draw clipped to a rectangle and tinting one RGBA8 texture (`ui.vert`,
//! `ui.frag`). This is what a UI library such as egui hands a renderer each frame, in plain
//! types, so that the renderer does not depend on one.
//!
//! Colours and texels are sRGB-encoded with premultiplied alpha, and blending happens on the
//! encoded values, as the display image holds them (the blending egui's text is tuned for).

use std::collections::HashMap;

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use crate::backend::context::Context;
use crate::backend::descriptors::{create_set_layout, Bind, BoundSet};
use crate::backend::frames::FRAMES_IN_FLIGHT;
use crate::backend::guard::Destroy;
use crate::backend::resources::{copy_rect, Buffer, Image};
use crate::backend::sync::{Access, Pass, Resource, Use};
use crate::error::{Result, VkContext};
use crate::passes::raster::with_stages;

/// A vertex: position in points from the top-left corner, texture coordinates, and an
/// sRGB-encoded premultiplied colour (egui's `Vertex` has this layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct UiVertex {
    pub pos: [f32; 2],
    pub uv: [f32; 2],
    pub colour: [u8; 4],
}

/// One draw: `index_count` indices from `first_index`, added to `vertex_offset`, textured by
/// `texture` and clipped to `clip` (in pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UiDraw {
    pub texture: u64,
    pub clip: vk::Rect2D,
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
}

/// New texels for a texture: the whole texture (`offset` none), which makes it anew, or a
/// rectangle of it at `offset`. `rgba` holds `size[0] × size[1]` texels, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct UiTexels {
    pub texture: u64,
    pub offset: Option<[u32; 2]>,
    pub size: [u32; 2],
    pub rgba: Vec<u8>,
}

/// What the UI draws in one frame.
#[derive(Clone, Debug, Default)]
pub struct UiFrame {
    /// The screen's size in points (pixels divided by the scale factor).
    pub screen_points: [f32; 2],
    /// Texture changes, applied before the draws.
    pub texels: Vec<UiTexels>,
    pub vertices: Vec<UiVertex>,
    pub indices: Vec<u32>,
    pub draws: Vec<UiDraw>,
    /// Textures no longer needed, freed after the draws.
    pub freed: Vec<u64>,
}

struct UiTexture {
    image: Image,
    set: BoundSet,
}

impl Destroy for UiTexture {
    fn destroy(self, ctx: &Context) {
        self.set.destroy(ctx);
        ctx.destroy_image(self.image);
    }
}

/// A frame slot's vertex and index buffers, host-visible, grown when a frame needs more.
#[derive(Default)]
struct SlotBuffers {
    vertices: Option<Buffer>,
    indices: Option<Buffer>,
}

/// Texels on their way to a texture: a staging buffer, and where in the texture they go.
struct Upload {
    texture: u64,
    staging: Buffer,
    rect: vk::Rect2D,
}

/// Staging buffers that a submitted frame copies from, to destroy once it has finished.
pub struct UiStaging(Vec<Buffer>);

impl Destroy for UiStaging {
    fn destroy(self, ctx: &Context) {
        self.0.destroy(ctx);
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    screen_points: [f32; 2],
}

pub struct UiPass {
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    sampler: vk::Sampler,
    textures: HashMap<u64, UiTexture>,
    /// Textures a frame freed, destroyed when the next frame is prepared.
    freed: Vec<u64>,
    /// Texels given to [`UiPass::prepare`] that no submitted frame has copied yet.
    pending: Vec<Upload>,
    slots: [SlotBuffers; FRAMES_IN_FLIGHT],
}

/// The format of the display image the pass draws on.
const TARGET_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

impl UiPass {
    /// The pipeline of `ui.vert` and `ui.frag` (`vertex`, `fragment`), drawing on RGBA8 images.
    pub fn new(ctx: &Context, vertex: &[u32], fragment: &[u32]) -> Result<Self> {
        let mut pass = ctx.guard(UiPass {
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            sampler: vk::Sampler::null(),
            textures: HashMap::new(),
            freed: Vec::new(),
            pending: Vec::new(),
            slots: Default::default(),
        });
        pass.set_layout =
            create_set_layout(ctx, &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER], vk::ShaderStageFlags::FRAGMENT)?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX)
            .size(std::mem::size_of::<Push>() as u32)];
        let set_layouts = [pass.set_layout];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&ranges);
        // SAFETY: a valid create info that outlives the call.
        pass.layout = unsafe { ctx.device.create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        let sampler = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        // SAFETY: as above.
        pass.sampler = unsafe { ctx.device.create_sampler(&sampler, None) }.vk("vkCreateSampler")?;
        pass.pipeline = create_pipeline(ctx, pass.layout, vertex, fragment)?;
        ctx.set_name(pass.pipeline, "ui");
        Ok(pass.keep())
    }

    /// Applies `frame`'s texture changes and writes its vertices and indices to the buffers of
    /// frame slot `slot`, whose previous frame must have finished. Destroying a texture (one
    /// the previous frame freed, or one made anew) waits for every frame in flight
    /// (`wait_all`) first: that is rare (a new font size), and the texels of a rectangle go
    /// through the frame itself, in [`UiPass::passes`]. Returns the images it made, which the
    /// frame's barrier tracker has not seen (their handles may repeat a destroyed image's,
    /// whose state it must forget).
    pub fn prepare(
        &mut self,
        ctx: &Context,
        slot: usize,
        frame: &UiFrame,
        wait_all: &mut dyn FnMut() -> Result<()>,
    ) -> Result<Vec<Resource>> {
        if !self.freed.is_empty() {
            wait_all()?;
            for id in std::mem::take(&mut self.freed) {
                self.textures.remove(&id).destroy(ctx);
            }
        }
        self.freed.extend(&frame.freed);
        let mut made = Vec::new();
        self.upload_texels(ctx, frame, &mut made, wait_all)?;
        self.write_geometry(ctx, slot, frame)?;
        Ok(made)
    }

    fn upload_texels(
        &mut self,
        ctx: &Context,
        frame: &UiFrame,
        made: &mut Vec<Resource>,
        wait_all: &mut dyn FnMut() -> Result<()>,
    ) -> Result<()> {
        for texels in &frame.texels {
            let [width, height] = texels.size;
            if texels.rgba.len() != (width as usize) * (height as usize) * 4 || width == 0 || height == 0 {
                return Err(crate::Error::Invalid(format!(
                    "UI texture {}: {} bytes for {width}x{height} texels",
                    texels.texture,
                    texels.rgba.len()
                )));
            }
            let offset = match texels.offset {
                Some(offset) => {
                    let fits = self.textures.get(&texels.texture).is_some_and(|t| {
                        offset[0] + width <= t.image.extent.width && offset[1] + height <= t.image.extent.height
                    });
                    if !fits {
                        return Err(crate::Error::Invalid(format!(
                            "UI texture {}: texels at {offset:?} outside the texture",
                            texels.texture
                        )));
                    }
                    offset
                }
                None => {
                    let extent = vk::Extent2D { width, height };
                    let texture = self.create_texture(ctx, extent)?;
                    made.push(Resource::image(&texture.image));
                    if let Some(old) = self.textures.insert(texels.texture, texture) {
                        // Texels still pending for the old texture go nowhere now.
                        let (stale, pending) = std::mem::take(&mut self.pending)
                            .into_iter()
                            .partition(|u: &Upload| u.texture == texels.texture);
                        self.pending = pending;
                        wait_all()?;
                        old.destroy(ctx);
                        for upload in stale {
                            ctx.destroy_buffer(upload.staging);
                        }
                    }
                    [0, 0]
                }
            };
            let staging = ctx.create_buffer_with_data("ui texels", &texels.rgba, vk::BufferUsageFlags::TRANSFER_SRC)?;
            let rect = vk::Rect2D {
                offset: vk::Offset2D { x: offset[0] as i32, y: offset[1] as i32 },
                extent: vk::Extent2D { width, height },
            };
            self.pending.push(Upload { texture: texels.texture, staging, rect });
        }
        Ok(())
    }

    fn create_texture(&self, ctx: &Context, extent: vk::Extent2D) -> Result<UiTexture> {
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let image = ctx.guard(ctx.create_image("ui texture", extent, vk::Format::R8G8B8A8_UNORM, usage)?);
        let set =
            BoundSet::new(ctx, "ui texture", &[Bind::Sampled(&image, self.sampler)], vk::ShaderStageFlags::FRAGMENT)?;
        Ok(UiTexture { image: image.keep(), set })
    }

    /// Copies the frame's vertices and indices into slot `slot`'s buffers, made larger first
    /// if they are too small.
    fn write_geometry(&mut self, ctx: &Context, slot: usize, frame: &UiFrame) -> Result<()> {
        let buffers = &mut self.slots[slot];
        let vertices: &[u8] = bytemuck::cast_slice(&frame.vertices);
        let indices: &[u8] = bytemuck::cast_slice(&frame.indices);
        for (buffer, bytes, usage, name) in [
            (&mut buffers.vertices, vertices, vk::BufferUsageFlags::VERTEX_BUFFER, "ui vertices"),
            (&mut buffers.indices, indices, vk::BufferUsageFlags::INDEX_BUFFER, "ui indices"),
        ] {
            if buffer.as_ref().is_none_or(|b| b.size < bytes.len() as u64) {
                // The slot's previous frame, the only one that used the buffer, has finished.
                buffer.take().destroy(ctx);
                // Room for twice as much, so that a growing UI does not remake it each frame.
                let size = (bytes.len() as u64 * 2).max(64 * 1024);
                *buffer = Some(ctx.create_buffer(name, size, usage, MemoryLocation::CpuToGpu)?);
            }
            let mapped = buffer.as_mut().and_then(Buffer::mapped_mut).expect("CpuToGpu buffers are mapped");
            mapped[..bytes.len()].copy_from_slice(bytes);
        }
        Ok(())
    }

    /// The passes that copy the pending texels into their textures and draw `frame` over
    /// `display` (RGBA8, in `GENERAL` layout) from slot `slot`'s buffers, as
    /// [`UiPass::prepare`] left them. Once the frame is submitted, [`UiPass::submitted`] hands
    /// over the staging buffers; until then the texels stay pending.
    pub fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        display: &'a Image,
        slot: usize,
        frame: &UiFrame,
    ) -> Result<Vec<Pass<'a>>> {
        let mut passes = Vec::new();
        for Upload { texture, staging, rect } in &self.pending {
            let image = &self.texture(*texture)?.image;
            let uses = vec![Use::buffer(staging, Access::TRANSFER_READ), Use::image(image, Access::TRANSFER_WRITE)];
            passes.push(Pass::new("ui texels", uses, move |cmd| copy_texels(ctx, cmd, staging, image, *rect)));
        }
        let buffers = &self.slots[slot];
        let (Some(vertices), Some(indices)) = (&buffers.vertices, &buffers.indices) else {
            return Ok(passes);
        };
        if frame.draws.is_empty() {
            return Ok(passes);
        }
        let mut uses = vec![
            Use::image(display, Access::COLOR_ATTACHMENT_BLEND),
            Use::buffer(vertices, Access::VERTEX_INDEX_READ),
            Use::buffer(indices, Access::VERTEX_INDEX_READ),
        ];
        let mut draws = Vec::with_capacity(frame.draws.len());
        for draw in &frame.draws {
            let texture = self.texture(draw.texture)?;
            // The tracker merges a texture's repeated uses.
            uses.push(Use::image(&texture.image, Access::FRAGMENT_SAMPLED));
            draws.push((*draw, texture.set.set));
        }
        let push = Push { screen_points: frame.screen_points };
        passes.push(Pass::new("ui", uses, move |cmd| {
            self.record(ctx, cmd, display, (vertices, indices), &draws, push);
        }));
        Ok(passes)
    }

    /// The staging buffers of the frame just submitted (or that may have been), to destroy
    /// once it has finished.
    pub fn submitted(&mut self) -> UiStaging {
        UiStaging(self.pending.drain(..).map(|u| u.staging).collect())
    }

    fn texture(&self, id: u64) -> Result<&UiTexture> {
        self.textures.get(&id).ok_or_else(|| crate::Error::Invalid(format!("UI texture {id} was never given texels")))
    }

    fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        display: &Image,
        (vertices, indices): (&Buffer, &Buffer),
        draws: &[(UiDraw, vk::DescriptorSet)],
        push: Push,
    ) {
        let device = &ctx.device;
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: display.extent };
        let attachments = [vk::RenderingAttachmentInfo::default()
            .image_view(display.view)
            .image_layout(vk::ImageLayout::GENERAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&attachments);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: area.extent.width as f32,
            height: area.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: `cmd` is recording outside a render pass; the display image, the buffers, the
        // sets and the pipeline belong to this device and outlive the frame; every draw's
        // indices were written to `indices` by `prepare`, and its scissor lies in the image.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::VERTEX, 0, bytemuck::bytes_of(&push));
            device.cmd_bind_vertex_buffers(cmd, 0, &[vertices.raw], &[0]);
            device.cmd_bind_index_buffer(cmd, indices.raw, 0, vk::IndexType::UINT32);
            let mut bound = vk::DescriptorSet::null();
            for (draw, set) in draws {
                let Some(clip) = clip_to(draw.clip, area.extent) else { continue };
                if *set != bound {
                    device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[*set], &[]);
                    bound = *set;
                }
                device.cmd_set_scissor(cmd, 0, &[clip]);
                device.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, draw.vertex_offset, 0);
            }
            device.cmd_end_rendering(cmd);
        }
    }

    pub fn destroy(self, ctx: &Context) {
        for upload in self.pending {
            ctx.destroy_buffer(upload.staging);
        }
        for (_, texture) in self.textures {
            texture.destroy(ctx);
        }
        for slot in self.slots {
            slot.vertices.destroy(ctx);
            slot.indices.destroy(ctx);
        }
        // SAFETY: no pending frame uses the pass any more (the caller's contract); null
        // handles are ignored.
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
            ctx.device.destroy_descriptor_set_layout(self.set_layout, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
    }
}

impl Destroy for UiPass {
    fn destroy(self, ctx: &Context) {
        UiPass::destroy(self, ctx);
    }
}

/// `clip` cut to an image of `extent`; `None` when nothing of it is left.
fn clip_to(clip: vk::Rect2D, extent: vk::Extent2D) -> Option<vk::Rect2D> {
    let x0 = clip.offset.x.clamp(0, extent.width as i32);
    let y0 = clip.offset.y.clamp(0, extent.height as i32);
    let x1 = (clip.offset.x + clip.extent.width as i32).clamp(0, extent.width as i32);
    let y1 = (clip.offset.y + clip.extent.height as i32).clamp(0, extent.height as i32);
    (x1 > x0 && y1 > y0).then(|| vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D { width: (x1 - x0) as u32, height: (y1 - y0) as u32 },
    })
}

/// Records the copy of `staging`'s texels into `rect` of `image` (in `TRANSFER_DST_OPTIMAL`).
fn copy_texels(ctx: &Context, cmd: vk::CommandBuffer, staging: &Buffer, image: &Image, rect: vk::Rect2D) {
    let region = copy_rect(image, rect);
    // SAFETY: recording outside a render pass; the buffer holds the rectangle's texels,
    // tightly packed, and the rectangle lies in the image (checked by `prepare`).
    unsafe {
        ctx.device.cmd_copy_buffer_to_image(
            cmd,
            staging.raw,
            image.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
        )
    };
}

/// The pipeline: triangles, no culling, no depth, premultiplied-alpha blending; viewport and
/// scissor dynamic.
fn create_pipeline(
    ctx: &Context,
    layout: vk::PipelineLayout,
    vertex: &[u32],
    fragment: &[u32],
) -> Result<vk::Pipeline> {
    with_stages(ctx, vertex, fragment, |stages| create_pipeline_from(ctx, layout, stages))
}

/// The pipeline of [`create_pipeline`] from the vertex and fragment `stages`.
fn create_pipeline_from(
    ctx: &Context,
    layout: vk::PipelineLayout,
    stages: [vk::PipelineShaderStageCreateInfo; 2],
) -> Result<vk::Pipeline> {
    let bindings = [vk::VertexInputBindingDescription::default()
        .binding(0)
        .stride(std::mem::size_of::<UiVertex>() as u32)
        .input_rate(vk::VertexInputRate::VERTEX)];
    let attributes = [
        vk::VertexInputAttributeDescription { location: 0, binding: 0, format: vk::Format::R32G32_SFLOAT, offset: 0 },
        vk::VertexInputAttributeDescription { location: 1, binding: 0, format: vk::Format::R32G32_SFLOAT, offset: 8 },
        vk::VertexInputAttributeDescription { location: 2, binding: 0, format: vk::Format::R8G8B8A8_UNORM, offset: 16 },
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(&bindings)
        .vertex_attribute_descriptions(&attributes);
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let blend = [vk::PipelineColorBlendAttachmentState::default()
        .blend_enable(true)
        .src_color_blend_factor(vk::BlendFactor::ONE)
        .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
        .color_blend_op(vk::BlendOp::ADD)
        .src_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_DST_ALPHA)
        .dst_alpha_blend_factor(vk::BlendFactor::ONE)
        .alpha_blend_op(vk::BlendOp::ADD)
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let formats = [TARGET_FORMAT];
    let mut rendering = vk::PipelineRenderingCreateInfo::default().color_attachment_formats(&formats);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .color_blend_state(&blending)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering)];
    // SAFETY: the create info and everything it points to outlive the call; the modules and
    // the layout belong to this device.
    let created = unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
    created.map(|p| p[0]).map_err(|(_, e)| e).vk("vkCreateGraphicsPipelines")
}
