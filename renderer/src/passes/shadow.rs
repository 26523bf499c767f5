//! Cube shadow maps of point lights, for the network pass's analytic direct light: per light,
//! six 90° views of the scene mesh, each storing the distance from the light to the nearest
//! surface. All lights share one atlas image (`shadow_cube.glsl` has its layout), so the
//! network pass reads it as a plain storage image and a frame renders it in one render pass.
//!
//! The pass draws the mesh without materials: alpha-masked cut-outs cast whole shadows.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::Image;
use crate::backend::sync::{Access, Pass, ResourceStates, Use};
use crate::error::{Result, VkContext};
use crate::lights::MAX_LIGHTS;
use crate::passes::mesh::GBufferMesh;
use crate::passes::raster::{self, cleared_depth, Raster, DEPTH_FORMAT};

/// Texels per side of a cube face (`SHADOW_SIZE` in `shadow_cube.glsl`).
pub const SHADOW_SIZE: u32 = 256;
const ATLAS_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
/// What a face texel holds where nothing was drawn: farther than anything.
const NOTHING: f32 = 1e30;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FacePush {
    light: [f32; 4],
    face: u32,
    pad: [u32; 3],
}

pub struct ShadowPass {
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    /// Distances, R32F: 6 faces wide, one row of faces per light ([`MAX_LIGHTS`] rows).
    atlas: Image,
    /// The depth test's buffer, the atlas's size.
    depth: Image,
}

impl ShadowPass {
    /// `vertex` and `fragment` are the SPIR-V of `shadow.vert` and `shadow.frag`.
    pub fn new(ctx: &Context, vertex: &[u32], fragment: &[u32]) -> Result<Self> {
        let extent = vk::Extent2D { width: 6 * SHADOW_SIZE, height: MAX_LIGHTS as u32 * SHADOW_SIZE };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE;
        let atlas = ctx.guard(ctx.create_image("shadow atlas", extent, ATLAS_FORMAT, usage)?);
        let depth = ctx.guard(ctx.create_image(
            "shadow depth",
            extent,
            DEPTH_FORMAT,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?);
        ctx.submit_once(|cmd| {
            ctx.transition(cmd, &atlas, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
            ctx.transition(cmd, &depth, vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        })?;
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX)
            .size(std::mem::size_of::<FacePush>() as u32)];
        // SAFETY: a valid create info; the layout is destroyed by `destroy` or below.
        let layout = unsafe {
            ctx.device
                .create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&push), None)
        }
        .vk("vkCreatePipelineLayout")?;
        let attributes =
            [vk::VertexInputAttributeDescription::default().location(0).format(vk::Format::R32G32B32_SFLOAT).offset(0)];
        let raster = Raster {
            vertex,
            fragment,
            attributes: &attributes,
            color_formats: &[ATLAS_FORMAT],
            depth_format: DEPTH_FORMAT,
        };
        let pipeline = match raster.pipelines(ctx, layout, &[0]) {
            Ok(p) => p[0],
            Err(e) => {
                // SAFETY: nothing uses the layout yet.
                unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
                return Err(e);
            }
        };
        ctx.set_name(pipeline, "shadow");
        Ok(ShadowPass { pipeline, layout, atlas: atlas.keep(), depth: depth.keep() })
    }

    /// The distances the network pass reads (`GENERAL` layout).
    pub fn atlas(&self) -> &Image {
        &self.atlas
    }

    /// Records where `new` left the images.
    pub fn register(&self, states: &mut ResourceStates) {
        states.set_layout(&self.atlas, vk::ImageLayout::GENERAL);
        states.set_layout(&self.depth, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
    }

    /// The pass for a frame list: the cube maps of `lights` (positions; at most
    /// [`MAX_LIGHTS`]), drawing every triangle of `mesh`.
    pub fn pass<'a>(&'a self, ctx: &'a Context, mesh: &'a GBufferMesh, lights: Vec<[f32; 3]>) -> Pass<'a> {
        let uses = vec![
            Use::image(&self.atlas, Access::COLOR_ATTACHMENT_WRITE),
            Use::image(&self.depth, Access::DEPTH_ATTACHMENT),
            Use::buffer(&mesh.buffer, Access::VERTEX_INDEX_READ),
        ];
        Pass::new("shadow maps", uses, move |cmd| self.record(ctx, cmd, mesh, &lights))
    }

    fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, mesh: &GBufferMesh, lights: &[[f32; 3]]) {
        let rows = lights.len().min(MAX_LIGHTS) as u32;
        if rows == 0 {
            return;
        }
        let device = &ctx.device;
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D { width: 6 * SHADOW_SIZE, height: rows * SHADOW_SIZE },
        };
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(self.atlas.view)
            .image_layout(vk::ImageLayout::GENERAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [NOTHING; 4] } })];
        let depth = cleared_depth(&self.depth);
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&color)
            .depth_attachment(&depth);
        raster::render(ctx, cmd, &info, area, (self.pipeline, self.layout, None), false, || {
            mesh.bind(ctx, cmd);
            for (row, light) in lights.iter().take(rows as usize).enumerate() {
                for face in 0..6u32 {
                    let offset = vk::Offset2D { x: (face * SHADOW_SIZE) as i32, y: (row as u32 * SHADOW_SIZE) as i32 };
                    let extent = vk::Extent2D { width: SHADOW_SIZE, height: SHADOW_SIZE };
                    let tile = vk::Rect2D { offset, extent };
                    raster::set_viewport(ctx, cmd, tile, tile);
                    let push = FacePush { light: [light[0], light[1], light[2], 1.0], face, pad: [0; 3] };
                    let stage = vk::ShaderStageFlags::VERTEX;
                    // SAFETY: `cmd` is recording; the layout has a vertex range of this size.
                    unsafe { device.cmd_push_constants(cmd, self.layout, stage, 0, bytemuck::bytes_of(&push)) };
                    for draw in &mesh.draws {
                        mesh.draw(ctx, cmd, draw);
                    }
                }
            }
        });
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for ShadowPass {
    fn destroy(self, ctx: &Context) {
        // SAFETY: no GPU work that uses the pass is pending.
        unsafe {
            ctx.device.destroy_pipeline(self.pipeline, None);
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        ctx.destroy_image(self.atlas);
        ctx.destroy_image(self.depth);
    }
}
