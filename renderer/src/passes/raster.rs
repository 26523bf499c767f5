//! The raster pipeline builder and depth attachment that the G-buffer and shadow passes share.

use ash::vk;

use crate::backend::context::Context;
use crate::backend::resources::Image;
use crate::error::{Result, VkContext};
use crate::passes::mesh::GBufferVertex;

/// The depth buffer of the passes that rasterise the mesh (G-buffer, shadow maps).
pub(crate) const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The depth attachment of a pass that rasterises the mesh: `depth` ([`DEPTH_FORMAT`]),
/// cleared to the far plane, not stored.
pub(crate) fn cleared_depth(depth: &Image) -> vk::RenderingAttachmentInfo<'static> {
    vk::RenderingAttachmentInfo::default()
        .image_view(depth.view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } })
}

/// Records a dynamic rendering of `info` into `cmd` (recording, outside a render pass):
/// `draw` records what is drawn inside it, with the viewport set to `view` (the rectangle
/// clip space maps to, which may be larger than the render area when only part of the image
/// is drawn), the scissor to the render area, and `pipeline` bound with `layout`'s set 0
/// (`set`, if any). `mirrored` says the view is seen in a mirror, which turns the scene's
/// counter-clockwise front faces clockwise on screen.
pub(crate) fn render(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    info: &vk::RenderingInfo,
    view: vk::Rect2D,
    (pipeline, layout, set): (vk::Pipeline, vk::PipelineLayout, Option<vk::DescriptorSet>),
    mirrored: bool,
    draw: impl FnOnce(),
) {
    let device = &ctx.device;
    // SAFETY: `cmd` is recording outside a render pass (the caller's contract); the
    // attachments, the pipeline and the set belong to this device and outlive the frame.
    unsafe { device.cmd_begin_rendering(cmd, info) };
    set_viewport(ctx, cmd, view, info.render_area);
    let front = if mirrored { vk::FrontFace::CLOCKWISE } else { vk::FrontFace::COUNTER_CLOCKWISE };
    // SAFETY: as above; every pipeline of `Raster` takes the front face dynamically.
    unsafe { device.cmd_set_front_face(cmd, front) };
    // SAFETY: as above.
    unsafe { device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline) };
    if let Some(set) = set {
        // SAFETY: as above; the set matches the layout's set 0.
        unsafe { device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, layout, 0, &[set], &[]) };
    }
    draw();
    // SAFETY: ends the rendering begun above.
    unsafe { device.cmd_end_rendering(cmd) };
}

/// Sets the viewport (depth 0 to 1) to `view` and the scissor to `scissor`: every pipeline of
/// [`Raster`] takes them dynamically. Inside [`render`] only.
pub(crate) fn set_viewport(ctx: &Context, cmd: vk::CommandBuffer, view: vk::Rect2D, scissor: vk::Rect2D) {
    let viewport = vk::Viewport {
        x: view.offset.x as f32,
        y: view.offset.y as f32,
        width: view.extent.width as f32,
        height: view.extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    // SAFETY: `cmd` is recording inside a rendering whose pipeline sets these dynamically.
    unsafe {
        ctx.device.cmd_set_viewport(cmd, 0, &[viewport]);
        ctx.device.cmd_set_scissor(cmd, 0, &[scissor]);
    }
}

/// Runs `create` with the vertex and fragment stages of the SPIR-V `vertex` and `fragment`
/// (entry points `main`), whose modules live only for the call.
pub(crate) fn with_stages<R>(
    ctx: &Context,
    vertex: &[u32],
    fragment: &[u32],
    create: impl FnOnce([vk::PipelineShaderStageCreateInfo; 2]) -> Result<R>,
) -> Result<R> {
    ctx.step("vkCreateGraphicsPipelines")?;
    let vs = ctx.create_shader_module(vertex)?;
    let created = ctx.create_shader_module(fragment).and_then(|fs| {
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
        ];
        let made = create(stages);
        ctx.destroy_shader_module(fs);
        made
    });
    ctx.destroy_shader_module(vs);
    created
}

/// A graphics pipeline that rasterises the scene mesh ([`GBufferVertex`]) with depth testing,
/// for the G-buffer and shadow passes.
pub(crate) struct Raster<'a> {
    pub vertex: &'a [u32],
    pub fragment: &'a [u32],
    /// The vertex attributes the shaders read, from one binding of `GBufferVertex`s.
    pub attributes: &'a [vk::VertexInputAttributeDescription],
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
}

impl Raster<'_> {
    /// One pipeline per value of specialization constant 0, with `layout`. No face culling;
    /// viewport, scissor and front face are dynamic. The caller destroys the pipelines.
    pub(crate) fn pipelines(
        &self,
        ctx: &Context,
        layout: vk::PipelineLayout,
        values: &[u32],
    ) -> Result<Vec<vk::Pipeline>> {
        with_stages(ctx, self.vertex, self.fragment, |stages| self.create(ctx, layout, values, stages))
    }

    /// The pipelines of [`Raster::pipelines`] from the vertex and fragment `stages`.
    fn create(
        &self,
        ctx: &Context,
        layout: vk::PipelineLayout,
        values: &[u32],
        stages: [vk::PipelineShaderStageCreateInfo; 2],
    ) -> Result<Vec<vk::Pipeline>> {
        let bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(std::mem::size_of::<GBufferVertex>() as u32)
            .input_rate(vk::VertexInputRate::VERTEX)];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(self.attributes);
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        // The projection's y flip and Vulkan's y-down framebuffer cancel: front faces are
        // counter-clockwise on screen, as in the scene, except in a mirror (`render` sets the
        // front face).
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let blend = vec![
            vk::PipelineColorBlendAttachmentState::default()
                .color_write_mask(vk::ColorComponentFlags::RGBA);
            self.color_formats.len()
        ];
        let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR, vk::DynamicState::FRONT_FACE];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(self.color_formats)
            .depth_attachment_format(self.depth_format);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blending)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering);
        let mut pipelines = Vec::with_capacity(values.len());
        for &value in values {
            let value = [value];
            let entries = [vk::SpecializationMapEntry { constant_id: 0, offset: 0, size: 4 }];
            let specialization =
                vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(&value));
            let mut stages = stages;
            stages[1] = stages[1].specialization_info(&specialization);
            let info = [info.stages(&stages)];
            // SAFETY: the create info and everything it points to outlive the call; the modules
            // and the layout belong to this device.
            match unsafe { ctx.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) } {
                Ok(p) => pipelines.push(p[0]),
                Err((_, e)) => {
                    for p in pipelines {
                        // SAFETY: made above and never used.
                        unsafe { ctx.device.destroy_pipeline(p, None) };
                    }
                    return Err(e).vk("vkCreateGraphicsPipelines");
                }
            }
        }
        Ok(pipelines)
    }
}
